"""The calibration's first guess: the payload from the record's static loads, the rest from a catalogue.

First guess: payload and its x from the measured static loads (the record's mean wheel forces:
the weight split, since the dynamic forces average out) on the catalogue truck; everything else
at :func:`catalogue`, a catalogue guess: the XML's nominal values times fixed factors (0.85 or
1.15) and a 2.5 Hz cab mount (:data:`CATALOGUE_CAB_MOUNT_HZ`), documented as such so that the fit always has work to do and never starts from a plant's
true values.

The payload's guess is the only one taken from the record; every other field starts from
:func:`catalogue`, which never reads a plant.

The truck is the one the scenario's ``[vehicle]`` describes (:func:`description`: its wheelbase,
tracks, rear tires, suspensions, spring rates and dampers, from its spec sheet;
:mod:`rigsim.mjcf.description`), the catalogue truck of ``truck_rig.xml`` where it gives none: the
nominal values are read from that truck compiled, and the catalogue guess is centred on them.
"""

from __future__ import annotations

import functools

import numpy as np

from rigsim.hydraulics.params import GRAVITY_M_S2
from rigsim.mjcf import names as mjnames
from rigsim.mjcf.build import build_model, nominal_values
from rigsim.mjcf.physics import EquilibriumError
from rigsim.mjcf.description import AIR_DAMPING_NS_PER_M, AIR_RATE_N_PER_M, DESCRIPTION_FIELDS, described, suspension_of
from rigsim.mjcf.variant import BOUNDS, TruckVariant
from rigsim.mjcf.names import CORNERS, FRONT
from rigsim.mjcf.tires import TIRE_PROGRESSIVE_ONSET_M
from rigsim.scenarios.core.config import Scenario, ScenarioError
from rigsim.mjcf.engine import ENGINE_MASS_KG
from rigsim.scenarios.records.model.family import FRAME_FITTED
from rigsim.scenarios.records.model.model_runs import static_axle_loads

__all__ = ["SPEC_FIELDS", "SPRING_CATALOGUE_FACTORS", "AIR_FRICTION_GUESS_N", "description", "spring_fields", "CATALOGUE_FACTORS", "CATALOGUE_CAB_MOUNT_HZ", "CATALOGUE_TIRE_RATIO", "CATALOGUE_FRAME_HZ", "frame_guess", "CATALOGUE_ENGINE_HZ", "engine_guess", "CATALOGUE_DAMPER_KNEE_M_PER_S", "CATALOGUE_DAMPER_RATIO", "CATALOGUE_DAMPER_REBOUND_RATIO", "damper_guess", "EMPTY_FRACTION", "LIGHT_FRACTION", "PAYLOAD_X_LIMIT_M", "empty_truck_loads", "empty_truck_kg", "is_light", "xml_nominal", "catalogue", "static_guess",
           "LATERAL_FLOOR_M", "static_lateral"]

#: The catalogue guess: XML nominal times these factors (1). Fixed, not tuned to any plant: a
#: lab's catalogue values are 10-30 % off the truck on its rig.
CATALOGUE_FACTORS = {"tire_stiffness_front_N_per_m": 0.85, "tire_stiffness_rear_N_per_m": 1.15,
                     "tire_damping_front_Ns_per_m": 1.15, "tire_damping_rear_Ns_per_m": 0.85,
                     "spring_friction_front_N": 0.85, "spring_friction_rear_N": 1.15,
                     # the axles' masses taken as the truck's specification gives them (the XML's)
                     "axle_mass_front_kg": 1.0, "axle_mass_rear_kg": 1.0}
