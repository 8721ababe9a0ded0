"""The fleet suite's trucks: each a spec sheet a lab writes and a plant truck it does not know.

Truck ``i`` of a draw (``seed``) is drawn from ``scenarios/data/suites/fleet.toml``:

* its **spec sheet** (:attr:`FleetTruck.spec`): the geometry and suspension a lab writes into
  TRUCK.toml's ``[vehicle]`` (:data:`rigsim.mjcf.description.DESCRIPTION_FIELDS`): wheelbase, tracks, dual
  or single rear tires, leaf or air on each axle, their rates and dampers;
* its **plant** (:attr:`FleetTruck.plant`): the spec sheet, the load (empty or 1.5-9 t at its place
  and height), the leaves' friction, then the mismatch suite's differences drawn on the described
  truck's own values (:func:`rigsim.scenarios.studies.model_suite.mismatch.draw_plant`) and the structure
  no model of the family has: an engine on rubber mounts (:mod:`rigsim.mjcf.engine`), dampers
  digressive (:mod:`rigsim.mjcf.dampers`) or worn, on an air axle its bushings' friction, and a frame
  that twists and bends (:mod:`rigsim.mjcf.frame`) unlike the model's. The model of a described truck
  fits a frame's first torsion and bending modes, its two halves hinged at mid-wheelbase and damped at
  4 %; the plant's frame is cut where a real frame's flexibility concentrates, behind the cab or at
  the body's front mount (0.35-0.65 of the wheelbase behind the front axle,
  ``TruckVariant.frame_hinge_share``), and damped as its joints and fixings happen to be (2-6 %,
  ``frame_damping_ratio``): the place and the damping of the frame's compliance are not the model's,
  so its modes load the axles in other shares than any of the model's frames can;
* its **road** (ISO class B-D, 30-90 km/h) and the lab chain that measured it: the typical lab
  (:data:`rigsim.scenarios.core.lab.TYPICAL_LAB`) with each filter corner off by up to +-5 % and the
  force channel's delay by up to +-10 %; the alignment uses the nominal chain.

A truck that cannot stand (:func:`rigsim.mjcf.standing.check_stands`) is drawn again from the next of
its seeds, so one seed gives one fleet. The frame's cut and damping come from a stream of their own
(:data:`FRAME_STREAM`), so every other value of a seed's trucks is drawn as without them.
"""

from __future__ import annotations

import dataclasses
import functools
import tomllib
from collections.abc import Mapping

import numpy as np

from rigsim.mjcf.build import build_model, nominal_values
from rigsim.mjcf.description import CHOICES, suspension_of
from rigsim.mjcf.names import CORNERS
from rigsim.mjcf.standing import check_stands
from rigsim.mjcf.variant import TruckVariant
from rigsim.scenarios.core.lab import TYPICAL_LAB, LabChain
from rigsim.scenarios.core.run import run
from rigsim.scenarios.studies.identify.compute import identify_rig
from rigsim.scenarios.studies.model_suite.mismatch import draw_plant
from rigsim.scenarios.studies.suites import case_scenario, suite_file

__all__ = ["FLEET_FILE", "FleetTruck", "fleet_ranges", "draw_spec", "draw_truck", "fleet_trucks", "fleet_job",
           "lacks"]

#: The data file of the fleet's ranges, under ``scenarios/data/suites/``.
FLEET_FILE = "fleet.toml"
#: The seed stream of the fleet's draws: ``numpy.random.default_rng((seed, FLEET_STREAM, i, attempt))``.
FLEET_STREAM = 41
#: The seed stream of the plant frame's cut and damping (``fleet.toml``'s ``structure.frame``), beside a
#: truck's own: ``numpy.random.default_rng((seed, FLEET_STREAM, i, attempt, FRAME_STREAM))``.
FRAME_STREAM = 1
#: Draws of one truck before giving up on a seed whose trucks cannot stand.
ATTEMPTS = 20
#: kg m^2: the least roll inertia of the chassis of a truck whose cab and engine are both on mounts.
#: The catalogue's lumped chassis (2600 kg m^2, an estimate with both rigid on it) cannot give up a
#: 1 t cab (its 2.4 x 1.9 m box alone: 780 kg m^2 about its centre, more about the chassis') and an
#: engine and still leave each half of a cut frame a rigid body's inertia; 3200 (x1.23, inside the
#: mismatch suite's x0.8-1.25) can.
CAB_AND_ENGINE_ROLL_KG_M2 = 3200.0


@functools.lru_cache(maxsize=1)
def fleet_ranges() -> Mapping:
    """``fleet.toml`` as read (a dict; the caller must not change it)."""
    return tomllib.loads(suite_file(FLEET_FILE).read_text(encoding="utf-8"))


