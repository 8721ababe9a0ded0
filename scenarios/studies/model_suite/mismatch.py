"""The mismatch suite's plant trucks: real trucks, drawn at random, several differences at once.

Each plant draws every feature of ``scenarios/data/suites/mismatch_plants.toml`` (seeded,
uniform within its range): factors on the case's payload and the XML's catalogue values, offsets
of the payload's position, each wheel station's own tire and leaf spring (:mod:`rigsim.mjcf.stations`),
the dampers' rebound ratio, and with a probability a suspended cab and tires that stiffen. The
model correction calibrates from the rig's records alone and never sees these values. Plant ``i``
runs on the generalization suite's case ``i`` (roads, speeds, payloads), measured as a lab
measures (:data:`rigsim.scenarios.core.lab.TYPICAL_LAB`).
"""

from __future__ import annotations

import dataclasses
import functools
import tomllib
import types
from collections.abc import Mapping

import numpy as np

from rigsim.mjcf.build import nominal_values
from rigsim.mjcf.names import CORNERS
from rigsim.mjcf.stations import STATION_FACTORS, station_factor_field
from rigsim.mjcf.variant import TruckVariant
from rigsim.scenarios.core.config import Scenario
from rigsim.scenarios.core.run import run
from rigsim.scenarios.studies.identify.compute import identify_rig
from rigsim.scenarios.studies.suites import case_payload_kg, case_scenario, suite_file

__all__ = ["MISMATCH_FILE", "PlantRanges", "plant_ranges", "draw_plant", "mismatch_plants", "mismatch_scenario",
           "mismatch_job", "describe"]

#: The data file of the plants' ranges, under ``scenarios/data/suites/``.
MISMATCH_FILE = "mismatch_plants.toml"
#: The seed stream of the plants' draws: ``numpy.random.default_rng((seed, PLANT_STREAM, i))``.
PLANT_STREAM = 31


@dataclasses.dataclass(frozen=True)
class PlantRanges:
    """The ranges the plants are drawn from (read-only mappings of ``(low, high)``).

    Attributes
    ----------
    factors : Mapping[str, tuple[float, float]]
        TruckVariant field -> factor range on the case's payload or the XML's value.
    offsets : Mapping[str, tuple[float, float]]
        TruckVariant field -> offset range (m) on the XML's value.
    stations : Mapping[str, tuple[float, float]]
        Quantity of :data:`rigsim.mjcf.stations.STATION_FACTORS` -> factor range, one draw per corner.
    values : Mapping[str, tuple[float, float]]
        TruckVariant field -> its range.
    sometimes : Mapping[str, tuple[float, Mapping[str, tuple[float, float]]]]
        Feature -> (probability, its fields' ranges).
    """

    factors: Mapping[str, tuple[float, float]]
    offsets: Mapping[str, tuple[float, float]]
    stations: Mapping[str, tuple[float, float]]
    values: Mapping[str, tuple[float, float]]
    sometimes: Mapping[str, tuple[float, Mapping[str, tuple[float, float]]]]


def _range(where: str, value) -> tuple[float, float]:
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value) or value[0] > value[1]):
        raise ValueError(f"{MISMATCH_FILE}: {where} must be [low, high] with low <= high, got {value!r}")
    return float(value[0]), float(value[1])


@functools.cache
def plant_ranges() -> PlantRanges:
    """The plants' ranges, read once per process from :data:`MISMATCH_FILE`.

    Raises
    ------
    ValueError
        A table or key the reader does not know, a field :class:`~rigsim.mjcf.variant.TruckVariant` does
        not have, or a range that is not ``[low, high]``.
    """
    doc = tomllib.loads(suite_file(MISMATCH_FILE).read_text(encoding="utf-8"))
    fields = set(TruckVariant.field_names())
    unknown = set(doc) - {"factors", "offsets", "stations", "values", "sometimes"}
    if unknown:
        raise ValueError(f"{MISMATCH_FILE}: unknown table(s) {sorted(unknown)}")

    def table(name: str, keys: set) -> Mapping[str, tuple[float, float]]:
        t = doc.get(name, {})
        if set(t) - keys:
            raise ValueError(f"{MISMATCH_FILE}: [{name}] names unknown field(s) {sorted(set(t) - keys)}")
        return types.MappingProxyType({k: _range(f"{name}.{k}", v) for k, v in t.items()})

    sometimes = {}
    for key, t in doc.get("sometimes", {}).items():
        p = t.get("probability")
        if isinstance(p, bool) or not isinstance(p, (int, float)) or not 0 <= p <= 1:
            raise ValueError(f"{MISMATCH_FILE}: sometimes.{key}.probability must be in [0, 1], got {p!r}")
        rest = {k: v for k, v in t.items() if k != "probability"}
        if set(rest) - fields:
            raise ValueError(f"{MISMATCH_FILE}: [sometimes.{key}] names unknown field(s) {sorted(set(rest) - fields)}")
        sometimes[key] = (float(p), types.MappingProxyType({k: _range(f"sometimes.{key}.{k}", v) for k, v in rest.items()}))
    return PlantRanges(factors=table("factors", fields), offsets=table("offsets", fields),
                       stations=table("stations", set(STATION_FACTORS)), values=table("values", fields),
                       sometimes=types.MappingProxyType(sometimes))