#: Hz: the catalogue guess of the cab's mount frequency (the XML has a rigid cab, so there is no
#: nominal value to take a factor of): a suspended cab bounces at 1.5-3 Hz (rigsim.mjcf.variant.BOUNDS);
#: its search range (:data:`~rigsim.scenarios.records.model.family.RANGES`) is 1-30 Hz.
CATALOGUE_CAB_MOUNT_HZ = 2.5
#: 1: the catalogue guess of the progressive tire's extra stiffness beyond its onset
#: (``TruckVariant.tire_progressive_ratio``; the XML's tire is linear, ratio 0): radial truck tires
#: stiffen by some 10-30 % over their working deflection (mjcf/README.md), so the middle, 0.2.
CATALOGUE_TIRE_RATIO = 0.2
#: Hz: the catalogue guess of a described truck's frame's first torsion and bending modes
#: (``TruckVariant.frame_torsion_hz``, ``frame_bending_hz``; the XML's chassis is rigid, so there is
#: no nominal value to take a factor of). **Estimate**: a ladder frame with its cab and body on it
#: has its first torsion and vertical bending modes at 5-12 Hz (mjcf/README.md, "Flexible frame";
#: :data:`rigsim.mjcf.frame.BOUNDS`), so the middle, 9 Hz, for both; searched 3-20 Hz
#: (:data:`~rigsim.scenarios.records.model.family.RANGES`).
CATALOGUE_FRAME_HZ = 9.0
#: The first guess of an engine's bounce on its mounts, Hz: the middle of a truck engine's 6-12 Hz
#: (:data:`rigsim.mjcf.engine.BOUNDS`); its mass the catalogue's :data:`rigsim.mjcf.engine.ENGINE_MASS_KG`.
CATALOGUE_ENGINE_HZ = 9.0
#: The first guess of a described truck's dampers: the knee, m/s, the middle of the 0.1-0.3 m/s where
#: vehicle dampers' blow-off valves open (:data:`rigsim.mjcf.dampers.BOUNDS`), and the slope beyond it
#: over the slope below, 1, nearly linear: held so in the fits before the dampers' own
#: (:mod:`~rigsim.scenarios.records.model.frame_choice`), which starts from them. A new damper's slope
#: beyond its knee is a fifth to a half of the one below; a damper worn to a third or a half of its
#: force is linear, and a truck's spec sheet does not say which its dampers are. The fit starts from
#: the linear end, where a worn truck's record leaves it, and the record moves it where the dampers
#: are digressive; not at 1 itself, where the knee would have no effect to start the search from.
CATALOGUE_DAMPER_KNEE_M_PER_S = 0.15
CATALOGUE_DAMPER_RATIO = 0.95
#: The first guess of a described truck's dampers' rebound over bump slope, 1: the low end of the 2-4
#: times harder in rebound a vehicle damper is valved to (:data:`rigsim.mjcf.variant.BOUNDS`), held
#: until fitted as the knee and slope are (a worn damper's valving is softer).
CATALOGUE_DAMPER_REBOUND_RATIO = 2.0


#: The fields of ``[vehicle]`` that describe the truck itself (its spec sheet), held in the model at
#: their given values: the geometry and suspension (:data:`rigsim.mjcf.description.DESCRIPTION_FIELDS`); the
#: spring rates and dampers are fitted from them (:func:`spring_fields`). The masses and
#: inertias are not among them: the model's are the catalogue's and the fit's (a plant's are its own,
#: and a scenario that carries a plant must not hand them to its model).
SPEC_FIELDS = DESCRIPTION_FIELDS
#: The catalogue guess of a described axle's spring rate and damper (1, on the description's): the
#: values a spec sheet gives are 10-30 % off the truck on the rig (an air spring's rate is quoted at
#: one load and pressure, a leaf spring's is made to 5-10 %, a damper wears to a third of its force),
#: as the catalogue's tire values are (:data:`CATALOGUE_FACTORS`).
SPRING_CATALOGUE_FACTORS = {"spring_rate_front_N_per_m": 1.15, "spring_rate_rear_N_per_m": 0.85,
                         "spring_damping_front_Ns_per_m": 0.85, "spring_damping_rear_Ns_per_m": 1.15}
#: N: the guess of an air axle's friction per spring (its bushings and its dampers' seals; an air
#: spring has no leaves to rub). **Estimate**: an air suspension's Coulomb friction is small beside
#: a multi-leaf spring's 1-5 kN (Cebon 1999, ch. 2), a hundred newtons or so; searched 0.05-8 times
#: the catalogue guess (:data:`~rigsim.scenarios.records.model.family.RANGES`), 6-900 N.
AIR_FRICTION_GUESS_N = 100.0


