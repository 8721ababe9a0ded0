"""Correcting a rig's record from Python: read it, correct it, write it.

::

    from rigsim import LinearOptions, correct_record, read_record
    record = read_record("rig.csv")  # .rsp/.mf4/.tdms; decimal=, thousands=, time_col=
    result = correct_record(record, LinearOptions(actuators="acts.toml"))  # or ModelOptions("truck.toml", pairs=...)
    result.write("corrected.rsp")

:func:`read_record` reads any file a lab keeps (CSV in any dialect, RPC III, MDF4, TDMS) into its
channels in SI; :func:`correct_record` corrects its wheel forces, linearly by ``T_a^-1 T_F``
(:func:`rigsim.correction.output.pipeline.correct_forces`) or by a truck model calibrated on the record,
and returns a :class:`~rigsim.scenarios.records.corrected.CorrectionResult` whose
:meth:`~rigsim.scenarios.records.corrected.CorrectionResult.write` writes what ``rigsim correct`` writes;
:func:`identify_record` fits T_a per corner from the record's drive and LVDT channels (what
``rigsim identify --from-file`` does). The correction is chosen by a typed option object,
:class:`~rigsim.scenarios.records.options.LinearOptions` or
:class:`~rigsim.scenarios.records.options.ModelOptions`; ``rigsim correct`` builds the same object
from its flags and calls the same :func:`plan_correction` (then the plan's
:meth:`~rigsim.scenarios.records.plan.CorrectionPlan.check_output` and
:meth:`~rigsim.scenarios.records.plan.CorrectionPlan.run`). Every refusal is one
:class:`~rigsim.scenarios.core.config.ScenarioError` sentence (a ``ValueError``) naming the keyword at
fault, never a Python or numpy error: the arguments are checked before any work
(:mod:`rigsim.scenarios.records.arguments`), and a path may be a ``str``, ``bytes`` or ``os.PathLike``.
Imports nothing heavy at module level.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

from rigsim.scenarios.records.arguments import checked_pairs, checked_record, file_path, shown
from rigsim.scenarios.records.channels import read_record
from rigsim.scenarios.records.corrected import ChannelLoads, CorrectionResult
from rigsim.scenarios.records.naming import KEYWORDS, Naming
from rigsim.scenarios.records.options import LinearOptions, ModelOptions
from rigsim.scenarios.records.settings import correction_settings

if TYPE_CHECKING:
    from rigsim.scenarios.records.plan import CorrectionPlan
    from rigsim.scenarios.records.recorded import RecordedIdentification

__all__ = ["read_record", "correct_record", "plan_correction", "identify_record", "CorrectionResult", "ChannelLoads",
           "LinearOptions", "ModelOptions"]


def correct_record(record, options, *, columns=None, corner_map=None, transient: str = "drop", force_filter=None,
                   lvdt_filter=None, progress=None) -> CorrectionResult:
    """Correct the wheel forces of a rig's record for the actuators' dynamics.

    ``options`` says which correction: :class:`~rigsim.scenarios.records.options.LinearOptions`,
    ``F_corrected = T_a^-1 T_F F_measured`` with its T_a and low-pass, or
    :class:`~rigsim.scenarios.records.options.ModelOptions`, a truck model calibrated on the
    record, ``F_corrected = F_model(x_ref) + L(W(F_rig - F_model(x_a)))`` with W the residual's
    white noise and drift taken out and L the linear correction (minutes of CPU; on the wheels
    where the model does not reproduce the forces L alone is used, and the result says why). The
    keywords say which channels, and how the lab's acquisition timed them.

    Parameters
    ----------
    record : rigsim.correction.io.measured.MeasuredChannels, str, bytes or os.PathLike
        The record (:func:`read_record`, or built with
        :func:`rigsim.correction.io.measured_core.make_channels`), or a file to read with only the
        channels needed.
    options : LinearOptions or ModelOptions
        The correction and its settings, checked (with their files read) before any work.
    columns : sequence of str or str, optional
        The force channels to correct (default: every force channel, N or no unit, that is not a
        drive or displacement channel; with a corner's T_a, those naming a corner).
    corner_map : Mapping[str, str], sequence of (str, str) or str, optional
        Corner -> force channel, ``{"fl": "Fz_FL"}`` or ``"fl=Fz_FL,..."``.
    transient : {"drop", "mark", "keep"}
        What the written file holds of the samples inside the correction's transients: none,
        all with a ``settled`` 0/1 channel, or all.
    force_filter, lvdt_filter : rigsim.correction.io.acquisition.ChannelFilter or str, optional
        The force channels' and the LVDT channels' anti-alias filter and delay as the lab's
        acquisition applied them (``ChannelFilter(200.0, 4, delay_s=2e-4)``, or the text
        ``"200:4"``, ``"150:4:bessel:digital"``): their phase and delay are taken out of those
        channels before correcting (:func:`rigsim.correction.io.acquisition.undo_timing`). The
        LVDT's goes with ``LinearOptions.identify`` or the model.
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
    >>> from rigsim.correction.io.measured import MeasuredChannels
    >>> from rigsim import LinearOptions, correct_record
    >>> t = np.arange(10_000) / 1000.0
    >>> force = 40e3 + 2e3 * np.sin(2 * np.pi * 3.0 * t) + 5e2 * np.sin(2 * np.pi * 12.0 * t)
    >>> record = MeasuredChannels(time_s=t, data={"Fz_FL": force}, units={"Fz_FL": "N"},
    ...                           source_units={"Fz_FL": "kN"}, fs_hz=1000.0, metadata={},
    ...                           path="", format="csv")
    >>> w = 2 * np.pi * 15.0
    >>> result = correct_record(record, LinearOptions(actuator=([w * w], [1.0, 1.4 * w, w * w])))
    >>> result.method, result.channels, result.corrected_N.shape
    ('linear', ('Fz_FL',), (10000, 1))
    >>> print(result.description)
    T_a given in the call, low-pass Butterworth order 6, 30 Hz, zerophase

    The correction by the truck model takes a scenario file and the drive and LVDT channels of
    each corner, and minutes of CPU (not run here):

    >>> from rigsim import ModelOptions
    >>> options = ModelOptions("truck.toml", pairs="fl=Soll_FL:Weg_FL,fr=Soll_FR:Weg_FR,"
    ...                                            "rl=Soll_RL:Weg_RL,rr=Soll_RR:Weg_RR")
    >>> result = correct_record("rig.csv", options)  # doctest: +SKIP
    """
    if progress is not None and not callable(progress):
        from rigsim.scenarios.core.config import ScenarioError

        raise ScenarioError(f"progress must be a callable taking each progress line (print, list.append), got "
                            f"{shown(progress)}")
    return plan_correction(record, options, columns=columns, corner_map=corner_map, transient=transient,
                           force_filter=force_filter, lvdt_filter=lvdt_filter).run(progress)


def plan_correction(record, options, *, columns=None, corner_map=None, transient: str = "drop", force_filter=None,
                    lvdt_filter=None, naming: Naming = KEYWORDS, time_col: str | None = None,
                    decimal: str | None = None, thousands: str | None = None) -> CorrectionPlan:
    """The correction :func:`correct_record` makes, checked and planned before any work (what
    ``rigsim correct`` calls too, with its flags' ``naming`` and the reader's ``time_col``,
    ``decimal`` and ``thousands`` for a file): a record given as a file is read with only the
    channels the options need. ``plan.check_output(path)`` refuses an output the writer would
    refuse; ``plan.run(progress)`` corrects."""
    settings = correction_settings(options, columns=columns, corner_map=corner_map, transient=transient,
                                   force_filter=force_filter, lvdt_filter=lvdt_filter, naming=naming)

    def planned(record):
        if isinstance(record, (str, bytes, os.PathLike)):
            return settings.read(record, time_col=time_col, decimal=decimal, thousands=thousands)
        return settings.plan(record)

    plan = planned(record)
    if not settings.calibration_records:
        return plan
    import dataclasses
    import pathlib

    from rigsim.scenarios.core.config import ScenarioError

    more, opt = [], naming("calibration_records")
    for other in settings.calibration_records:
        if isinstance(other, (str, bytes, os.PathLike)):
            path = pathlib.Path(file_path(other, opt))
            if plan.record.path and path.resolve() == pathlib.Path(str(plan.record.path)).resolve():
                raise ScenarioError(f"{opt} {str(path)!r} is the record corrected itself; give other records of "
                                    "this truck")
        more.append(planned(other))
        fs, here = more[-1].record.fs_hz, plan.record.fs_hz
        if abs(fs - here) > 1e-6 * here:
            raise ScenarioError(f"{opt} {str(more[-1].record.path)!r} is sampled at {fs:.6g} Hz, the record corrected "
                                f"at {here:.6g} Hz; calibrate on records of one rate")
    return dataclasses.replace(plan, more=tuple(more))


def identify_record(record, *, pairs, lvdt_filter=None) -> RecordedIdentification:
    """Fit T_a per corner from a record's drive and LVDT channels, as ``rigsim identify --from-file``.

    Parameters
    ----------
    record : rigsim.correction.io.measured.MeasuredChannels, str, bytes or os.PathLike
        The record (:func:`read_record`, or built in Python), or a file to read with only the
        pairs' channels: independent random drives on the posts give the cleanest fit.
    pairs : Mapping[str, tuple[str, str]] or str
        Per corner the drive and LVDT channels (lengths, m), ``{"fl": ("Soll_FL", "Weg_FL"), ...}``
        or ``"fl=Soll_FL:Weg_FL,..."``.
    lvdt_filter : rigsim.correction.io.acquisition.ChannelFilter or str, optional
        The LVDT channels' anti-alias filter and delay (``"150:4"``), taken out before the fit.

    Returns
    -------
    rigsim.scenarios.records.recorded.RecordedIdentification
        ``fits`` per corner (stable, minimum phase, ``T_a(0) = 1``), ``actuators()``, ``meta()``;
        :func:`rigsim.correction.io.actuator_file.write_actuators_file` writes them for ``actuators=``.

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
    >>> from rigsim.correction.io.measured import MeasuredChannels
    >>> from rigsim import identify_record
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
    from rigsim.scenarios.records import recorded

    pairs = recorded.pairs_of(checked_pairs(pairs))
    if isinstance(record, (str, bytes, os.PathLike)):
        return recorded.identify_recorded(file_path(record, "record"), pairs, lvdt_filter=lvdt_filter)
    return recorded.identify_pairs(checked_record(record), pairs=pairs, lvdt_filter=lvdt_filter)