@dataclasses.dataclass(frozen=True)
class FleetTruck:
    """One truck of the fleet.

    Attributes
    ----------
    name : str
        ``fleet<i>-<class>-<speed>kmh-<payload>kg``.
    spec : Mapping[str, float or str]
        The spec sheet: :class:`~rigsim.mjcf.variant.TruckVariant` fields a lab writes into ``[vehicle]``.
    plant : Mapping[str, float or str]
        The truck on the rig: every TruckVariant field it sets.
    document : Mapping
        The scenario document of its road (name, speed, duration, seed, road).
    lab : LabChain
        The chain that measured its record (the alignment uses :data:`rigsim.scenarios.core.lab.TYPICAL_LAB`).
    """

    name: str
    spec: Mapping
    plant: Mapping
    document: Mapping
    lab: LabChain

    def scenario(self, duration_s: float, *, truck: str = "plant", rate_hz: float | None = None):
        """The truck's road as a Scenario, ``duration_s`` s long, carrying its plant (``truck="plant"``)
        or its spec sheet (``"spec"``: the file a lab gives ``rigsim correct --model``), its records at
        ``rate_hz`` (Hz; default the scenario's 1 kHz)."""
        sc = case_scenario(dict(self.document))
        vehicle = TruckVariant(**(self.plant if truck == "plant" else self.spec))
        rate = {} if rate_hz is None else {"output_rate_hz": float(rate_hz)}
        return dataclasses.replace(sc, duration_s=float(duration_s), vehicle=vehicle, **rate)


def _uniform(rng, pair) -> float:
    lo, hi = pair
    return float(rng.uniform(float(lo), float(hi)))


def draw_spec(rng: np.random.Generator) -> tuple[dict, dict]:
    """(the spec sheet's fields, the truck's hidden values: its load and the leaves' friction), drawn
    in the file's order from ``rng``."""
    spec = fleet_ranges()["spec"]
    out = {k: _uniform(rng, v) for k, v in spec["values"].items() if k != "payload_z_m"}
    hidden = {"payload_z_m": _uniform(rng, spec["values"]["payload_z_m"])}
    for field, p in spec["words"].items():
        out[field] = CHOICES[field][1] if rng.uniform() < float(p) else CHOICES[field][0]
    for field, by in spec["by_word"].items():
        for key, pair in by[out[field]].items():
            value = _uniform(rng, pair)
            (hidden if key.startswith("spring_friction") else out)[key] = value
    load = spec["payload"]
    empty = rng.uniform() < float(load["empty_probability"])
    mass, share = _uniform(rng, load["payload_kg"]), _uniform(rng, load["behind_front_share"])
    hidden["payload_kg"] = 0.0 if empty else mass
    hidden["payload_x_m"] = out["wheelbase_m"] * (0.5 - share)
    return out, hidden


def _structure(spec: Mapping, rng: np.random.Generator) -> dict:
    """The plant-only structure: frame, engine, dampers, air bushings (:data:`FLEET_FILE`'s ``structure``)."""
    table = fleet_ranges()["structure"]
    out = {k: _uniform(rng, v) for k, v in table["values"].items()}
    dampers = table["dampers"]
    digressive = rng.uniform() < float(dampers["digressive_probability"])
    knee, ratio = _uniform(rng, dampers["damper_digressive_knee_m_per_s"]), _uniform(rng, dampers["damper_digressive_ratio"])
    worn = [_uniform(rng, dampers["worn_factor"]) for _ in CORNERS]
    if digressive:
        out |= {"damper_digressive_knee_m_per_s": knee, "damper_digressive_ratio": ratio}
    else:
        out |= {f"spring_damping_factor_{c}": w for c, w in zip(CORNERS, worn)}
    bushing = [_uniform(rng, table["air"]["bushing_friction_N"]) for _ in ("front", "rear")]
    for axle, friction in zip(("front", "rear"), bushing):
        if suspension_of(TruckVariant(**{k: v for k, v in spec.items()}), axle == "front") == "air":
            out[f"spring_friction_{axle}_N"] = friction
    return out


def _frame(rng: np.random.Generator) -> dict:
    """Where the plant's frame is cut and how much it is damped (:data:`FLEET_FILE`'s ``structure.frame``)."""
    return {k: _uniform(rng, v) for k, v in fleet_ranges()["structure"]["frame"].items()}


def _road(i: int, rng: np.random.Generator, payload_kg: float, seed: int) -> dict:
    road = fleet_ranges()["road"]
    cls = str(road["classes"][int(rng.integers(len(road["classes"])))])
    speed = float(round(_uniform(rng, road["speed_kmh"])))
    tracks = str(road["tracks"][int(rng.integers(len(road["tracks"])))])
    doc = {"name": f"fleet{i:02d}-{cls}-{speed:.0f}kmh-{payload_kg:.0f}kg", "speed_kmh": speed, "duration_s": 30.0,
           "seed": int(rng.integers(10_000, 100_000)), "road": {"roughness": cls, "tracks": tracks}}
    if cls == "D":
        doc["road"]["cuton_wavelength_m"] = 25.0  # the generalization suite's: class D inside the stroke
    return doc