def description(base_scenario: Scenario | None) -> TruckVariant:
    """The truck the scenario's ``[vehicle]`` describes: its :data:`SPEC_FIELDS` alone (payload,
    tires and plant features are the calibration's); the catalogue truck for None or no such field."""
    vehicle = None if base_scenario is None else base_scenario.vehicle
    if vehicle is None:
        return TruckVariant()
    return TruckVariant(**{k: getattr(vehicle, k) for k in SPEC_FIELDS if getattr(vehicle, k) is not None})


def _spec(desc: TruckVariant) -> dict:
    """The description's given fields, as keyword arguments of a :class:`TruckVariant`."""
    return {k: getattr(desc, k) for k in SPEC_FIELDS if getattr(desc, k) is not None}


def spring_fields(desc: TruckVariant) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(the springs' fields fitted on the described truck, per axle its spring rate and damper; the
    fields dropped: an air axle's left spring's friction over its right one's).

    A spec sheet's rates and dampers are uncertain (:data:`SPRING_CATALOGUE_FACTORS`), so a described
    truck's are fitted on both kinds of axle. An air axle has no interleaf friction, but its
    bushings and its dampers' seals rub: its friction is fitted from :data:`AIR_FRICTION_GUESS_N`,
    one value for the axle (a few hundred newtons cannot be told apart left from right). The
    catalogue truck (no description) holds its leaves' rate and damper at the XML's."""
    fit, drop = [], []
    if not described(desc):
        return (), ()
    for axle, corner in (("front", FRONT[0]), ("rear", "rl")):
        fit += [f"spring_rate_{axle}_N_per_m", f"spring_damping_{axle}_Ns_per_m"]
        if suspension_of(desc, axle == "front") == "air":
            drop += [f"spring_friction_factor_{corner}"]
    return tuple(fit), tuple(drop)


def frame_guess(desc: TruckVariant) -> dict[str, float]:
    """The first guess of the frame's modes (:data:`CATALOGUE_FRAME_HZ`, Hz) on a described truck, whose
    calibration fits them; none on the catalogue truck, whose chassis stays the XML's rigid one."""
    return dict.fromkeys(FRAME_FITTED, CATALOGUE_FRAME_HZ) if described(desc) else {}


def engine_guess(desc: TruckVariant) -> dict[str, float]:
    """The first guess of the engine on its mounts (:data:`CATALOGUE_ENGINE_HZ`, Hz, and
    :data:`rigsim.mjcf.engine.ENGINE_MASS_KG`, kg) on a described truck, whose calibration may fit it;
    none on the catalogue truck, whose engine stays in the XML's rigid chassis."""
    return {"engine_mount_hz": CATALOGUE_ENGINE_HZ, "engine_mass_kg": ENGINE_MASS_KG} if described(desc) else {}


def damper_guess(desc: TruckVariant) -> dict[str, float]:
    """The first guess of digressive spring dampers (:data:`CATALOGUE_DAMPER_KNEE_M_PER_S`, m/s,
    :data:`CATALOGUE_DAMPER_RATIO` and :data:`CATALOGUE_DAMPER_REBOUND_RATIO`, 1) on a described truck,
    held until its calibration fits them; none on the catalogue truck, whose dampers stay the XML's
    linear, symmetric ones."""
    return ({"damper_digressive_knee_m_per_s": CATALOGUE_DAMPER_KNEE_M_PER_S,
             "damper_digressive_ratio": CATALOGUE_DAMPER_RATIO,
             "damper_rebound_ratio": CATALOGUE_DAMPER_REBOUND_RATIO} if described(desc) else {})


@functools.lru_cache(maxsize=8)
def _nominal(desc: TruckVariant = TruckVariant()) -> tuple[dict, tuple[float, float], np.ndarray]:
    """(the fitted fields' values, (front, rear) axle x in the chassis frame (m), each wheel's pan
    y (m, left positive, :data:`CORNERS` order)) of the compiled described truck (``desc``, default
    the XML's), compiled once per process and description."""
    import mujoco

    model = build_model(desc)
    f, r = CORNERS.index(FRONT[0]), CORNERS.index("rl")
    nominal = nominal_values(model)
    values = {k: nominal[k] for k in ("payload_kg", "payload_x_m", "payload_z_m", "chassis_pitch_inertia_kg_m2",
                                      "chassis_roll_inertia_kg_m2",
                                      "tire_stiffness_front_N_per_m",
                                      "tire_stiffness_rear_N_per_m", "tire_damping_front_Ns_per_m",
                                      "tire_damping_rear_Ns_per_m", "spring_friction_front_N",
                                      "spring_friction_rear_N", "axle_mass_front_kg", "axle_mass_rear_kg")}

    def body(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)

    for field in spring_fields(desc)[0]:  # each axle's given rate (an air spring's at the empty load) and damper
        side = "front" if "front" in field else "rear"
        corner = CORNERS[f] if side == "front" else CORNERS[r]
        tendon = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, mjnames.spring_tendon(corner))
        given, air = getattr(desc, field), suspension_of(desc, side == "front") == "air"
        if field.startswith("spring_rate"):
            default = AIR_RATE_N_PER_M[side] if air else float(model.tendon_stiffness[tendon])
        else:
            default = AIR_DAMPING_NS_PER_M[side] if air else float(model.tendon_damping[tendon])
        values[field] = float(default if given is None else given)
        friction = f"spring_friction_{side}_N"
        if air and getattr(desc, friction) is None:  # the air axle's friction: the guess, not the XML's 0
            values[friction] = AIR_FRICTION_GUESS_N
    axles = tuple(float(model.body_pos[body(mjnames.axle_body(c)), 0]) for c in (CORNERS[f], CORNERS[r]))
    pans_y = np.array([model.body_pos[body(mjnames.pan_body(c)), 1] for c in CORNERS])  # children of the world
    return values, axles, pans_y


