"""A programme's settings: its records and their truck configurations, from flags or a programme file.

A programme is many records of one or more truck configurations (:class:`TruckSettings`: the
truck file, the channels and the calibration's options, as ``rigsim correct --model`` takes them),
each record corrected into ``NAME_corrected.EXT`` (:class:`RecordEntry`). :func:`from_flags` makes
one configuration from ``rigsim programme``'s flags and expands the inputs (files, folders, globs);
:func:`read_programme` reads a programme file::

    [trucks.loaded]
    model = "truck.toml"              # relative to the programme file
    pairs = "fl=Soll_FL:Weg_FL,fr=Soll_FR:Weg_FR,rl=Soll_RL:Weg_RL,rr=Soll_RR:Weg_RR"
    cab = "held"                      # map, columns, time_col, decimal, thousands, cab,
                                      # calibration_windows, max_evaluations, drift_cut_hz,
    calibrate_on = 3                  # calibrate_on: windows of the truck's first N records

    [[records]]
    path = "day1/*.csv"               # a file, a folder or a glob
    truck = "loaded"                  # may be left out where one truck is configured

Every refusal is one :class:`~rigsim.scenarios.core.config.ScenarioError` sentence naming the flag
or key and the fix, before any work: each configuration's options are checked by the records API
(:func:`rigsim.scenarios.records.settings.correction_settings`, reading TRUCK.toml). Paths are
absolute, so that every worker reads the same files.
"""

from __future__ import annotations

import glob
import os
import pathlib
import re
from dataclasses import asdict, dataclass

from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.records.naming import CLI_NAMING

__all__ = ["FORMATS", "CALIBRATE_ON", "TRUCK_KEYS", "TruckSettings", "RecordEntry", "Programme", "from_flags", "read_programme"]

#: The output formats ``--format`` names (default: each record's own).
FORMATS = ("csv", "rsp", "mf4", "tdms")
#: The records API's field -> the configuration's key.
_FIELDS = {"truck": "model", "pairs": "pairs", "corner_map": "map", "columns": "columns", "cab": "cab",
           "calibration_windows": "calibration_windows", "max_evaluations": "max_evaluations",
           "drift_cut_hz": "drift_cut_hz", "calibration_records": "calibrate_on"}
#: A truck configuration's keys in a programme file, and the flag each is in ``rigsim programme``:
#: ``rigsim correct``'s (:data:`~rigsim.scenarios.records.naming.FLAGS`), the reader's, and the
#: programme's own ``--calibrate-on``.
TRUCK_KEYS = {key: CLI_NAMING(field) for field, key in _FIELDS.items() if field != "calibration_records"} | {
    "time_col": "--time-col", "decimal": "--decimal", "thousands": "--thousands", "calibrate_on": "--calibrate-on"}
#: The records a truck is calibrated on by default: windows of its first three (or as many as it has).
#: Measured (``benchmarks/programme.py --duration-s 60``, a mismatched truck on roads and speeds of
#: its own, --cab auto): on 4 records each record's DLC corrected with the programme's calibration
#: within 0.135 % of the record calibrated alone with 3, within 0.200 % with 1; on 20 records with 3
#: (``--records 20 --alone 20``), 16 within 0.2 %, worst 0.290 %, and the DLC error against the road
#: the same as the records calibrated alone (0.572 % and 0.571 % mean over 80 wheels).
CALIBRATE_ON = 3
#: The extensions a folder's records are found by.
RECORD_EXTENSIONS = (".csv", ".txt", ".dat", ".rsp", ".drv", ".tim", ".rpc", ".mf4", ".mdf", ".tdms")
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")


