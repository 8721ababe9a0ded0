"""Correcting a rig's record from Python: read it, correct it, write it.

::

    from scenarios.records import read_record, correct_record
    record = read_record("rig.csv")                          # .rsp/.mf4/.tdms; decimal=, thousands=, time_col=
    result = correct_record(record, actuators="acts.toml")  # or actuator=, identify=, model=..., pairs=...
    result.write("corrected.rsp")

:func:`read_record` reads any file a lab keeps (CSV in any dialect, RPC III, MDF4, TDMS) into its
channels in SI; :func:`correct_record` corrects its wheel forces, linearly by ``T_a^-1 T_F``
(:func:`correction.output.pipeline.correct_forces`) or by a truck model calibrated on the record,
and returns a :class:`~scenarios.records.corrected.CorrectionResult` whose
:meth:`~scenarios.records.corrected.CorrectionResult.write` writes what ``rigsim correct`` writes;
:func:`identify_record` fits T_a per corner from the record's drive and LVDT channels (what
``rigsim identify --from-file`` does). ``rigsim correct`` runs the same steps
(:func:`scenarios.records.settings.correction_settings`, then the settings'
:meth:`~scenarios.records.settings.CorrectionSettings.read`, the plan's
:meth:`~scenarios.records.plan.CorrectionPlan.check_output` and
:meth:`~scenarios.records.plan.CorrectionPlan.run`). Every refusal is one
:class:`~scenarios.core.config.ScenarioError` sentence (a ``ValueError``) naming the keyword at
fault, never a Python or numpy error: the arguments are checked before any work
(:mod:`scenarios.records.arguments`), and a path may be a ``str``, ``bytes`` or ``os.PathLike``.
Imports nothing heavy at module level.
"""

from __future__ import annotations

import os

from scenarios.records.arguments import checked_pairs, checked_record, file_path, shown
from scenarios.records.channels import read_record
from scenarios.records.corrected import ChannelLoads, CorrectionResult
from scenarios.records.settings import correction_settings

__all__ = ["read_record", "correct_record", "identify_record", "CorrectionResult", "ChannelLoads"]


