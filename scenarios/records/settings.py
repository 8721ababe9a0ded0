"""What to correct and how: the options of a record's correction checked, and their files read.

:func:`correction_settings` checks every field of a correction's options
(:class:`~rigsim.scenarios.records.options.LinearOptions`,
:class:`~rigsim.scenarios.records.options.ModelOptions`) and the keywords of
:func:`rigsim.scenarios.records.api.correct_record` before any record is read (types, choices,
the low-pass corner, which T_a source and its form, the model's options) and reads the files they name (the actuator files, the truck's scenario
file; paths as ``str``, ``bytes`` or ``os.PathLike``); the :class:`CorrectionSettings` it returns
knows which channels a record needs (:attr:`CorrectionSettings.channels`) and plans the
correction of a record (:meth:`CorrectionSettings.plan`, :meth:`CorrectionSettings.read`:
:mod:`rigsim.scenarios.records.plan`), holding the settings against the record before any work: the
low-pass's transients against its length and the calibration windows it holds
(:mod:`rigsim.scenarios.records.arguments`). Every refusal is one
:class:`~rigsim.scenarios.core.config.ScenarioError` sentence naming the parameter as ``naming`` says.
Imports nothing heavy at module level.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass

from rigsim.scenarios.records.arguments import (check_corner, check_windows, checked_corner_map, checked_names,
                                                checked_record, count, file_path, finite, flag, is_path, refusal, shown,
                                                ta_form)
from rigsim.scenarios.records.model_settings import checked_drift_hz, model_pairs_workers, saved_calibration, truck_scenario
from rigsim.scenarios.records.channels import parse_columns, parse_corner_map, parse_identify, wanted_channels
from rigsim.scenarios.records.naming import KEYWORDS, Naming
from rigsim.scenarios.records.output import GIVEN
from rigsim.scenarios.records.timing import check_timing

__all__ = ["LOWPASSES", "MODES", "TRANSIENTS", "CABS", "CorrectionSettings", "correction_settings"]

LOWPASSES = ("paper", "regularized")
MODES = ("causal", "zerophase")
TRANSIENTS = ("drop", "mark", "keep")
CABS = ("auto", "held", "fitted")


@dataclass(frozen=True)
class CorrectionSettings:
    """A correction's options, checked, with their files read (made by :func:`correction_settings`).

    Attributes
    ----------
    method : {"linear", "model"}
        The correction asked for.
    columns : tuple of str or None
        The force channels to correct (None: chosen by unit and corner names).
    corner_map : tuple of (str, str) or None
        (corner, channel) pairs.
    identify : tuple of str
        The (drive, displacement) channels T_a is fitted from; empty when not.
    ta : object or None
        The T_a: one (``actuator``) or corner -> T_a (``actuators``); with the model, the linear
        fallback's (one, or one per corner fl, fr, rl, rr), None: identified from ``pairs``.
    per_corner : bool
        ``ta`` is a corner -> T_a mapping (linear correction).
    ta_source : str or None
        The T_a's file as given, or :data:`~rigsim.scenarios.records.output.GIVEN`.
    pairs : Mapping[str, tuple[str, str]] or None
        The model's (drive, LVDT) channels per corner, in corner order.
    scenario : rigsim.scenarios.core.config.Scenario or None
        The truck model's scenario (the model correction).
    scenario_file : str or None
    lowpass : {"paper", "regularized"}
    lowpass_hz : float or None, Hz
        The regularized low-pass's corner; None: :data:`rigsim.correction.output.lowpass.BAND_HZ`.
    mode : {"causal", "zerophase"}
    transient : {"drop", "mark", "keep"}
    normalize_dc : bool
    workers : int or None
        Worker processes of the model correction.
    max_evaluations, calibration_windows : int or None
        The model's calibration: most fit evaluations, windows.
    cab : {"auto", "held", "fitted"}
    inputs : tuple of str
        The files read besides the record (a corrected file never replaces one).
    naming : Naming
        How messages name the parameters.
    force_filter, lvdt_filter : rigsim.correction.io.acquisition.ChannelFilter or None
        The force and LVDT channels' anti-alias filters and delays, undone before correcting
        (:mod:`rigsim.scenarios.records.timing`); None: the channels as recorded.
    saved : rigsim.scenarios.records.model.saved.SavedCalibration or None
        A calibration to correct with (checked on the record first); None: calibrate on the record.
    saved_file : str or None
        Its file as given, or :data:`~rigsim.scenarios.records.output.GIVEN`.
    calibration_records : tuple
        Other records (paths or records) whose windows the calibration fits too.
    drift_hz : float or None, Hz
        The model correction's drift cut (:func:`rigsim.scenarios.records.model.differential.hybrid_correction`);
        None: no cut (asked for with 0), or the linear correction.
    """

    method: str
    columns: tuple | None
    corner_map: tuple | None
    identify: tuple
    ta: object
    per_corner: bool
    ta_source: str | None
    pairs: Mapping | None
    scenario: object
    scenario_file: str | None
    lowpass: str
    lowpass_hz: float | None
    mode: str
    transient: str
    normalize_dc: bool
    workers: int | None
    max_evaluations: int | None
    calibration_windows: int | None
    cab: str
    inputs: tuple
    naming: Naming = KEYWORDS
    force_filter: object = None
    lvdt_filter: object = None
    drift_hz: float | None = None
    saved: object = None
    saved_file: str | None = None
    calibration_records: tuple = ()

    @property
    def channels(self) -> list[str] | None:
        """The channels a record needs (the columns, the corner map's, the identification's or the
        pairs'), or None: every numeric channel (neither columns nor corner map given)."""
        extra = [c for cols in self.pairs.values() for c in cols] if self.pairs else list(self.identify)
        return wanted_channels(None if self.columns is None else list(self.columns),
                               None if self.corner_map is None else list(self.corner_map), extra)

    def plan(self, record, as_read: Mapping | None = None):
        """The correction of ``record`` (a :class:`~rigsim.correction.io.measured.MeasuredChannels`) planned and
        checked (:class:`rigsim.scenarios.records.plan.CorrectionPlan`); ``as_read``: channel name as given ->
        as the reader returned it (default: matched exactly, else by case). The calibration windows
        the record holds and the low-pass's transients against its length are checked too."""
        from rigsim.scenarios.records.plan import make_plan

        record = checked_record(record)
        check_windows(self, record)
        plan = make_plan(self, record, as_read)
        check_corner(self, record)
        return plan

    def read(self, path, *, time_col: str | None = None, decimal: str | None = None, thousands: str | None = None):
        """Read ``path`` with only the channels these settings need (:attr:`channels`;
        :func:`rigsim.scenarios.records.channels.read_record`'s options) and plan its correction."""
        from rigsim.scenarios.records.channels import read_record

        wanted = self.channels
        record = read_record(path, time_col=time_col, channels=wanted, decimal=decimal, thousands=thousands)
        return self.plan(record, dict(zip(wanted, record.names)) if wanted is not None else None)


def _choice(naming: Naming, key: str, value, allowed) -> None:
    if not isinstance(value, str) or value not in allowed:
        raise refusal(f"{naming(key)} must be one of {', '.join(allowed)}, got {shown(value)}")


def _check_lowpass(naming: Naming, lowpass: str, lowpass_hz) -> float | None:
    if lowpass_hz is None:
        return None
    opt = naming("lowpass_hz")
    hz = finite(lowpass_hz)
    if hz is None or hz <= 0:
        raise refusal(f"{opt} must be a finite number of Hz > 0, got {shown(lowpass_hz)}")
    if lowpass != "regularized":
        raise refusal(f"{opt} sets the corner of the regularized low-pass; the paper's low-pass keeps its 16/24 Hz: "
                     f"drop {opt} or pass {naming.setting('lowpass', 'regularized')}")
    return hz


def _one_ta(value, naming: Naming):
    """(T_a, source) from ``value``: an actuator file (path) or a T_a object."""
    opt = naming("actuator")
    if not is_path(value):
        return ta_form(value, opt), GIVEN
    from rigsim.correction.io.actuator_file import read_actuator_file

    path = file_path(value, opt)
    try:
        return read_actuator_file(path), path
    except ValueError as exc:
        raise refusal(f"{opt}: {exc}") from None


def _corner_tas(value, naming: Naming) -> tuple[dict, str]:
    """(corner -> T_a, source) from ``value``: a per-corner actuator file (path) or a mapping."""
    opt = naming("actuators")
    if not is_path(value):
        if not isinstance(value, Mapping) or not value:
            raise refusal(f"{opt} must be a per-corner actuator file or a mapping of corner -> T_a, got "
                         f"{shown(value)}")
        return {str(c): ta_form(ta, f"{opt} {c!r}") for c, ta in value.items()}, GIVEN
    from rigsim.correction.io.actuator_file import read_actuators_file

    path = file_path(value, opt)
    try:
        return read_actuators_file(path), path
    except ValueError as exc:
        raise refusal(f"{opt}: {exc}") from None


def _fallback_tas(naming: Naming, actuator, actuators):
    """(the model's linear fallback T_a: one, or one per corner in corner order, or None; its source)."""
    from rigsim.mjcf.names import CORNERS

    if actuator is not None:
        return _one_ta(actuator, naming)
    if actuators is None:
        return None, None
    table, source = _corner_tas(actuators, naming)
    missing = [c for c in CORNERS if c not in table]
    if missing:
        raise refusal(f"{naming('actuators')} {source!r} has no corner {missing[0]!r}; the linear fallback of "
                     f"{naming('model')} corrects the four corners {', '.join(CORNERS)}")
    return [table[c] for c in CORNERS], source


def _options(options, naming: Naming):
    """(the model's options or None, the linear correction's options) from ``options``."""
    from rigsim.scenarios.records.options import LinearOptions, ModelOptions

    if isinstance(options, LinearOptions):
        return None, options
    if isinstance(options, ModelOptions):
        linear = LinearOptions() if options.linear is None else options.linear
        if not isinstance(linear, LinearOptions):
            raise refusal(f"{naming('linear')} must be a rigsim.LinearOptions (L's T_a and low-pass) or None, got "
                         f"{shown(linear)}")
        return options, linear
    raise refusal(f"{naming('options')} must be rigsim.LinearOptions(actuators=...) (the linear correction) or "
                 f"rigsim.ModelOptions(truck, pairs=...) (a truck model calibrated on the record), got {shown(options)}")


def correction_settings(options, *, columns=None, corner_map=None, transient: str = "drop", force_filter=None,
                        lvdt_filter=None, naming: Naming = KEYWORDS) -> CorrectionSettings:
    """Check the options of a correction and read their files: ``options`` a
    :class:`~rigsim.scenarios.records.options.LinearOptions` or
    :class:`~rigsim.scenarios.records.options.ModelOptions`, the rest
    :func:`rigsim.scenarios.records.api.correct_record`'s keywords (``naming``: how messages name
    the fields, by keyword or by flag).

    Raises
    ------
    ScenarioError
        One sentence naming the field (an option, a file, a T_a source) and the fix.
    """
    n = naming
    model, linear = _options(options, n)
    actuator, actuators, identify = linear.actuator, linear.actuators, linear.identify
    lowpass, lowpass_hz, mode, normalize_dc = linear.lowpass, linear.lowpass_hz, linear.mode, linear.normalize_dc
    cab = None if model is None else model.cab
    identify = checked_names(n, "identify", identify, "'DRIVE,DISP' or the two channel names")
    columns = checked_names(n, "columns", columns, "'A,B' or a sequence of channel names")
    corner_map = checked_corner_map(n, corner_map)
    _choice(n, "lowpass", lowpass, LOWPASSES)
    _choice(n, "mode", mode, MODES)
    _choice(n, "transient", transient, TRANSIENTS)
    _choice(n, "cab", "auto" if cab is None else cab, CABS)
    lowpass_hz = _check_lowpass(n, lowpass, lowpass_hz)
    normalize_dc = flag(n, "normalize_dc", normalize_dc)
    force_filter, lvdt_filter = check_timing(force_filter, "force_filter", n), check_timing(lvdt_filter, "lvdt_filter", n)
    if lvdt_filter is not None and model is None and identify is None:
        raise refusal(f"{n('lvdt_filter')} describes the LVDT channels that {n('identify')} or {n('model')} read; "
                     f"drop it, or identify T_a with it (rigsim identify --from-file takes it too)")
    common = dict(lowpass=lowpass, lowpass_hz=lowpass_hz, mode=mode, transient=transient,
                  normalize_dc=normalize_dc, cab="auto" if cab is None else cab, naming=n,
                  force_filter=force_filter, lvdt_filter=lvdt_filter)
    if model is None:
        id_cols = parse_identify(identify, n)
        asked, items = parse_columns(columns, n), parse_corner_map(corner_map, n)
        sources = [k for k, v in (("actuator", actuator), ("actuators", actuators), ("identify", identify))
                   if v is not None]
        if len(sources) != 1:
            raise refusal(f"give exactly one of {n.setting('actuator', 'ACT.toml')}, "
                         f"{n.setting('actuators', 'ACTS.toml')} and {n.setting('identify', 'DRIVE_COL,DISP_COL')}")
        if items is not None and actuators is None:
            raise refusal(f"{n('corner_map')} maps corners of a per-corner file: use it with "
                         f"{n.setting('actuators', 'ACTS.toml')}")
        ta, source = (None, None) if identify is not None else (
            _one_ta(actuator, n) if actuator is not None else _corner_tas(actuators, n))
        return CorrectionSettings(
            method="linear", columns=None if asked is None else tuple(asked),
            corner_map=None if items is None else tuple(items), identify=tuple(id_cols), ta=ta,
            per_corner=actuators is not None, ta_source=source, pairs=None, scenario=None, scenario_file=None,
            workers=None, max_evaluations=None, calibration_windows=None,
            inputs=(source,) if is_path(actuator) or is_path(actuators) else (), **common)
    pairs, workers = model_pairs_workers(n, identify, actuator, actuators, model.pairs, model.workers)
    max_evaluations = count(n, "max_evaluations", model.max_evaluations)
    calibration_windows = count(n, "calibration_windows", model.calibration_windows)
    drift_hz = checked_drift_hz(n, model.drift_cut_hz)
    scenario, scenario_file = truck_scenario(n, model.truck)
    saved, saved_file = saved_calibration(n, model.calibration, scenario)
    more = model.calibration_records
    if isinstance(more, (str, bytes, os.PathLike)) or not isinstance(more, (tuple, list)):
        raise refusal(f"{n('calibration_records')} must be a list of other records of this truck (files or "
                     f"read_record's records), got {shown(more)}")
    asked, items = parse_columns(columns, n), parse_corner_map(corner_map, n)
    ta, source = _fallback_tas(n, actuator, actuators)
    return CorrectionSettings(
        method="model", columns=None if asked is None else tuple(asked),
        corner_map=None if items is None else tuple(items), identify=(), ta=ta, per_corner=False,
        ta_source=source, pairs=pairs, scenario=scenario, scenario_file=scenario_file, workers=workers,
        max_evaluations=max_evaluations, calibration_windows=calibration_windows, drift_hz=drift_hz,
        saved=saved, saved_file=saved_file, calibration_records=tuple(more),
        inputs=tuple(f for f in (scenario_file, source, saved_file) if f not in (None, GIVEN)), **common)
