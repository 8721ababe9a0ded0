"""The two corrections a record can have, as typed option objects: :class:`LinearOptions` and
:class:`ModelOptions`.

:func:`rigsim.correct_record` takes one of them; ``rigsim correct`` builds the same object from
its flags (:data:`rigsim.scenarios.records.naming.FLAGS`, one table of flag and field) and calls the
same planning (:func:`rigsim.scenarios.records.api.plan_correction`). The objects only hold what
was given: every value is checked, and every file read, by
:func:`rigsim.scenarios.records.settings.correction_settings` before any work, in one
:class:`~rigsim.scenarios.core.config.ScenarioError` sentence naming the field. Imports numpy
alone (through the low-pass's defaults).
"""

from __future__ import annotations

from dataclasses import dataclass

from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE

__all__ = ["LinearOptions", "ModelOptions"]


@dataclass(frozen=True)
class LinearOptions:
    """The linear correction ``F_corrected = T_a^-1 T_F F_measured``, and its T_a.

    Give exactly one source of T_a: ``actuator``, ``actuators`` or ``identify``. Inside
    :class:`ModelOptions` (as ``linear``) it is the model correction's L, whose T_a may be left
    out: it is then identified per corner from the model's ``pairs``.

    Parameters
    ----------
    actuator : str, bytes, os.PathLike or T_a, optional
        One T_a for every force channel: an actuator file (``[transfer_function] num, den`` or
        eq. 4's ``[parameters]``, :mod:`rigsim.correction.io.actuator_file`), or ``(num, den)`` in
        descending powers of s (s in rad/s), an ``ActuatorFit`` or a ``control.TransferFunction``.
    actuators : str, bytes, os.PathLike or Mapping[str, T_a], optional
        One T_a per corner: a per-corner actuator file (``rigsim identify``'s ``actuators.toml``)
        or corner -> T_a (``RecordedIdentification.fits``); each corner corrects the force channel
        whose name holds the corner as a token (``tire_force_fl_N``, ``Fz_FL``) or the one
        ``corner_map`` gives.
    identify : (str, str) or str, optional
        The drive and pan displacement channels (lengths) one T_a is fitted from
        (:func:`rigsim.correction.identification.actuator_fit.fit_actuator`), ``("drive", "lvdt")``
        or ``"drive,lvdt"``.
    lowpass : {"regularized", "paper"}
        The low-pass T_F: a Butterworth of order :data:`~rigsim.correction.output.lowpass.BAND_ORDER`
        at ``lowpass_hz`` (default), or the paper's eq. 5 (16/24 Hz).
    lowpass_hz : float, Hz, optional
        The regularized low-pass's -3 dB corner (default
        :data:`~rigsim.correction.output.lowpass.BAND_HZ`, 30 Hz); finite, > 0, below fs / 2, and
        high enough that the low-pass's transients fit in the record (about 6.3 s Hz / corner
        zero-phase: 0.32 Hz at the least for a 20 s record).
    mode : {"zerophase", "causal"}
        ``zerophase``: ``|T_a^-1 T_F|`` with T_a^-1's phase, offline; ``causal``: as a real-time filter.
    normalize_dc : bool
        Scale each T_a to ``T_a(0) = 1`` instead of refusing one that is off.

    Examples
    --------
    >>> import rigsim
    >>> rigsim.LinearOptions(actuators="actuators.toml", lowpass_hz=25.0)
    LinearOptions(actuators='actuators.toml', lowpass_hz=25.0)
    """

    actuator: object = None
    actuators: object = None
    identify: object = None
    lowpass: str = BAND_LOWPASS
    lowpass_hz: float | None = None
    mode: str = BAND_MODE
    normalize_dc: bool = False

    def __repr__(self) -> str:
        return _repr(self, LinearOptions())