def xml_nominal(desc: TruckVariant = TruckVariant()) -> dict[str, float]:
    """The fitted fields' values of the described truck (``desc``, :func:`description`; default
    ``truck_rig.xml``'s) (SI), read from it compiled."""
    return dict(_nominal(desc)[0])


def catalogue(desc: TruckVariant = TruckVariant()) -> dict:
    """The catalogue guess of the non-payload fields: :func:`xml_nominal` of the described truck
    (``desc``) times :data:`CATALOGUE_FACTORS` (and a described axle's :data:`SPRING_CATALOGUE_FACTORS`), with
    the description's own fields (:data:`SPEC_FIELDS`), so that ``TruckVariant(**catalogue(desc))``
    is the described truck."""
    nominal = xml_nominal(desc)
    air = {k: nominal[k] * SPRING_CATALOGUE_FACTORS[k] for k in spring_fields(desc)[0]}
    return {**_spec(desc), **{k: nominal[k] * v for k, v in CATALOGUE_FACTORS.items()}, **air,
            "cab_mount_hz": CATALOGUE_CAB_MOUNT_HZ,
            "tire_progressive_ratio": CATALOGUE_TIRE_RATIO, "tire_progressive_onset_m": TIRE_PROGRESSIVE_ONSET_M,
            "tire_progressive_ratio_rear": CATALOGUE_TIRE_RATIO, "tire_progressive_onset_rear_m": TIRE_PROGRESSIVE_ONSET_M}


