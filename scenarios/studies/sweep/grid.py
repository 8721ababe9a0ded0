"""Sweep grid files: a base scenario plus axes (and/or a list of cases), expanded and validated.

A grid file is TOML::

    [sweep]
    name = "example"                 # optional; default: the file's stem
    base = "../paper/high_72kmh_3640kg.toml"   # the base scenario file (relative to this file)
    actuator = "identified"          # how each case is corrected and scored (all optional; the
    lowpass = "regularized"          # defaults are the paper study's "best" method and noise):
    correction_mode = "zerophase"    # see scenarios.studies.sweep.settings
    noise_N = 100.0

    [base]                           # ... or the base scenario inline (exactly one of the two)
    name = "base"
    speed_kmh = 72.0
    duration_s = 20.0
    road = { roughness = "high" }

    [axes]                           # each key a scenario key (dotted for tables), each value a list
    speed_kmh = [48, 72, 90]
    vehicle.payload_kg = [3640, 6360]
    road.roughness = ["medium", "high"]
    actuator.bulk_modulus_Pa = [1.0e9, 1.4e9]
    seed = [1, 2]

    [[cases]]                        # optional explicit cases: each a table of overrides
    vehicle.payload_kg = 3640
    vehicle.tire_stiffness_rear_N_per_m = 2.0e6

The cases are the cartesian product of the axes; with ``[[cases]]`` too, the list is one more
axis of the product (every explicit case is combined with every point of the axes); ``[[cases]]``
alone is the list. A key may not be both an axis and a key of an explicit case. Setting one of
``road.roughness``, ``road.gd_n0_m3``, ``road.profile_csv`` replaces the base's choice among them.

Every case is validated with :func:`scenarios.core.config.parse_scenario` before anything runs; an
unknown axis name or an invalid value is a :class:`~scenarios.core.config.ScenarioError` naming it.
Each case gets a stable id from its own values (keys sorted, so the order of the axes in the file
does not matter), e.g. ``road.roughness=high__speed_kmh=72__vehicle.payload_kg=3640``.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import itertools
import json
import math
import pathlib
import re
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from correction.tomlfile import check_keys, read_toml
from scenarios.core.config import RoadConfig, Scenario, ScenarioError, parse_scenario
from scenarios.studies.sweep.settings import SETTING_KEYS, EvalSettings, parse_settings
from scenarios.studies.scoring import MIN_SCORED_S, shortest_scorable_s

__all__ = ["Case", "SweepGrid", "EvalSettings", "axis_keys", "load_grid", "parse_grid", "format_value",
           "GRID_FORMAT", "MAX_CASES"]

#: Version of the case-file format and of the fingerprint recipe (part of every fingerprint).
#: 2: cases scored by scenarios.studies.scoring.score_pair (settings gained actuator, noise_N).
GRID_FORMAT = 3

_SWEEP_KEYS = {"name", "base", *SETTING_KEYS}
_GRID_KEYS = {"sweep", "base", "axes", "cases"}
_ROAD_CHOICE = ("roughness", "gd_n0_m3", "profile_csv")
_MAX_ID = 180  # characters; longer ids end in a hash (file names stay below common limits)

#: Most cases a grid may have. Each case is two runs (tens of core-seconds for a 60 s case) and
#: a validated scenario in memory (~2 kB); 10 000 cases are days of a cluster's time, more is
#: almost surely an axis given too many values (a million cases took 1.9 GB just to validate).
MAX_CASES = 10_000


@dataclass(frozen=True)
class Case:
    """One case of a sweep.

    Attributes
    ----------
    case_id : str
        Stable id from the case's own values (file-name safe).
    values : Mapping[str, object]
        The swept keys (dotted) and this case's values, in the grid's axis order.
    doc : Mapping
        The full scenario document of the case (base with the values applied), plain TOML types.
    source : pathlib.Path or None
        The file relative paths of the scenario (``road.profile_csv``) are resolved against.
    scenario : Scenario
        ``doc`` validated.
    fingerprint : str
        SHA-256 of the scenario document (and a measured profile's resolved path), the
        evaluation settings and :data:`GRID_FORMAT`: a finished case file is reused only if its
        fingerprint matches.
    """

    case_id: str
    values: Mapping[str, Any]
    doc: Mapping[str, Any]
    source: pathlib.Path | None
    scenario: Scenario
    fingerprint: str


@dataclass(frozen=True)
class SweepGrid:
    """A validated sweep.

    Attributes
    ----------
    name : str
    source : pathlib.Path or None
        The grid file.
    axes : tuple of (str, tuple)
        Swept keys and their values in file order (the explicit cases' keys after them).
    cases : tuple of Case
        In product order.
    settings : EvalSettings
    """

    name: str
    source: pathlib.Path | None
    axes: tuple[tuple[str, tuple], ...]
    cases: tuple[Case, ...]
    settings: EvalSettings

    @property
    def keys(self) -> tuple[str, ...]:
        """All swept keys (dotted), axes first, then keys of explicit cases."""
        return tuple(k for k, _ in self.axes)


def axis_keys() -> dict[str, tuple[str, ...]]:
    """The keys a grid may sweep: ``{"": top-level, "road": ..., "vehicle": ..., "actuator": ...}``."""
    from hydraulics.params import ActuatorParams
    from mjcf.build import TruckVariant

    top = tuple(f.name for f in dataclasses.fields(Scenario) if f.name not in
                ("name", "source", "road", "vehicle", "actuator"))
    return {
        "": top,
        "road": tuple(f.name for f in dataclasses.fields(RoadConfig)),
        "vehicle": tuple(f.name for f in dataclasses.fields(TruckVariant)),
        "actuator": tuple(f.name for f in dataclasses.fields(ActuatorParams)),
    }


def format_value(value: Any) -> str:
    """A value as it appears in case ids and CSV cells: integral floats without ".0", else repr."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if value.is_integer() and abs(value) < 1e16:
            return str(int(value))
        return repr(value)
    return str(value)


class _UnknownKey(Exception):
    """A key :func:`correction.tomlfile.check_keys` refused (its close-match hint is reused)."""


def _check_key(key: str, where: str) -> None:
    """Refuse a swept key that is not a scenario key, suggesting the closest one."""
    valid = axis_keys()
    everything = [*valid[""], *(f"{t}.{n}" for t in ("road", "vehicle", "actuator") for n in valid[t])]
    if key in everything:
        return
    # A unit suffix left out ("speed" for "speed_kmh") first, else the closest key.
    hint = next((f"; did you mean {k!r}?" for k in everything if k.startswith(key + "_")), "")
    if not hint:
        try:
            check_keys({key: None}, everything, "", error=_UnknownKey)
        except _UnknownKey as exc:
            _, found, match = str(exc).rpartition("; did you mean ")
            hint = found + match if found else \
                "; sweep a top-level key (speed_kmh, seed...) or road.*, vehicle.*, actuator.*"
    if key in ("name", "description"):
        hint = "; each case's name is made from the base's name and the case id"
    raise ScenarioError(f"{where} {key} is not a scenario key{hint}")


def _refuse(where: str):
    """The ``error`` of :mod:`correction.tomlfile` checks: a ScenarioError prefixed by ``where``."""
    return lambda message: ScenarioError(f"{where}{message}")


def _flatten(table: Mapping, prefix: str = "") -> dict[str, Any]:
    """``{"vehicle": {"payload_kg": x}}`` -> ``{"vehicle.payload_kg": x}`` (TOML dotted keys)."""
    out: dict[str, Any] = {}
    for k, v in table.items():
        key = f"{prefix}{k}"
        if isinstance(v, Mapping):
            out.update(_flatten(v, key + "."))
        else:
            out[key] = v
    return out


def _scalar(value: Any) -> bool:
    return isinstance(value, (bool, int, float, str))


def _apply(base: Mapping, values: Mapping[str, Any]) -> dict:
    doc = copy.deepcopy(dict(base))
    for key, value in values.items():
        parts = key.split(".")
        if len(parts) == 1:
            doc[key] = value
            continue
        table = dict(doc.get(parts[0], {}))
        if parts[0] == "road" and parts[1] in _ROAD_CHOICE:
            for other in _ROAD_CHOICE:
                table.pop(other, None)
        table[parts[1]] = value
        doc[parts[0]] = table
    return doc


def _show(value: Any) -> str:
    """A value as TOML would write it (strings quoted)."""
    return json.dumps(value) if isinstance(value, str) else format_value(value)


def _slug(value: Any) -> str:
    return re.sub(r"[^A-Za-z0-9.+-]", "-", format_value(value))


def _case_id(values: Mapping[str, Any]) -> str:
    if not values:
        return "base"
    cid = "__".join(f"{k}={_slug(values[k])}" for k in sorted(values))
    if len(cid) > _MAX_ID:
        digest = hashlib.sha256(cid.encode()).hexdigest()[:12]
        cid = cid[: _MAX_ID - 14] + "~" + digest
    return cid


def _fingerprint(doc: Mapping, source: pathlib.Path | None, settings: EvalSettings) -> str:
    # The source folder matters only for a measured profile's relative path; leaving it out
    # otherwise lets a sweep folder be resumed after the project or the grid file moved.
    profile = doc.get("road", {}).get("profile_csv")
    where = str((source.parent if source else pathlib.Path()) / profile) if profile else None
    blob = json.dumps({"format": GRID_FORMAT, "scenario": doc, "profile_csv": where,
                       "evaluation": settings.as_dict()}, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()


def _base(doc: Mapping, source: pathlib.Path | None, where: str) -> tuple[dict, pathlib.Path | None]:
    sweep = doc.get("sweep", {})
    if ("base" in sweep) == ("base" in doc):
        raise ScenarioError(f"{where}give the base scenario either as sweep.base = \"FILE.toml\" or as a [base] "
                            "table, exactly one of them")
    if "base" in doc:
        if not isinstance(doc["base"], Mapping):
            raise ScenarioError(f"{where}[base] must be a table (a scenario)")
        base = dict(doc["base"])
        base.setdefault("name", "sweep")
        return base, source
    if not isinstance(sweep["base"], str):
        raise ScenarioError(f"{where}sweep.base must be a scenario file path string")
    path = pathlib.Path(sweep["base"])
    if not path.is_absolute() and source is not None:
        path = source.parent / path
    path = path.resolve()
    return read_toml(path, "base scenario file", error=ScenarioError), path


def _validate(base: Mapping, values: Mapping, source, case_id: str, where: str) -> tuple[dict, Scenario]:
    doc = _apply(base, values)
    doc["name"] = f"{base.get('name', 'sweep')}[{case_id}]"
    try:
        return doc, parse_scenario(doc, source=source)
    except ScenarioError as exc:
        # Name the value that is refused on its own, if one is; else the combination.
        for key, value in values.items():
            try:
                parse_scenario({**_apply(base, {key: value}), "name": "check"}, source=source)
            except ScenarioError as single:
                raise ScenarioError(f"{where}{key} = {_show(value)} is refused: {single}") from None
        raise ScenarioError(f"{where}case {case_id} is refused: {exc}") from None


def parse_grid(doc: Mapping, *, source: pathlib.Path | None = None) -> SweepGrid:
    """Validate a parsed grid document (see the module docstring) into a :class:`SweepGrid`.

    Parameters
    ----------
    doc : Mapping
        The TOML document.
    source : pathlib.Path, optional
        The grid file (relative ``sweep.base`` paths and the inline base's relative paths).

    Returns
    -------
    SweepGrid

    Raises
    ------
    ScenarioError
        One sentence naming the unknown key, axis or value, or the case that is refused.
    """
    where = f"{source.name}: " if source is not None else ""
    check_keys(doc, _GRID_KEYS, "", error=_refuse(where))
    sweep = doc.get("sweep", {})
    if not isinstance(sweep, Mapping):
        raise ScenarioError(f"{where}[sweep] must be a table")
    check_keys(sweep, _SWEEP_KEYS, "sweep.", error=_refuse(where))
    settings = parse_settings(sweep, where)
    base, base_source = _base(doc, source, where)
    name = sweep.get("name", source.stem if source is not None else "sweep")
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9._-]+", name):
        raise ScenarioError(f"{where}sweep.name must be letters, digits, '.', '_' or '-', got {name!r}")

    axes_table = doc.get("axes", {})
    if not isinstance(axes_table, Mapping):
        raise ScenarioError(f"{where}[axes] must be a table of lists")
    axes: list[tuple[str, tuple]] = []
    for key, values in _flatten(axes_table).items():
        _check_key(key, f"{where}axis")
        if not isinstance(values, list) or not values:
            raise ScenarioError(f"{where}axis {key} must be a non-empty list of values, got {values!r}")
        for v in values:
            if not _scalar(v):
                raise ScenarioError(f"{where}axis {key} has a value that is not a number or string: {v!r}")
        seen = [format_value(v) for v in values]
        dup = next((s for s in seen if seen.count(s) > 1), None)
        if dup is not None:
            shown = dup if dup and dup.isprintable() and dup.strip() == dup else repr(dup)  # one line, visible
            raise ScenarioError(f"{where}axis {key} lists the value {shown} twice")
        axes.append((key, tuple(values)))

    cases_list = doc.get("cases", None)
    explicit: list[dict[str, Any]] = []
    if cases_list is not None:
        if not isinstance(cases_list, list) or not cases_list or not all(isinstance(c, Mapping) for c in cases_list):
            raise ScenarioError(f"{where}[[cases]] must be a non-empty array of tables of overrides")
        axis_names = {k for k, _ in axes}
        for i, table in enumerate(cases_list, 1):
            flat = _flatten(table)
            for key, value in flat.items():
                _check_key(key, f"{where}key of case {i}:")
                if key in axis_names:
                    raise ScenarioError(f"{where}{key} is both an axis and a key of case {i}; keep one of them")
                if not _scalar(value):
                    raise ScenarioError(f"{where}case {i}: {key} must be a number or string, got {value!r}")
            explicit.append(flat)
    if not axes and not explicit:
        explicit = [{}]  # a sweep of one case: the base

    extra_keys: list[str] = []
    for flat in explicit:
        for key in flat:
            if key not in extra_keys:
                extra_keys.append(key)
    all_axes = tuple(axes) + tuple(
        (k, tuple({format_value(f[k]): f[k] for f in explicit if k in f}.values())) for k in extra_keys)

    sizes = [len(vals) for _, vals in axes] + ([len(explicit)] if explicit else [])
    n_cases = math.prod(sizes)
    if n_cases > MAX_CASES:
        product = " x ".join([*(f"{len(vals)} {k}" for k, vals in axes),
                              *([f"{len(explicit)} [[cases]]"] if cases_list is not None else [])])
        raise ScenarioError(f"{where}the grid has {n_cases} cases ({product}), more than the cap of {MAX_CASES}; "
                            "split it into several grids or give the axes fewer values")
    cases: list[Case] = []
    ids: dict[str, dict] = {}
    for point in itertools.product(*[[(k, v) for v in vals] for k, vals in axes]):
        for flat in explicit or [{}]:
            values = dict(point)
            values.update(flat)
            cid = _case_id(values)
            if cid in ids:
                raise ScenarioError(f"{where}two cases get the same id {cid} ({ids[cid]} and {values}); "
                                    "make their values differ")
            ids[cid] = values
            case_doc, scenario = _validate(base, values, base_source, cid, where)
            shortest = shortest_scorable_s(scenario.output_rate_hz, settings.method)
            if scenario.duration_s < shortest:
                raise ScenarioError(f"{where}case {cid}: duration_s = {scenario.duration_s:g} s is too short to "
                                    f"score (the band limit's transients alone take {shortest - MIN_SCORED_S:.2g} s); "
                                    f"give well over {shortest:.2g} s")
            cases.append(Case(case_id=cid, values=MappingProxyType(values), doc=MappingProxyType(case_doc),
                              source=base_source, scenario=scenario,
                              fingerprint=_fingerprint(case_doc, base_source, settings)))
    return SweepGrid(name=name, source=source, axes=all_axes, cases=tuple(cases), settings=settings)


def load_grid(path) -> SweepGrid:
    """Read and validate a grid file (see the module docstring).

    Raises
    ------
    ScenarioError
        Missing file, malformed TOML, unknown key or axis, invalid value; one sentence.
    """
    p = pathlib.Path(path).resolve()
    return parse_grid(read_toml(p, "grid file", error=ScenarioError), source=p)