def _lab(rng: np.random.Generator) -> LabChain:
    tol = fleet_ranges()["lab"]
    corner, delay = float(tol["corner_tolerance"]), float(tol["delay_tolerance"])
    return dataclasses.replace(TYPICAL_LAB,
                               force_filter_hz=TYPICAL_LAB.force_filter_hz * (1 + rng.uniform(-corner, corner)),
                               lvdt_filter_hz=TYPICAL_LAB.lvdt_filter_hz * (1 + rng.uniform(-corner, corner)),
                               force_delay_s=TYPICAL_LAB.force_delay_s * (1 + rng.uniform(-delay, delay)))


def draw_truck(i: int, seed: int) -> FleetTruck:
    """Truck ``i`` of the draw ``seed`` (see the module's description); a truck that cannot stand is
    drawn again from the next attempt's seed.

    Raises
    ------
    ValueError
        No truck that stands in :data:`ATTEMPTS` draws (the file's ranges, in one sentence).
    """
    last = None
    for attempt in range(ATTEMPTS):
        rng = np.random.default_rng((int(seed), FLEET_STREAM, int(i), attempt))
        spec, hidden = draw_spec(rng)
        described = TruckVariant(**spec, **hidden)
        nominal = nominal_values(build_model(described)) | {k: v for k, v in hidden.items()}
        mismatch = draw_plant(hidden["payload_kg"], rng, nominal=nominal)
        plant = {**spec, **hidden, **mismatch, **_structure(spec, rng),
                 **_frame(np.random.default_rng((int(seed), FLEET_STREAM, int(i), attempt, FRAME_STREAM)))}
        if "cab_mount_hz" in plant:  # cab and engine both off the chassis: its roll inertia must hold both
            plant["chassis_roll_inertia_kg_m2"] = max(plant["chassis_roll_inertia_kg_m2"], CAB_AND_ENGINE_ROLL_KG_M2)
        doc = _road(i, rng, hidden["payload_kg"], seed)
        lab = _lab(rng)
        try:
            check_stands(described)
            check_stands(TruckVariant(**plant))
        except ValueError as exc:
            last = exc
            continue
        return FleetTruck(name=doc["name"], spec=spec, plant=plant, document=doc, lab=lab)
    raise ValueError(f"fleet truck {i} of seed {seed}: no truck that stands in {ATTEMPTS} draws ({last}); "
                     f"narrow the ranges of {FLEET_FILE}")


def fleet_trucks(n: int, seed: int) -> list[FleetTruck]:
    """The first ``n`` trucks of the draw ``seed``."""
    return [draw_truck(i, seed) for i in range(int(n))]


def fleet_job(truck: FleetTruck, duration_s: float, kind: str, rate_hz: float | None = None):
    """Worker job: one MuJoCo run of the truck's plant: "road", "rig" or "identify" (its LVDTs measured
    through the truck's lab chain and aligned with the nominal one, :data:`TYPICAL_LAB`), recorded at
    ``rate_hz`` (Hz; default 1 kHz)."""
    sc = truck.scenario(duration_s, rate_hz=rate_hz)
    return identify_rig(sc, lab=truck.lab, align=TYPICAL_LAB) if kind == "identify" else run(sc, kind)


def lacks(truck: FleetTruck) -> str:
    """What the plant has that its model lacks, in a few words: the frame's modes (the model fits its
    own, cut at mid-wheelbase and damped 4 %) with where the plant's is cut and its damping, and the rest
    (the dampers' rebound over bump among them: the model fits its own from twice, a spec sheet gives none)."""
    p = truck.plant
    parts = [f"frame {p['frame_torsion_hz']:.1f}/{p['frame_bending_hz']:.1f} Hz cut at "
             f"{p['frame_hinge_share']:.2f} of the wheelbase, damped {100 * p['frame_damping_ratio']:.1f} %",
             f"engine {p['engine_mass_kg']:.0f} kg on {p['engine_mount_hz']:.1f} Hz"]
    if "damper_digressive_ratio" in p:
        parts.append(f"dampers digressive x{p['damper_digressive_ratio']:.2f} above {p['damper_digressive_knee_m_per_s']:.2f} m/s")
    else:
        worn = [p[f"spring_damping_factor_{c}"] for c in CORNERS]
        parts.append(f"dampers worn to {min(worn):.2f}-{max(worn):.2f}")
    if "damper_rebound_ratio" in p:
        parts.append(f"rebound x{p['damper_rebound_ratio']:.2f}")
    if "cab_mount_hz" in p:
        parts.append(f"cab {p['cab_mount_hz']:.1f} Hz")
    if p.get("tire_progressive_spread_m"):
        parts.append(f"tire +{100 * p['tire_progressive_ratio']:.0f} % spread {100 * p['tire_progressive_spread_m']:.1f} cm")
    parts.append(f"payload y {100 * p.get('payload_y_m', 0.0):+.0f} cm")
    return ", ".join(parts)


def spec_text(truck: FleetTruck) -> str:
    """The spec sheet in a few words: wheelbase, tires, suspensions, load."""
    s = truck.spec
    return (f"{s['wheelbase_m']:.2f} m, {s['rear_tires']}, {s['suspension_front']}/{s['suspension_rear']}, "
            f"{truck.plant['payload_kg'] / 1e3:.1f} t")
