"""Sweep grid files: a base scenario plus axes (and/or a list of cases), expanded and validated.

A grid file is TOML::

    [sweep]
    name = "example"                 # optional; default: the file's stem
    base = "../paper/high_72kmh_3640kg.toml"   # the base scenario file (relative to this file)
    actuator = "identified"          # how each case is corrected and scored (all optional; the
    lowpass = "regularized"          # defaults are the paper study's "best" method and noise):
    correction_mode = "zerophase"    # see rigsim.scenarios.studies.sweep.settings
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

The axes and explicit cases are read by :func:`rigsim.scenarios.studies.sweep.axes.read_axes`, which
refuses a grid of more than :data:`MAX_CASES` cases from the lengths of its lists, before any
value is looked at. Every case is then validated with :func:`rigsim.scenarios.core.config.parse_scenario`
before anything runs; an unknown axis name or an invalid value is a
:class:`~rigsim.scenarios.core.config.ScenarioError` naming it.
Each case gets a stable id from its own values (keys sorted, so the order of the axes in the file
does not matter), e.g. ``road.roughness=high__speed_kmh=72__vehicle.payload_kg=3640``.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import pathlib
import re
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from rigsim.correction.io.tomlfile import check_keys, read_toml
from rigsim.scenarios.core.config import Scenario, ScenarioError, parse_scenario
from rigsim.scenarios.studies.sweep.axes import MAX_CASES, axis_keys, format_value, read_axes
from rigsim.scenarios.studies.sweep.settings import SETTING_KEYS, EvalSettings, parse_settings
from rigsim.scenarios.studies.scoring import MIN_SCORED_S, shortest_scorable_s

__all__ = ["Case", "SweepGrid", "EvalSettings", "axis_keys", "load_grid", "parse_grid", "format_value",
           "GRID_FORMAT", "MAX_CASES"]

#: Version of the case-file format and of the fingerprint recipe (part of every fingerprint): a
#: case file of another version is not reused. Raise it whenever either changes.
GRID_FORMAT = 3

_SWEEP_KEYS = {"name", "base", *SETTING_KEYS}
_GRID_KEYS = {"sweep", "base", "axes", "cases"}
_ROAD_CHOICE = ("roughness", "gd_n0_m3", "profile_csv")
_MAX_ID = 180  # characters; longer ids end in a hash (file names stay below common limits)


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


def _refuse(where: str):
    """The ``error`` of :mod:`rigsim.correction.io.tomlfile` checks: a ScenarioError prefixed by ``where``."""
    return lambda message: ScenarioError(f"{where}{message}")


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

    axes, explicit = read_axes(doc.get("axes", {}), doc.get("cases", None), where)  # the cap checked first
    if not axes and not explicit:
        explicit = [{}]  # a sweep of one case: the base

    extra_keys: list[str] = []
    for flat in explicit:
        for key in flat:
            if key not in extra_keys:
                extra_keys.append(key)
    all_axes = tuple(axes) + tuple(
        (k, tuple({format_value(f[k]): f[k] for f in explicit if k in f}.values())) for k in extra_keys)

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
