"""The axes of a sweep grid: the keys a grid may sweep, its axes and explicit cases read and
checked, and the number of cases held to :data:`MAX_CASES`.

A grid's cases are the product of its axes (a ``[[cases]]`` list is one more axis), so their
number follows from the lengths of the lists alone. :func:`read_axes` checks the swept keys and
those lengths first and refuses a grid over the cap at once, whatever the size of its lists: the
values of a refused grid are never looked at. The values of an accepted grid (each a number or a
string, none twice on one axis) are then checked in time linear in their number.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping
from typing import Any

from rigsim.correction.io.tomlfile import check_keys
from rigsim.scenarios.core.config import RoadConfig, Scenario, ScenarioError

__all__ = ["MAX_CASES", "axis_keys", "check_key", "flatten", "format_value", "read_axes"]

#: Most cases a grid may have. Each case is two runs (tens of core-seconds for a 60 s case) and
#: a validated scenario in memory (~2 kB); 10 000 cases are days of a cluster's time, more is
#: almost surely an axis given too many values (a million cases take 1.9 GB just to validate).
MAX_CASES = 10_000


def axis_keys() -> dict[str, tuple[str, ...]]:
    """The keys a grid may sweep: ``{"": top-level, "road": ..., "vehicle": ..., "actuator": ...}``."""
    from rigsim.hydraulics.params import ActuatorParams
    from rigsim.mjcf.variant import TruckVariant

    top = tuple(f.name for f in dataclasses.fields(Scenario) if f.name not in
                ("name", "source", "road", "vehicle", "actuator"))
    return {
        "": top,
        "road": tuple(f.name for f in dataclasses.fields(RoadConfig)),
        "vehicle": tuple(f.name for f in dataclasses.fields(TruckVariant)),
        "actuator": tuple(f.name for f in dataclasses.fields(ActuatorParams)),
    }


@functools.lru_cache(maxsize=1)
def _dotted_keys() -> tuple[str, ...]:
    """Every key of :func:`axis_keys`, dotted (``vehicle.payload_kg``): computed once, as a grid
    may check thousands of explicit cases' keys."""
    valid = axis_keys()
    return (*valid[""], *(f"{t}.{n}" for t in ("road", "vehicle", "actuator") for n in valid[t]))


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
    """A key :func:`rigsim.correction.io.tomlfile.check_keys` refused (its close-match hint is reused)."""


def check_key(key: str, where: str) -> None:
    """Refuse a swept key that is not a scenario key, suggesting the closest one.

    Raises
    ------
    ScenarioError
        ``"{where} {key} is not a scenario key; did you mean ...?"``.
    """
    everything = _dotted_keys()
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


def flatten(table: Mapping, prefix: str = "") -> dict[str, Any]:
    """``{"vehicle": {"payload_kg": x}}`` -> ``{"vehicle.payload_kg": x}`` (TOML dotted keys)."""
    out: dict[str, Any] = {}
    for k, v in table.items():
        key = f"{prefix}{k}"
        if isinstance(v, Mapping):
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


def _scalar(value: Any) -> bool:
    return isinstance(value, (bool, int, float, str))


def _check_size(lengths: list[tuple[str, int]], where: str) -> None:
    """Refuse a grid whose product of axis lengths (``(name, length)`` pairs) is over the cap."""
    n_cases = math.prod(n for _, n in lengths)
    if n_cases > MAX_CASES:
        product = " x ".join(f"{n} {name}" for name, n in lengths)
        raise ScenarioError(f"{where}the grid has {n_cases} cases ({product}), more than the cap of {MAX_CASES}; "
                            "split it into several grids or give the axes fewer values")


def _check_values(key: str, values: list, where: str) -> None:
    """Each value of axis ``key`` a number or a string, none given twice (as its case id shows it)."""
    seen: set[str] = set()
    for v in values:
        if not _scalar(v):
            raise ScenarioError(f"{where}axis {key} has a value that is not a number or string: {v!r}")
        shown = format_value(v)
        if shown in seen:
            shown = shown if shown and shown.isprintable() and shown.strip() == shown else repr(shown)  # one line, visible
            raise ScenarioError(f"{where}axis {key} lists the value {shown} twice")
        seen.add(shown)


def read_axes(axes_table: Any, cases_list: Any, where: str = "") -> tuple[list[tuple[str, tuple]], list[dict]]:
    """Read a grid's ``[axes]`` table and ``[[cases]]`` list, the number of cases checked first.

    Parameters
    ----------
    axes_table : Mapping
        The grid's ``[axes]`` (``{}`` if it has none): each key a scenario key, each value a list.
    cases_list : list of Mapping or None
        The grid's ``[[cases]]``, or None if it has none.
    where : str
        Prefix of every message (the grid file's name and ``": "``, or ``""``).

    Returns
    -------
    axes : list of (str, tuple)
        Each swept key (dotted) and its values, in file order.
    explicit : list of dict
        Each explicit case's overrides (dotted keys); empty without ``[[cases]]``.

    Raises
    ------
    ScenarioError
        One sentence: a key that is not a scenario key, an axis that is not a non-empty list, an
        axis or a ``[[cases]]`` list longer than :data:`MAX_CASES`, a product of lengths over it
        (all refused before any value is looked at), a value that is not a number or string, a
        value given twice on one axis, an explicit case that is not a table, a key both an axis
        and a key of an explicit case.
    """
    if not isinstance(axes_table, Mapping):
        raise ScenarioError(f"{where}[axes] must be a table of lists")
    flat_axes = flatten(axes_table)
    lengths: list[tuple[str, int]] = []
    for key, values in flat_axes.items():
        check_key(key, f"{where}axis")
        if not isinstance(values, list) or not values:
            raise ScenarioError(f"{where}axis {key} must be a non-empty list of values, got {values!r}")
        if len(values) > MAX_CASES:
            raise ScenarioError(f"{where}axis {key} has {len(values)} values, more than the cap of {MAX_CASES} "
                                "cases; split the grid into several grids or give the axis fewer values")
        lengths.append((key, len(values)))
    if cases_list is not None:
        if not isinstance(cases_list, list) or not cases_list:
            raise ScenarioError(f"{where}[[cases]] must be a non-empty array of tables of overrides")
        if len(cases_list) > MAX_CASES:
            raise ScenarioError(f"{where}[[cases]] lists {len(cases_list)} cases, more than the cap of {MAX_CASES}; "
                                "split the grid into several grids")
        lengths.append(("[[cases]]", len(cases_list)))
    _check_size(lengths, where)

    axes: list[tuple[str, tuple]] = []
    for key, values in flat_axes.items():
        _check_values(key, values, where)
        axes.append((key, tuple(values)))
    explicit: list[dict[str, Any]] = []
    if cases_list is not None:
        if not all(isinstance(c, Mapping) for c in cases_list):
            raise ScenarioError(f"{where}[[cases]] must be a non-empty array of tables of overrides")
        for i, table in enumerate(cases_list, 1):
            flat = flatten(table)
            for key, value in flat.items():
                check_key(key, f"{where}key of case {i}:")
                if key in flat_axes:
                    raise ScenarioError(f"{where}{key} is both an axis and a key of case {i}; keep one of them")
                if not _scalar(value):
                    raise ScenarioError(f"{where}case {i}: {key} must be a number or string, got {value!r}")
            explicit.append(flat)
    return axes, explicit
