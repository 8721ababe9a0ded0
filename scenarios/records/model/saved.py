"""A calibration as a file: the truck model calibrated on one record, kept to correct the next.

A programme on a road simulator is many records of one truck; its model is calibrated once and
reused. :class:`SavedCalibration` is what the file holds: the :class:`~.result.Calibration` (the
fitted values with their 1-sigma, the fixed ones, the fit figures per wheel), the model error
per wheel it had on its record, the truck description the fit started from (the spec sheet's
:data:`~rigsim.mjcf.description.DESCRIPTION_FIELDS`), the record and the windows it came from,
and the rigsim version. :func:`write_calibration` writes it as JSON (atomically, never over an
input), :func:`read_calibration` reads it back strictly: a file that is not a calibration, or one
whose fields do not make a truck, is refused in one sentence naming the key. Imports nothing heavy
at module level.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import MISSING, dataclass, fields

from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.records.model.result import Calibration

__all__ = ["FORMAT", "VERSION", "SavedCalibration", "spec_of", "write_calibration", "check_target", "read_calibration",
           "truck_differs", "on_record", "check_saved"]

#: The file's ``format`` key: what a reader checks before anything else.
FORMAT = "rigsim calibration"
#: The layout's version (an integer raised when a key changes meaning).
VERSION = 1


@dataclass(frozen=True)
class SavedCalibration:
    """A truck model calibrated on a record, as a file keeps it.

    Attributes
    ----------
    calibration : Calibration
        The fit: fitted and fixed values (SI), their 1-sigma, the fit figures per wheel.
    truck : Mapping[str, object]
        The description the fit started from: the given
        :data:`~rigsim.mjcf.description.DESCRIPTION_FIELDS` of TRUCK.toml's ``[vehicle]`` (SI;
        empty: the catalogue truck).
    truck_file : str
        TRUCK.toml as given to the calibration.
    record : str
        The record it was calibrated on, as given.
    record_s : float, s
        That record's duration.
    fs_hz : float, Hz
        Its sampling rate.
    rigsim_version : str
        The rigsim that calibrated it.
    also : tuple of str
        The other records whose windows were fitted too, as given (:attr:`Calibration.window_records`
        numbers them from 1); empty: the record's windows alone.

    Examples
    --------
    What ``CorrectionResult.saved_calibration`` holds after a correction by the truck model; one
    made by hand here, the payload and its place fitted:

    >>> import rigsim
    >>> cal = rigsim.Calibration(names=("payload_kg", "payload_x_m"), units=("kg", "m"),
    ...                          initial=(6000.0, -1.0), fitted=(6352.4, -1.32), sigma=(8.1, 0.004),
    ...                          sigma_robust=(21.0, 0.011), fixed={}, fit_nrmse=(0.041, 0.043, 0.052, 0.049),
    ...                          initial_nrmse=(0.31, 0.30, 0.42, 0.40), windows_s=((5.0, 10.0),),
    ...                          weighted=True, evaluations=42, converged=True, message="", wall_time_s=95.0)
    >>> saved = rigsim.SavedCalibration(cal, truck={"wheelbase_m": 4.6}, truck_file="truck.toml",
    ...                                 record="run1.csv", record_s=60.0, fs_hz=1000.0, rigsim_version="0.1.0")
    >>> saved.model_error
    (0.041, 0.043, 0.052, 0.049)
    """

    calibration: Calibration
    truck: Mapping
    truck_file: str
    record: str
    record_s: float
    fs_hz: float
    rigsim_version: str
    also: tuple = ()

    @property
    def model_error(self) -> tuple:
        """Per wheel fl, fr, rl, rr: the model error on its own record (1,
        :attr:`Calibration.excess_nrmse`)."""
        return self.calibration.excess_nrmse

    def to_dict(self) -> dict:
        """The file's content: ``format``, ``version``, then the fields (the model error per wheel
        beside the calibration, for a reader of the file). The calibration's wall time is left out
        (null): a time is kept apart from the outputs, so the same record gives the same file."""
        import dataclasses

        return {"format": FORMAT, "version": VERSION, "rigsim_version": self.rigsim_version,
                "truck_file": self.truck_file, "truck": dict(self.truck),
                "record": {"path": self.record, "duration_s": self.record_s, "fs_hz": self.fs_hz},
                **({"also_records": list(self.also)} if self.also else {}),
                "model_error": list(self.model_error),
                "calibration": dataclasses.replace(self.calibration, wall_time_s=None)}


def write_calibration(path, saved: SavedCalibration, *, overwrite: bool = False, inputs=()):
    """Write ``saved`` to ``path`` (JSON, atomically; the parent folder must exist).

    Parameters
    ----------
    path : str or os.PathLike
        The file (``.json``).
    saved : SavedCalibration
    overwrite : bool
        Replace an existing file; refused otherwise.
    inputs : sequence of paths
        Files read for this output: writing onto one of them is refused.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ScenarioError
        ``path`` exists (without ``overwrite``) or is one of ``inputs`` (one sentence).
    """
    from rigsim.scenarios.core.files import write_json

    return write_json(check_target(path, overwrite=overwrite, inputs=inputs), saved)


def check_target(path, *, overwrite: bool = False, inputs=(), beside: str = ""):
    """``path`` (a :class:`pathlib.Path`) where a calibration may be written: not one of ``inputs``
    (paths, the files read for this output), and, without ``overwrite``, not an existing file.

    Raises
    ------
    ScenarioError
        One sentence naming the file (and ``beside``, the output it goes with: "of -o out.csv") and the fix.
    """
    import pathlib

    path = pathlib.Path(os.fsdecode(path))
    said = f"calibration file {str(path)!r}" + (f" {beside}" if beside else "")
    if any(pathlib.Path(os.fsdecode(i)).resolve() == path.resolve() for i in inputs if i):
        raise ScenarioError(f"{said} is an input of this run; name another output")
    if path.exists() and not overwrite:
        raise ScenarioError(f"{said} exists; pass --force (overwrite=True) to replace it, or name another output")
    return path


def _fail(path, message: str):
    return ScenarioError(f"calibration file {str(path)!r}: {message}")


def _numbers(path, key: str, value, n: int | None = None, *, none: bool = False) -> tuple:
    if not isinstance(value, list) or (n is not None and len(value) != n):
        raise _fail(path, f"{key} must be a list of {n if n is not None else 'some'} numbers, got {value!r}"[:300])
    out = []
    for v in value:
        if v is None and none:
            out.append(math.nan)
        elif isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise _fail(path, f"{key} holds {v!r}, not a finite number")
        else:
            out.append(float(v))
    return tuple(out)


def _calibration(path, d) -> Calibration:
    from rigsim.scenarios.records.model.family import FITTED, UNITS

    if not isinstance(d, Mapping):
        raise _fail(path, "calibration must be a table of the fit's fields")
    known = {f.name for f in fields(Calibration)}
    required = {f.name for f in fields(Calibration) if f.default is MISSING and f.default_factory is MISSING}
    missing = sorted(required - set(d))
    if missing:
        raise _fail(path, f"calibration has no {missing[0]!r}; the file is not one rigsim correct --model wrote")
    extra = sorted(set(d) - known)
    if extra:
        raise _fail(path, f"calibration has an unknown key {extra[0]!r}; write it again with this rigsim")
    names = d["names"]
    if not isinstance(names, list) or not names or any(n not in FITTED for n in names) or len(set(names)) != len(names):
        raise _fail(path, f"calibration.names must be distinct fitted fields of the truck model ({', '.join(FITTED)})")
    n = len(names)
    fixed = d["fixed"]
    if not isinstance(fixed, Mapping) or any(not isinstance(v, (int, float, str, type(None))) or isinstance(v, bool)
                                             for v in fixed.values()):
        raise _fail(path, "calibration.fixed must be a table of field = number (or null for the XML's)")
    values = dict(d)
    values["names"] = tuple(names)
    values["units"] = tuple(UNITS[k] for k in names)
    for key in ("initial", "fitted", "sigma", "sigma_robust"):
        values[key] = _numbers(path, f"calibration.{key}", d[key], n, none=key.startswith("sigma"))
    for key in ("fit_nrmse", "initial_nrmse", "noise_nrmse", "band_nrmse", "band_noise_nrmse"):
        if key in d:
            values[key] = _numbers(path, f"calibration.{key}", d[key], None if key != "fit_nrmse" else 4)
    for key in ("windows_s", "bounds"):
        if key in d:
            rows = d[key]
            if not isinstance(rows, list):
                raise _fail(path, f"calibration.{key} must be a list of [start, end] pairs")
            values[key] = tuple(_numbers(path, f"calibration.{key}", r, 2) for r in rows)
    values["wheels"] = tuple(d.get("wheels", ()))
    owners = d.get("window_records", [])
    if (not isinstance(owners, list) or any(isinstance(i, bool) or not isinstance(i, int) or i < 0 for i in owners)
            or (owners and len(owners) != len(values.get("windows_s", ())))):
        raise _fail(path, "calibration.window_records must list a record number (0, 1, ...) per window of windows_s")
    values["window_records"] = tuple(owners)
    values["fixed"] = {k: (float(v) if isinstance(v, (int, float)) else v) for k, v in fixed.items()}
    cal = Calibration(**values)
    try:
        cal.variant()
    except (TypeError, ValueError) as exc:
        raise _fail(path, f"its fitted and fixed values make no truck ({str(exc).rstrip('.')})") from None
    return cal


def read_calibration(path) -> SavedCalibration:
    """Read a calibration file :func:`write_calibration` wrote.

    Parameters
    ----------
    path : str, bytes or os.PathLike
        The file.

    Returns
    -------
    SavedCalibration

    Raises
    ------
    ScenarioError
        The file cannot be read, is not JSON, not a calibration, of a later layout, or its values
        make no truck (one sentence naming the key).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import rigsim
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "run1.calibration.json"
    >>> _ = path.write_text('{"format": "rigsim calibration", "version": 9}')
    >>> try:
    ...     rigsim.read_calibration(path)
    ... except rigsim.RigsimError as error:
    ...     print(str(error).split(": ", 1)[1])
    has layout version 9, this rigsim reads 1
    """
    import pathlib

    path = pathlib.Path(os.fsdecode(path))
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise ScenarioError(f"calibration file {str(path)!r} does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise _fail(path, f"cannot be read ({exc})") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise _fail(path, f"is not JSON (line {exc.lineno}: {exc.msg})") from None
    if not isinstance(doc, Mapping) or doc.get("format") != FORMAT:
        raise _fail(path, f"is not a calibration (no format = {FORMAT!r}); rigsim correct --model writes one")
    if doc.get("version") != VERSION:
        raise _fail(path, f"has layout version {doc.get('version')!r}, this rigsim reads {VERSION}")
    record = doc.get("record")
    if not isinstance(record, Mapping):
        raise _fail(path, "record must be a table of path, duration_s and fs_hz")
    duration, fs = _numbers(path, "record", [record.get("duration_s"), record.get("fs_hz")], 2)
    truck = doc.get("truck")
    if not isinstance(truck, Mapping):
        raise _fail(path, "truck must be a table of the description's fields")
    also = doc.get("also_records", [])
    if not isinstance(also, list) or not all(isinstance(a, str) for a in also):
        raise _fail(path, "also_records must be a list of the other records' paths")
    cal = _calibration(path, doc.get("calibration"))
    if cal.window_records and max(cal.window_records) > len(also):
        raise _fail(path, f"calibration.window_records names record {max(cal.window_records)}, but also_records "
                          f"lists {len(also)}")
    return SavedCalibration(calibration=cal, truck=dict(truck),
                            truck_file=str(doc.get("truck_file", "")), record=str(record.get("path", "")),
                            record_s=duration, fs_hz=fs, rigsim_version=str(doc.get("rigsim_version", "")),
                            also=tuple(also))


def spec_of(scenario) -> dict:
    """The truck description a scenario's ``[vehicle]`` gives: its given
    :data:`~rigsim.mjcf.description.DESCRIPTION_FIELDS`, SI (empty: the catalogue truck)."""
    from rigsim.scenarios.records.model.first_guess import SPEC_FIELDS, description

    desc = description(scenario)
    return {k: getattr(desc, k) for k in SPEC_FIELDS if getattr(desc, k) is not None}


def truck_differs(saved: SavedCalibration, truck: Mapping) -> str:
    """One sentence naming the first description field where ``truck`` (the given ``[vehicle]``
    fields, SI) differs from the one ``saved`` was calibrated from (numbers to 1e-9 relative), or ""."""
    for key in sorted(set(saved.truck) | set(truck)):
        a, b = saved.truck.get(key), truck.get(key)
        same = (a == b if not (isinstance(a, (int, float)) and isinstance(b, (int, float)))
                else math.isclose(a, b, rel_tol=1e-9, abs_tol=0.0))
        if not same:
            return (f"the calibration was made for a truck described with {key} = {a!r}, this one has {b!r}: "
                    "calibrate this truck on its own record, or give its own description")
    return ""


def on_record(cal: Calibration, model_N, force_N, x_a_m, t_s, windows: tuple) -> Calibration:
    """``cal`` as this record shows it: its fit figures and model error on this record's own
    ``windows`` (each (lead-in start, scored start, end), samples), from the model's force with the
    pans following the measured x_a (``model_N``, N, (n, 4)); no fit, no evaluation counted.

    Parameters
    ----------
    cal : Calibration
        The calibration saved from another record.
    model_N : numpy.ndarray, N, (n, 4)
        The calibrated model's force on this record, pans following ``x_a_m``.
    force_N : numpy.ndarray, N, (n, 4)
        This record's measured wheel forces.
    x_a_m : numpy.ndarray, m, (n, 4)
        Its measured pan displacement (the load cells' fitted mass is taken out with it).
    t_s : numpy.ndarray, s, (n,)
    windows : tuple of (int, int, int)
        :func:`~rigsim.scenarios.records.model.calibrate.fit_windows` of this record.

    Returns
    -------
    Calibration
        ``cal`` with this record's ``fit_nrmse``, ``noise_nrmse``, ``band_nrmse``,
        ``band_noise_nrmse`` and ``windows_s`` (its :attr:`~Calibration.excess_nrmse` is the model
        error here), ``evaluations`` 0.
    """
    import dataclasses

    import numpy as np

    from rigsim.correction.identification.noise import noise_rms
    from rigsim.correction.metrics.dlc import nrmse
    from rigsim.scenarios.records.model.band_error import band_errors
    from rigsim.scenarios.records.model.cell_mass import without_cell_mass

    t = np.asarray(t_s, dtype=float)
    fs = 1.0 / (t[1] - t[0])
    model = np.asarray(model_N, dtype=float)
    force = without_cell_mass(force_N, x_a_m, fs, cal.cell_mass_kg)
    scored = np.concatenate([np.arange(s, e) for _, s, e in windows])
    fit = nrmse(model[scored], force[scored])
    noise = noise_rms(np.asarray(force_N, dtype=float), fs)
    band, band_noise = band_errors([model[a:e] for a, _, e in windows], force, windows, fs, noise)
    return dataclasses.replace(cal, fit_nrmse=tuple(float(v) for v in fit),
                               noise_nrmse=tuple(float(v) for v in noise / force[scored].std(axis=0)), band_nrmse=band,
                               band_noise_nrmse=band_noise, evaluations=0, window_records=(),
                               windows_s=tuple((float(t[s]), float(t[e - 1] + 1.0 / fs)) for _, s, e in windows))


def check_saved(cal: Calibration, model_runs, force_N, x_a_m, t_s, windows: tuple, limit: float) -> tuple:
    """A saved calibration checked on this record: (``cal`` as :func:`on_record` shows it, the
    model's runs, "") where its model error is within ``limit`` (1) on every wheel it was fitted
    on, else (None, None, one sentence: the truck is calibrated again).

    ``model_runs(variant)`` runs the calibrated truck on this record: a tuple of wheel forces (N,
    (n, 4)) whose last is on the measured pans, F_model(x_a), the one the check reads (the
    correction's (F_model(x_ref), F_model(x_a)) where it uses them as they are); ``windows`` are
    this record's (:func:`~rigsim.scenarios.records.model.calibrate.fit_windows`)."""
    import dataclasses
    import time

    import numpy as np

    from rigsim.mjcf.names import CORNERS

    t0 = time.perf_counter()
    runs = model_runs(cal.variant())
    here = on_record(cal, runs[-1], force_N, x_a_m, t_s, windows)
    here = dataclasses.replace(here, wall_time_s=round(time.perf_counter() - t0, 3))
    excess = np.where(np.isin(CORNERS, here.wheels), here.excess_nrmse, 0.0)
    if excess.max() <= limit:
        return here, runs, ""
    worst = int(np.argmax(excess))
    return None, None, (f"the saved calibration's model error on this record ({excess[worst]:.3f} on "
                        f"{CORNERS[worst]}) is past {limit:g}, so the truck was calibrated again from its values")