def correct_record(record, *, actuator=None, actuators=None, identify=None, model=None, pairs=None, columns=None,
                   corner_map=None, lowpass: str = "regularized", lowpass_hz: float | None = None,
                   mode: str = "zerophase", transient: str = "drop", normalize_dc: bool = False,
                   workers: int | None = None, max_evaluations: int | None = None,
                   calibration_windows: int | None = None, cab: str | None = None,
                   drift_cut_hz: float | None = None, force_filter=None, lvdt_filter=None,
                   progress=None) -> CorrectionResult:
    """Correct the wheel forces of a rig's record for the actuators' dynamics.

    Give exactly one source of T_a (``actuator``, ``actuators`` or ``identify``) for the linear
    correction ``F_corrected = T_a^-1 T_F F_measured``, or ``model`` and ``pairs`` for the
    correction by a truck model calibrated on the record,
    ``F_corrected = F_model(x_ref) + L(W(F_rig - F_model(x_a)))`` with W the residual's white noise
    taken out and L the linear correction (minutes
    of CPU; on the wheels where the model does not reproduce the forces L alone is used, and the
    result says why).

    Parameters
    ----------
    record : correction.io.measured.MeasuredChannels, str, bytes or os.PathLike
        The record (:func:`read_record`, or built with
        :func:`correction.io.measured_core.make_channels`), or a file to read with only the
        channels needed.
    actuator : str, bytes, os.PathLike or T_a, optional
        One T_a for every force channel: an actuator file (``[transfer_function] num, den`` or
        eq. 4's ``[parameters]``, :mod:`correction.io.actuator_file`), or ``(num, den)`` in
        descending powers of s (s in rad/s), an ``ActuatorFit`` or a ``control.TransferFunction``.
        With ``model``: L's T_a.
    actuators : str, bytes, os.PathLike or Mapping[str, T_a], optional
        One T_a per corner: a per-corner actuator file (``rigsim identify``'s ``actuators.toml``)
        or corner -> T_a; each corner corrects the force channel whose name holds the corner as
        a token (``tire_force_fl_N``, ``Fz_FL``) or the one ``corner_map`` gives. With ``model``:
        L's, one for each of fl, fr, rl, rr (default: identified per corner from ``pairs``).
    identify : (str, str) or str, optional
        The drive and pan displacement channels (lengths) T_a is fitted from
        (:func:`correction.identification.actuator_fit.fit_actuator`), ``("drive", "lvdt")`` or ``"drive,lvdt"``.
    model : str, bytes, os.PathLike or Scenario, optional
        A scenario file whose rig is used and whose ``[vehicle]`` values start the calibration.
    pairs : Mapping[str, tuple[str, str]] or str, optional
        With ``model``: per corner fl, fr, rl, rr the drive and LVDT channels,
        ``{"fl": ("Soll_FL", "Weg_FL"), ...}`` or ``"fl=Soll_FL:Weg_FL,..."``.
    columns : sequence of str or str, optional
        The force channels to correct (default: every force channel, N or no unit, that is not a
        drive or displacement channel; with a corner's T_a, those naming a corner).
    corner_map : Mapping[str, str], sequence of (str, str) or str, optional
        Corner -> force channel, ``{"fl": "Fz_FL"}`` or ``"fl=Fz_FL,..."``.
    lowpass : {"regularized", "paper"}
        The low-pass T_F: a Butterworth of order :data:`~correction.output.lowpass.BAND_ORDER` at
        ``lowpass_hz`` (default), or the paper's eq. 5 (16/24 Hz).
    lowpass_hz : float, Hz, optional
        The regularized low-pass's corner, its -3 dB frequency (default
        :data:`~correction.output.lowpass.BAND_HZ`, 30 Hz); finite, > 0, below fs / 2, and high
        enough that the low-pass's transients fit in the record (about 6.3 s Hz / corner
        zero-phase: 0.32 Hz at the least for a 20 s record).
    mode : {"zerophase", "causal"}
        ``zerophase``: ``|T_a^-1 T_F|`` with T_a^-1's phase, offline; ``causal``: as a real-time filter.
    transient : {"drop", "mark", "keep"}
        What the written file holds of the samples inside the correction's transients: none,
        all with a ``settled`` 0/1 channel, or all.
    normalize_dc : bool
        Scale each T_a to ``T_a(0) = 1`` instead of refusing one that is off.
    workers : int, optional
        With ``model``: worker processes (default: all cores).
    max_evaluations : int, optional
        With ``model``: most evaluations of the calibration's residual (default 60); a whole number >= 1.
    calibration_windows : int, optional
        With ``model``: windows of 5 s lead-in + 5 s the model is fitted on (default 2); at most
        as many as the record holds side by side (3 in 20 s).
    cab : {"auto", "held", "fitted"}, optional
        With ``model``: the model's cab held, its mount frequency fitted, or (default) the better fit.
    drift_cut_hz : float, Hz, optional
        With ``model``: the corner below which W takes the model's residual for the load cells'
        drift and leaves the slow force to the model (default
        :data:`~correction.output.denoise.DRIFT_HZ`, 0.7 Hz; at most 1.5 Hz); 0: no drift cut, for
        a lab whose load cells do not drift.
    force_filter, lvdt_filter : correction.io.acquisition.ChannelFilter or str, optional
        The force channels' and the LVDT channels' anti-alias filter and delay as the lab's
        acquisition applied them (``ChannelFilter(200.0, 4, delay_s=2e-4)``, or the text
        ``"200:4"``, ``"150:4:bessel:digital"``): their phase and delay are taken out of those
        channels before correcting (:func:`correction.io.acquisition.undo_timing`). The LVDT's
        goes with ``identify`` or ``model``.
    progress : callable, optional
        Called with each progress line or note of a long run (the model's calibration), a str; default:
        silent.

    Returns
    -------
    CorrectionResult
        The corrected forces (N, every sample) and which are settled, ``fs_hz`` (Hz), the method
        used and why, the calibration (model), the metadata and the per-channel loads
        (``loads``, ``table()``); ``write(path)`` writes the file.

    Raises
    ------
    ScenarioError
        One sentence naming the keyword, channel or file at fault and the fix; nothing is computed.

    Examples
    --------
    A wheel force measured at 1 kHz (made in memory here), corrected linearly with a T_a given
    as ``(num, den)``, a second-order actuator at 15 Hz, 0.7 of critical damping:

    >>> import numpy as np
    >>> from correction.io.measured import MeasuredChannels
    >>> from scenarios.records import correct_record
    >>> t = np.arange(10_000) / 1000.0
    >>> force = 40e3 + 2e3 * np.sin(2 * np.pi * 3.0 * t) + 5e2 * np.sin(2 * np.pi * 12.0 * t)
    >>> record = MeasuredChannels(time_s=t, data={"Fz_FL": force}, units={"Fz_FL": "N"},
    ...                           source_units={"Fz_FL": "kN"}, fs_hz=1000.0, metadata={},
    ...                           path="", format="csv")
    >>> w = 2 * np.pi * 15.0
    >>> result = correct_record(record, actuator=([w * w], [1.0, 1.4 * w, w * w]))
    >>> result.method, result.channels, result.corrected_N.shape
    ('linear', ('Fz_FL',), (10000, 1))
    >>> print(result.description)
    T_a given in the call, low-pass Butterworth order 6, 30 Hz, zerophase

    The correction by the truck model takes a scenario file and the drive and LVDT channels of
    each corner, and minutes of CPU (not run here):

    >>> result = correct_record("rig.csv", model="truck.toml",  # doctest: +SKIP
    ...                         pairs="fl=Soll_FL:Weg_FL,fr=Soll_FR:Weg_FR,"
    ...                               "rl=Soll_RL:Weg_RL,rr=Soll_RR:Weg_RR")
    """
    if progress is not None and not callable(progress):
        from scenarios.core.config import ScenarioError

        raise ScenarioError(f"progress must be a callable taking each progress line (print, list.append), got "
                            f"{shown(progress)}")
    settings = correction_settings(
        actuator=actuator, actuators=actuators, identify=identify, model=model, pairs=pairs, columns=columns,
        corner_map=corner_map, lowpass=lowpass, lowpass_hz=lowpass_hz, mode=mode, transient=transient,
        normalize_dc=normalize_dc, workers=workers, max_evaluations=max_evaluations,
        calibration_windows=calibration_windows, cab=cab, drift_cut_hz=drift_cut_hz, force_filter=force_filter,
        lvdt_filter=lvdt_filter)
    plan = settings.read(record) if isinstance(record, (str, bytes, os.PathLike)) else settings.plan(record)
    return plan.run(progress)