#: An estimated payload within this fraction of the empty truck's weight (1) is an empty truck:
#: the mean wheel loads of an empty truck put its payload a few kg either side of zero (the
#: catalogue's axle and cab masses are not the plant's exactly), where its position is meaningless
#: (measured on the generalization suite's four empty trucks: -11 to -6 kg, x -4.3 to -10.8 m).
EMPTY_FRACTION = 0.01
#: An estimated payload down to this fraction of the empty truck's weight below zero (1) is an empty
#: truck lighter than the catalogue's: a real truck's body, tanks, axles and equipment put its empty
#: weight some per cent either side of the catalogue's (the mismatch suite's trucks: chassis +-10 %,
#: axles +-15 %). Further below, the loads are refused as no truck (a channel's scale or sign).
LIGHTER_FRACTION = 0.1
#: An estimated payload below this fraction of the empty truck's weight (1) is light: its height
#: barely moves the sprung mass's pitch inertia, and the chassis' own (its tanks, body and
#: equipment, not the catalogue's) sets the body's pitch mode; :func:`calibrate` fits the chassis'
#: pitch inertia in the payload height's place (:data:`~rigsim.scenarios.records.model.family.EMPTY_STAND_IN`).
#: An empty truck whose chassis and axles are off the catalogue reads as a light one (the mismatch
#: suite's empty gen21: 360 kg, 5 %; the height fitted, its front wheels stay at 0.54 and 0.48 of
#: the linear floor, the pitch inertia fitted 0.36 and 0.34). At 1400-1540 kg (gen10, gen22: 20-22 %)
#: the two fits give the same correction; the bound keeps the height where a payload is a load.
LIGHT_FRACTION = 0.1
#: m: the payload's centre along the truck is within this of the chassis frame's origin (the bed's
#: reach on the fleet's longest truck, 6.5 m wheelbase); the fit's bound on ``payload_x_m``.
PAYLOAD_X_LIMIT_M = 3.5


#: m: a payload centre the measured left/right moment puts closer to the centreline than this is on
#: the centreline. The record's mean loads carry the load cells' offsets and the catalogue truck's
#: own small asymmetries (millimetres of centre of mass); a payload stacked off-centre is off by
#: tens of centimetres.
LATERAL_FLOOR_M = 0.01


def static_lateral(force_N, base_scenario: Scenario, payload_kg: float, payload_x_m: float) -> float:
    """The payload's centre across the truck (m, left positive) from the measured static loads.

    The record's mean wheel forces are the static loads; their moment about the centreline,
    sum(F_i y_i), is the truck's weight times its centre of mass's lateral offset (moment balance
    about the x axis). The truck rolls towards an off-centre payload, which carries its sprung mass
    further out, so the moment is matched on the catalogue truck with this payload (mass and x)
    by the secant method on its static equilibrium, not by the lever rule. Within
    :data:`LATERAL_FLOOR_M` of the centreline: 0.

    Raises
    ------
    ScenarioError
        A moment no payload on the bed explains (more than 0.8 m off the centreline), or a payload on
        which the catalogue guess finds no rest, in one sentence.
    """
    if payload_kg <= 0.0:  # an empty truck (static_guess): no payload to place
        return 0.0
    desc = description(base_scenario)
    y_c = _nominal(desc)[2]
    measured = float(np.asarray(force_N, dtype=float).mean(axis=0) @ y_c)
    cat = catalogue(desc)

    def moment(y: float) -> float:
        try:
            return float(static_axle_loads(TruckVariant(payload_kg=payload_kg, payload_x_m=payload_x_m,
                                                        payload_y_m=y, **cat), base_scenario) @ y_c)
        except EquilibriumError:
            raise ScenarioError(f"the catalogue guess of the described truck with {payload_kg:.0f} kg at x = "
                                f"{payload_x_m:.2f} m, {y:+.2f} m off the centreline, finds no rest: the measured "
                                "static loads place no payload on it; check the description's springs") from None

    y0, m0 = 0.0, moment(0.0)
    y1 = 0.05
    m1 = moment(y1)
    for _ in range(2):  # the moment is nearly linear in y: two secant steps
        if m1 == m0:
            break
        y2 = y1 + (measured - m1) * (y1 - y0) / (m1 - m0)
        if abs(y2) > 0.8:
            raise ScenarioError(f"the measured left/right load split ({measured / 1e3:.1f} kN m about the "
                                f"centreline) puts the payload {abs(y2):.2f} m off the centreline, off the bed "
                                "(at most 0.8 m): check which force channels are left and right")
        y0, m0, y1 = y1, m1, y2
        m1 = moment(y1)
    return 0.0 if abs(y1) < LATERAL_FLOOR_M else float(y1)