def draw_plant(case_payload_kg: float, rng: np.random.Generator,
               nominal: Mapping[str, float] | None = None) -> dict[str, float]:
    """One plant truck's :class:`~rigsim.mjcf.variant.TruckVariant` fields, drawn from :func:`plant_ranges`.

    Parameters
    ----------
    case_payload_kg : float, kg
        The case's payload (the plant's is a factor of it).
    rng : numpy.random.Generator
        Draws, in a fixed order (the file's), so one seed gives one plant.
    nominal : Mapping[str, float], optional
        The values the factors and offsets apply to (SI; :func:`rigsim.mjcf.build.nominal_values` of a
        described truck); default the XML's.
    """
    ranges, nominal = plant_ranges(), nominal_values() if nominal is None else nominal
    out: dict[str, float] = {}
    for field, (lo, hi) in ranges.factors.items():
        base = case_payload_kg if field == "payload_kg" else nominal[field]
        out[field] = float(base * rng.uniform(lo, hi))
    for field, (lo, hi) in ranges.offsets.items():
        out[field] = float(nominal[field] + rng.uniform(lo, hi))
    for quantity, (lo, hi) in ranges.stations.items():
        for corner in CORNERS:
            out[station_factor_field(quantity, corner)] = float(rng.uniform(lo, hi))
    for field, (lo, hi) in ranges.values.items():
        out[field] = float(rng.uniform(lo, hi))
    for _key, (p, fields) in ranges.sometimes.items():
        present = rng.uniform() < p
        draws = {f: float(rng.uniform(lo, hi)) for f, (lo, hi) in fields.items()}  # drawn either way: fixed order
        if present:
            out.update(draws)
    return out


def mismatch_plants(cases, seed: int = 0) -> list[dict[str, float]]:
    """Plant ``i`` of ``cases`` (scenario documents or files): :func:`draw_plant` of case ``i``'s
    payload from ``numpy.random.default_rng((seed, PLANT_STREAM, i))``; each a valid TruckVariant."""
    plants = []
    for i, case in enumerate(cases):
        values = draw_plant(case_payload_kg(case_scenario(case)), np.random.default_rng((int(seed), PLANT_STREAM, i)))
        TruckVariant(**values)  # refused here, before any run
        plants.append(values)
    return plants


def mismatch_scenario(case, plant: Mapping[str, float], duration_s: float) -> Scenario:
    """The case with plant truck ``plant`` (its TruckVariant fields), ``duration_s`` s long."""
    return dataclasses.replace(case_scenario(case), duration_s=float(duration_s), vehicle=TruckVariant(**plant))


def mismatch_job(case, plant: Mapping[str, float], duration_s: float, kind: str, lab=None, align: bool = False):
    """Worker job: one MuJoCo run of the case's plant: "road", "rig" or "identify"
    (:func:`rigsim.scenarios.studies.identify.compute.identify_rig`, its LVDTs measured through ``lab``,
    a :class:`rigsim.scenarios.core.lab.LabChain`, their timing undone where ``align``)."""
    sc = mismatch_scenario(case, plant, duration_s)
    return identify_rig(sc, lab=lab, align=align) if kind == "identify" else run(sc, kind)


def describe(plant: Mapping[str, float]) -> str:
    """A plant in a few words: payload offset, the spread of its stations, cab and tire."""
    nominal = nominal_values()
    parts = [f"y {100 * plant.get('payload_y_m', 0.0):+.0f} cm"]
    for quantity, short in (("tire_stiffness", "kt"), ("spring_rate", "ks")):
        f = [plant.get(station_factor_field(quantity, c), 1.0) for c in CORNERS]
        parts.append(f"{short} {100 * (min(f) - 1):+.0f}..{100 * (max(f) - 1):+.0f} %")
    if "damper_rebound_ratio" in plant:
        parts.append(f"rebound x{plant['damper_rebound_ratio']:.1f}")
    if "cab_mount_hz" in plant:
        parts.append(f"cab {plant['cab_mount_hz']:.1f} Hz")
    if "tire_progressive_ratio" in plant:
        parts.append(f"tire +{100 * plant['tire_progressive_ratio']:.0f} %")
    if "axle_mass_rear_kg" in plant:
        parts.append(f"rear axle {100 * (plant['axle_mass_rear_kg'] / nominal['axle_mass_rear_kg'] - 1):+.0f} %")
    return ", ".join(parts)