def identify_record(record, *, pairs, lvdt_filter=None):
    """Fit T_a per corner from a record's drive and LVDT channels, as ``rigsim identify --from-file``.

    Parameters
    ----------
    record : correction.io.measured.MeasuredChannels, str, bytes or os.PathLike
        The record (:func:`read_record`, or built in Python), or a file to read with only the
        pairs' channels: independent random drives on the posts give the cleanest fit.
    pairs : Mapping[str, tuple[str, str]] or str
        Per corner the drive and LVDT channels (lengths, m), ``{"fl": ("Soll_FL", "Weg_FL"), ...}``
        or ``"fl=Soll_FL:Weg_FL,..."``.
    lvdt_filter : correction.io.acquisition.ChannelFilter or str, optional
        The LVDT channels' anti-alias filter and delay (``"150:4"``), taken out before the fit.

    Returns
    -------
    scenarios.records.recorded.RecordedIdentification
        ``fits`` per corner (stable, minimum phase, ``T_a(0) = 1``), ``actuators()``, ``meta()``;
        :func:`correction.io.actuator_file.write_actuators_file` writes them for ``actuators=``.

    Raises
    ------
    ScenarioError
        A channel, unit or pair problem, or a record that cannot support a fit (one sentence).

    Examples
    --------
    A record of 60 s of random drive on the front-left post and its LVDT, made in memory (the
    actuator second order at 15 Hz, 0.7 of critical damping):

    >>> import numpy as np
    >>> from scipy import signal
    >>> from correction.io.measured import MeasuredChannels
    >>> from scenarios.records import identify_record
    >>> fs = 500.0
    >>> t = np.arange(30_000) / fs
    >>> drive = 2e-3 * np.random.default_rng(1).standard_normal(t.size)
    >>> w = 2 * np.pi * 15.0
    >>> lvdt = signal.lsim(([w * w], [1.0, 1.4 * w, w * w]), drive, t)[1]
    >>> record = MeasuredChannels(time_s=t, data={"Soll_FL": drive, "Weg_FL": lvdt},
    ...                           units={"Soll_FL": "m", "Weg_FL": "m"},
    ...                           source_units={"Soll_FL": "mm", "Weg_FL": "mm"}, fs_hz=fs,
    ...                           metadata={}, path="", format="csv")
    >>> found = identify_record(record, pairs="fl=Soll_FL:Weg_FL")
    >>> fit = found.fits["fl"]
    >>> print(f"{fit.bandwidth_hz:.0f} Hz, |T_a(10 Hz)| = {abs(fit.frequency_response(10.0)):.2f}")
    15 Hz, |T_a(10 Hz)| = 0.92
    """
    from scenarios.records import recorded

    pairs = recorded.pairs_of(checked_pairs(pairs))
    if isinstance(record, (str, bytes, os.PathLike)):
        return recorded.identify_recorded(file_path(record, "record"), pairs, lvdt_filter=lvdt_filter)
    return recorded.identify_record(checked_record(record), pairs=pairs, lvdt_filter=lvdt_filter)