def empty_truck_loads(base_scenario: Scenario) -> np.ndarray:
    """The catalogue guess of the described truck's static wheel loads without payload (N, (4,), corners
    fl fr rl rr)."""
    return static_axle_loads(TruckVariant(payload_kg=0.0, **catalogue(description(base_scenario))), base_scenario)


def empty_truck_kg(base_scenario: Scenario) -> float:
    """The catalogue truck's mass without payload, as its static wheel loads weigh it (float, kg)."""
    return float(empty_truck_loads(base_scenario).sum() / GRAVITY_M_S2)


def is_light(payload_kg: float, base_scenario: Scenario) -> bool:
    """Whether an estimated payload (float, kg) is light: below :data:`LIGHT_FRACTION` of the empty truck."""
    return payload_kg < LIGHT_FRACTION * empty_truck_kg(base_scenario)


def static_guess(force_N, base_scenario: Scenario) -> tuple[float, float]:
    """Payload (kg) and its x (m, chassis frame) from the measured static loads.

    The record's mean wheel force is the static load (the dynamic forces average out over the
    record); the catalogue truck without payload gives its own static loads; the difference is
    the payload's weight, and the front axle's share of it places it between the axles. A payload
    within :data:`EMPTY_FRACTION` of the empty truck's weight, or below zero by at most
    :data:`LIGHTER_FRACTION` of it (an empty truck lighter than the catalogue's), is an empty truck:
    (0, the XML's x), which :func:`calibrate` holds instead of fitting.

    A light payload (:func:`is_light`) whose share puts it off the truck is the empty truck's own
    weight and balance off the catalogue's (its chassis, tanks and engine), not a load: it is placed
    at the nearest end of the bed (:data:`PAYLOAD_X_LIMIT_M`), from where the fit moves it (the
    fleet suite's fresh draw: an empty 4.89 m truck on leaves read as 74 kg at x = -6.94 m).

    Raises
    ------
    ScenarioError
        Measured loads that imply no payload on the truck, or a load (not light) off the truck (one
        sentence).
    """
    f = np.asarray(force_N, dtype=float).mean(axis=0)
    empty = empty_truck_loads(base_scenario)
    front = np.array([c in FRONT for c in CORNERS])
    d_total = float(f.sum() - empty.sum())
    d_front = float(f[front].sum() - empty[front].sum())
    payload = d_total / GRAVITY_M_S2
    empty_kg = empty.sum() / GRAVITY_M_S2
    if -LIGHTER_FRACTION * empty_kg <= payload <= EMPTY_FRACTION * empty_kg:
        return 0.0, float(xml_nominal(description(base_scenario))["payload_x_m"])
    lo, hi = BOUNDS["payload_kg"][:2]
    if not (lo < payload <= hi) or d_total <= 0:
        raise ScenarioError(f"the measured mean wheel loads ({f.sum() / 1e3:.1f} kN in all) imply a payload of "
                            f"{payload:.0f} kg, outside {lo:g} to {hi:g} kg: check the force channels' scale and sign")
    x_f, x_r = _nominal(description(base_scenario))[1]  # the axles' positions in the chassis frame
    x = x_r + (x_f - x_r) * d_front / d_total
    if abs(x) > PAYLOAD_X_LIMIT_M and is_light(payload, base_scenario):
        return float(payload), float(np.sign(x) * PAYLOAD_X_LIMIT_M)
    if abs(x) > PAYLOAD_X_LIMIT_M:
        raise ScenarioError(f"the measured front/rear load split puts the payload at x = {x:.2f} m, off the truck "
                            f"({-PAYLOAD_X_LIMIT_M:g} to {PAYLOAD_X_LIMIT_M:g} m): check which force channels are front and rear")
    return float(payload), float(x)