@dataclass(frozen=True)
class TruckSettings:
    """One truck configuration: the truck, its channels and the calibration's options.

    Attributes
    ----------
    name : str
        The configuration's name; its calibration is ``NAME.calibration.json``.
    model : str
        TRUCK.toml (absolute).
    pairs : str
        One ``DRIVE:LVDT`` pair per corner, ``fl=Soll_FL:Weg_FL,...``.
    map, columns, time_col, decimal, thousands, cab : str or None
        As ``rigsim correct`` takes them.
    calibration_windows, max_evaluations : int or None
    drift_cut_hz : float or None, Hz
    calibrate_on : int or None
        The truck is calibrated on windows of its first this many records (default
        :data:`CALIBRATE_ON`; ``ModelOptions.calibration_records``).
    where : str
        How messages name a key: ``""`` (the flags) or ``"[trucks.NAME] "`` (a programme file).
    """

    name: str
    model: str
    pairs: str
    map: str | None = None
    columns: str | None = None
    time_col: str | None = None
    decimal: str | None = None
    thousands: str | None = None
    cab: str | None = None
    calibration_windows: int | None = None
    max_evaluations: int | None = None
    drift_cut_hz: float | None = None
    calibrate_on: int | None = None
    where: str = ""

    def naming(self):
        """The records API's :class:`~rigsim.scenarios.records.naming.Naming` for this configuration's messages."""
        from rigsim.scenarios.records.naming import Naming

        def name(key):
            return TRUCK_KEYS[key] if not self.where else f"{self.where}{key}"
        return Naming({field: name(key) for field, key in _FIELDS.items()} | {"model": name("model"), "path": "--out"})

    def options(self, calibration=None, *, workers: int | None = 1, more=()):
        """The :class:`~rigsim.scenarios.records.options.ModelOptions` of a record of this truck:
        ``workers`` processes for its model runs (one where the programme runs records side by side;
        None: all cores), ``calibration`` the saved calibration to reuse (None: calibrate on the
        record, and on windows of the records ``more`` too)."""
        from rigsim.scenarios.records.options import ModelOptions

        return ModelOptions(self.model, pairs=self.pairs, workers=workers, max_evaluations=self.max_evaluations,
                            calibration_windows=self.calibration_windows, cab=self.cab,
                            drift_cut_hz=self.drift_cut_hz, calibration=calibration, calibration_records=tuple(more))

    def call(self) -> dict:
        """The keywords of :func:`rigsim.scenarios.records.api.plan_correction` besides the options."""
        return {"columns": self.columns, "corner_map": self.map, "naming": self.naming(), "time_col": self.time_col,
                "decimal": self.decimal, "thousands": self.thousands}

    def as_dict(self) -> dict:
        """The settings that make a record's output (the resume's fingerprint)."""
        return {k: v for k, v in asdict(self).items() if k != "where"}

    def check(self) -> None:
        """Check the options as the records API does before any work (reads TRUCK.toml)."""
        from rigsim.scenarios.records.settings import correction_settings

        call = self.call()
        if self.calibrate_on is not None and self.calibrate_on < 1:
            raise ScenarioError(f"{self.naming()('calibration_records')} must be a whole number >= 1 (the records "
                                f"the truck is calibrated on), got {self.calibrate_on}; give a positive number")
        correction_settings(self.options(), columns=call["columns"], corner_map=call["corner_map"],
                            naming=call["naming"])


@dataclass(frozen=True)
class RecordEntry:
    """One record of the programme.

    Attributes
    ----------
    path : str
        The record (absolute).
    truck : str
        Its truck configuration's name.
    name : str
        The record's name in the programme: its file name without extension.
    output : str
        The corrected file's name in ``--out``: ``NAME_corrected`` and the extension.
    """

    path: str
    truck: str
    name: str
    output: str


@dataclass(frozen=True)
class Programme:
    """The records and their truck configurations, checked.

    Attributes
    ----------
    trucks : tuple of TruckSettings
    records : tuple of RecordEntry
        In the order given: a configuration is calibrated on its first record.
    """

    trucks: tuple
    records: tuple

    def truck(self, name: str) -> TruckSettings:
        """The configuration named ``name``."""
        return next(t for t in self.trucks if t.name == name)


def _expand(text: str, option: str, base: pathlib.Path | None = None) -> list[pathlib.Path]:
    """The records ``text`` names: a file, every record of a folder, or a glob's matches (sorted)."""
    path = pathlib.Path(os.path.expanduser(text))
    if base is not None and not path.is_absolute():
        path = base / path
    if glob.has_magic(str(path)):
        found = sorted(pathlib.Path(p) for p in glob.glob(str(path), recursive=True) if os.path.isfile(p))
        if not found:
            raise ScenarioError(f"{option} {text!r} matches no file; check the pattern")
        return [p.absolute() for p in found]
    if path.is_dir():
        found = sorted(p for p in path.iterdir() if p.is_file() and p.suffix.lower() in RECORD_EXTENSIONS)
        if not found:
            raise ScenarioError(f"{option} {text!r} is a folder with no record ({', '.join(RECORD_EXTENSIONS)}); "
                                "name the files")
        return [p.absolute() for p in found]
    if not path.is_file():
        raise ScenarioError(f"{option} {text!r} does not exist; give a record file, a folder or a glob")
    return [path.absolute()]


def _entries(paths: list[tuple[pathlib.Path, str]], out_format: str | None, option: str) -> tuple:
    """One :class:`RecordEntry` per distinct record, refusing two that would write the same output."""
    if out_format is not None and out_format not in FORMATS:
        raise ScenarioError(f"--format {out_format!r} is not one of {', '.join(FORMATS)}; give one of them")
    entries, seen = [], {}
    for path, truck in paths:
        if any(path == p for p, _ in seen.values()):
            continue
        ext = f".{out_format}" if out_format else path.suffix
        if ext.lower() not in RECORD_EXTENSIONS:
            raise ScenarioError(f"{option} {str(path)!r} has no record extension ({', '.join(RECORD_EXTENSIONS)}); "
                                "rename it or leave it out")
        name = path.stem
        if name.lower() in seen:
            raise ScenarioError(f"{option}: records {str(seen[name.lower()][0])!r} and {str(path)!r} would both be "
                                f"written as {name}_corrected{ext} in --out; rename one of them")
        seen[name.lower()] = (path, truck)
        entries.append(RecordEntry(str(path), truck, name, f"{name}_corrected{ext}"))
    return tuple(entries)