@dataclass(frozen=True)
class ModelOptions:
    """The correction by a truck model calibrated on the record:
    ``F_corrected = F_model(x_ref) + L(W(F_rig - F_model(x_a)))`` per wheel, W the residual's white
    noise and drift taken out and L the linear correction; where the model does not reproduce the
    forces, L alone corrects those wheels and the result says why. Minutes of CPU.

    Parameters
    ----------
    truck : str, bytes, os.PathLike or Scenario
        A scenario file (TRUCK.toml) whose rig is used and whose ``[vehicle]`` (the truck's spec
        sheet) the calibration starts from and is centred on.
    pairs : Mapping[str, tuple[str, str]] or str
        Per corner fl, fr, rl, rr the drive and LVDT channels, ``{"fl": ("Soll_FL", "Weg_FL"), ...}``
        or ``"fl=Soll_FL:Weg_FL,..."``.
    linear : LinearOptions, optional
        L: its low-pass, mode and T_a (``actuator`` or ``actuators``; default: identified per
        corner from ``pairs``). Its ``identify`` is refused (L's T_a comes from ``pairs``).
    workers : int, optional
        Worker processes (default: all cores).
    max_evaluations : int, optional
        Most evaluations of the calibration's residual (default 60); a whole number >= 1.
    calibration_windows : int, optional
        Windows of 5 s lead-in + 5 s the model is fitted on (default 2); at most as many as the
        record holds side by side (3 in 20 s).
    cab : {"auto", "held", "fitted"}, optional
        The model's cab held, its mount frequency fitted, or (default) the better fit.
    drift_cut_hz : float, Hz, optional
        The corner below which W takes the model's residual for the load cells' drift and leaves
        the slow force to the model (default :data:`~rigsim.correction.output.denoise.DRIFT_HZ`,
        0.7 Hz; at most 1.5 Hz); 0: no drift cut, for load cells that do not drift.
    calibration : str, bytes, os.PathLike or SavedCalibration, optional
        A calibration of this truck saved from another record (``rigsim correct --model`` writes
        ``OUT.calibration.json``): the record is corrected with it once its model error on this
        record's own windows is within the limit, its tire's progressive stiffening refitted on
        this record's loads (:mod:`~rigsim.scenarios.records.model.refine`); beyond it, the truck
        is calibrated again from the saved values, and the result says so. Default: calibrated
        on this record.
    calibration_records : sequence of records, optional
        Other records of the same truck on the rig (files, or records read with
        :func:`rigsim.read_record`), with the same channels and rate: the calibration fits
        ``calibration_windows`` windows of each besides this record's (other roads and speeds
        excite more of the truck). Each is read and checked before any work; the calibration
        file names them.

    Examples
    --------
    >>> import rigsim
    >>> rigsim.ModelOptions("truck.toml", pairs="fl=D1:X1,fr=D2:X2,rl=D3:X3,rr=D4:X4", cab="held")
    ModelOptions(truck='truck.toml', pairs='fl=D1:X1,fr=D2:X2,rl=D3:X3,rr=D4:X4', cab='held')
    """

    truck: object
    pairs: object = None
    linear: LinearOptions | None = None
    workers: int | None = None
    max_evaluations: int | None = None
    calibration_windows: int | None = None
    cab: str | None = None
    drift_cut_hz: float | None = None
    calibration: object = None
    calibration_records: tuple = ()

    def __repr__(self) -> str:
        return _repr(self, ModelOptions(None))


def _differs(value, default) -> bool:
    if value is default:
        return False
    if isinstance(value, (str, int, float)) and type(value) is type(default):
        return value != default
    return True


def _repr(options, default) -> str:
    """``Name(field=value, ...)`` of the fields given other than their defaults (``truck`` always)."""
    from dataclasses import fields

    shown = [f"{f.name}={getattr(options, f.name)!r}" for f in fields(options)
             if f.name == "truck" or _differs(getattr(options, f.name), getattr(default, f.name))]
    return f"{type(options).__name__}({', '.join(shown)})"