def from_flags(inputs, *, model: str | None, pairs: str | None, out_format: str | None = None, **options) -> Programme:
    """The programme of ``rigsim programme IN... --model TRUCK.toml --pairs ...``: one truck
    configuration (named after TRUCK.toml's file name), every input expanded.

    ``options``: the configuration's other fields (:data:`TRUCK_KEYS`), None where not given.

    Raises
    ------
    ScenarioError
        No input, no ``--model`` or ``--pairs``, an input that names no record, two records of one
        name, an option the records API refuses (one sentence naming the flag).
    """
    if not inputs:
        raise ScenarioError("rigsim programme needs records: give files, folders or globs, or --programme FILE.toml")
    if model is None or pairs is None:
        raise ScenarioError("rigsim programme needs the truck: give --model TRUCK.toml and --pairs fl=DRIVE:LVDT,... "
                            "(or --programme FILE.toml)")
    truck = TruckSettings(_truck_name(pathlib.Path(model).stem, "--model"), str(pathlib.Path(model).absolute()),
                          pairs, **options)
    truck.check()
    paths = [(p, truck.name) for text in inputs for p in _expand(text, "IN")]
    return Programme((truck,), _entries(paths, out_format, "IN"))


def _truck_name(name: str, where: str) -> str:
    if not _NAME.fullmatch(name):
        raise ScenarioError(f"{where}: the truck configuration's name {name!r} must be letters, digits, '_', '-' or "
                            "'.' (it names its calibration file); rename it")
    return name


def _typed(where: str, key: str, value, kind):
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kind) or isinstance(value, bool):
        raise ScenarioError(f"{where}{key} must be a {'whole number' if kind is int else kind.__name__}, got "
                            f"{value!r}; write it as such")
    return value


def read_programme(path, out_format: str | None = None) -> Programme:
    """Read a programme file (the format in this module's docstring); paths relative to its folder.

    Raises
    ------
    ScenarioError
        One sentence naming the file and the key: not TOML, an unknown key, a truck configuration
        without ``model`` or ``pairs``, a record without ``path`` or naming an unknown truck, an
        option the records API refuses.
    """
    from rigsim.correction.io.tomlfile import check_keys, read_toml

    path = pathlib.Path(path).absolute()
    doc = read_toml(path, "programme file", error=ScenarioError)
    shown = f"programme file {str(path)!r}"
    check_keys(doc, ("trucks", "records"), shown, error=ScenarioError)
    trucks_doc, records_doc = doc.get("trucks"), doc.get("records")
    if not isinstance(trucks_doc, dict) or not trucks_doc:
        raise ScenarioError(f"{shown} has no [trucks.NAME] table; add one with model and pairs")
    if not isinstance(records_doc, list) or not records_doc:
        raise ScenarioError(f"{shown} has no [[records]]; add one with path (and truck)")
    kinds = {"calibration_windows": int, "max_evaluations": int, "drift_cut_hz": float, "calibrate_on": int}
    trucks = []
    for name, table in trucks_doc.items():
        where = f"[trucks.{_truck_name(name, shown)}] "
        if not isinstance(table, dict):
            raise ScenarioError(f"{shown}: trucks.{name} must be a table of model, pairs and options")
        check_keys(table, TRUCK_KEYS, f"{shown} {where.strip()}", error=ScenarioError)
        for key in ("model", "pairs"):
            if key not in table:
                raise ScenarioError(f"{shown}: {where}has no {key}; add it as rigsim correct --model takes it")
        values = {k: _typed(where, k, v, kinds.get(k, str)) for k, v in table.items()}
        values["model"] = str((path.parent / os.path.expanduser(values["model"])).absolute())
        truck = TruckSettings(name, where=where, **values)
        truck.check()
        trucks.append(truck)
    names = [t.name for t in trucks]
    paths = []
    for i, rec in enumerate(records_doc):
        where = f"{shown} records[{i}]"
        if not isinstance(rec, dict):
            raise ScenarioError(f"{where} must be a table with path and truck")
        check_keys(rec, ("path", "truck"), where, error=ScenarioError)
        if not isinstance(rec.get("path"), str):
            raise ScenarioError(f"{where} has no path (a file, a folder or a glob); add it")
        truck = rec.get("truck", names[0] if len(names) == 1 else None)
        if truck not in names:
            raise ScenarioError(f"{where}: truck {truck!r} is not one of {', '.join(names)}; name a [trucks.NAME]")
        paths += [(p, truck) for p in _expand(rec["path"], f"{where} path", path.parent)]
    return Programme(tuple(trucks), _entries(paths, out_format, f"{shown} records"))
