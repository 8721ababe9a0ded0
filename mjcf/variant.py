"""What a scenario may change on the truck and the rig: :class:`TruckVariant`, its fields' bounds and checks.

The XML (``truck_rig.xml``) holds the nominal truck with every constant explained; a variant
names the values a scenario changes (``[vehicle]``), each validated here against its physical
range (:data:`BOUNDS`) before any model is built. :func:`rigsim.mjcf.build.build_spec` applies them.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from rigsim.mjcf import dampers, description, engine, frame
from rigsim.mjcf.names import CORNERS, FRONT
from rigsim.mjcf.stations import STATION_FACTORS, station_factor_field
from rigsim.mjcf.tires import check_progressive

__all__ = ["TruckVariant", "BOUNDS"]


def _positive(name: str, value: float | None, allow_zero: bool = False) -> None:
    if value is None:
        return
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        raise ValueError(f"vehicle.{name} must be a finite number, got {value!r}")
    if value < 0 or (value == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"vehicle.{name} must be {bound}, got {value!r}")


#: Physical bounds of the :class:`TruckVariant` fields: ``{field: (low, high, unit, why)}``,
#: inclusive, in SI (the reasons are in the field docstrings).
BOUNDS: dict[str, tuple[float, float, str, str]] = {
    "payload_kg": (0.0, 40_000.0, "kg", "heavier loads push the leaf springs through their 0.3 m travel"),
    "tire_stiffness_front_N_per_m": (1e5, 1e8, "N/m", "a truck tire is 0.8-1.2 MN/m; softer is a flat tire, "
                                     "stiffer a rigid wheel beyond the time step's stability limit"),
    "tire_stiffness_rear_N_per_m": (1e5, 1e8, "N/m", "a dual pair is 1.6-2.4 MN/m; softer is a flat tire, "
                                    "stiffer a rigid wheel beyond the time step's stability limit"),
    "tire_damping_front_Ns_per_m": (0.0, 5e4, "N s/m", "a tire's is ~1.5 kN s/m; more is beyond critical "
                                    "damping and the time step's stability limit"),
    "tire_damping_rear_Ns_per_m": (0.0, 5e4, "N s/m", "a tire's is ~1.5 kN s/m; more is beyond critical "
                                   "damping and the time step's stability limit"),
    "pan_mass_kg": (50.0, 5000.0, "kg", "a wheelpan with piston and rod weighs hundreds of kg (DYNTRAC: ~500 kg)"),
    "cab_mount_hz": (0.5, 30.0, "Hz", "a suspended truck cab bounces at 1.5-3 Hz; below 0.5 Hz no cab mount "
                     "holds the cab, above ~10 Hz it is a rubber-bushed (near-rigid) cab, and at 30 Hz, a decade "
                     "above the body modes, it moves with the frame (a stiffer one is the model without "
                     "cab_mount_hz)"),
    "cab_mass_kg": (200.0, 1200.0, "kg", "a truck cab weighs 0.8-1.5 t; the chassis' roll inertia (2600 kg m^2, "
                    "truck_rig.xml) leaves the frame without its cab no roll inertia beyond ~1.35 t and "
                    "an implausibly small one above 1.2 t"),
    "tire_progressive_ratio": (0.0, 3.0, "1", "a pneumatic tire stiffens by tens of % over its working deflection; "
                               "a tire whose stiffness more than quadruples is not one"),
    "tire_progressive_onset_m": (0.0, 0.1, "m", "a truck tire deflects 2-4 cm under its rated load; an onset beyond "
                                 "0.1 m (a fifth of the radius) is never reached by a tire that is not flat"),
    "tire_progressive_spread_m": (0.0, 0.05, "m", "a tire stiffens over a few cm of its working deflection; wider "
                                  "than 5 cm is beyond a truck tire's working range"),
    "tire_progressive_ratio_rear": (0.0, 3.0, "1", "as tire_progressive_ratio's"),
    "tire_progressive_onset_rear_m": (0.0, 0.1, "m", "as tire_progressive_onset_m's"),
    "payload_z_m": (0.2, 1.6, "m", "a load on the bed (top at 0.16 m) has its centre at least a few cm above it, "
                    "and a 4 m tall truck's load (2.8 m above the bed) at most 1.4 m above it"),
    "axle_mass_front_kg": (400.0, 1200.0, "kg", "a steer axle with hubs, brakes, wheels and tires weighs "
                           "600-800 kg (truck_rig.xml)"),
    "axle_mass_rear_kg": (700.0, 2000.0, "kg", "a drive axle with its differential, brakes and dual wheels "
                          "weighs 1.0-1.6 t (truck_rig.xml)"),
    "chassis_mass_kg": (3000.0, 9000.0, "kg", "the sprung mass of an empty two-axle truck (frame, cab, engine, "
                        "body; truck_rig.xml: 5.2 t) is 4-7 t"),
    "chassis_roll_inertia_kg_m2": (1300.0, 5200.0, "kg m^2", "half to twice truck_rig.xml's estimate"),
    "chassis_pitch_inertia_kg_m2": (6_000.0, 90_000.0, "kg m^2", "half to twice truck_rig.xml's estimate (25 200 kg "
                                    "m^2 at 5 m) at the 3.6-6.5 m wheelbases of two-axle trucks (its radius of "
                                    "gyration 0.44 of the wheelbase)"),
    "damper_rebound_ratio": (1.0, 5.0, "1", "dampers are valved up to 2-4 times harder in rebound than in bump; "
                             "1 is the XML's symmetric damper"),
    "timestep_s": (1e-6, 1e-3, "s", "coarser steps do not resolve the tire and hydraulic modes, finer ones "
                   "only cost time and memory; the defaults are 1e-4 s (road test) and 1e-3 s (rig test)"),
}


BOUNDS.update({station_factor_field(q, c): (lo, hi, "1", why)
               for q, (lo, hi, why) in STATION_FACTORS.items() for c in CORNERS})
BOUNDS.update(description.BOUNDS)
BOUNDS.update(frame.BOUNDS)
BOUNDS.update(engine.BOUNDS)
BOUNDS.update(dampers.BOUNDS)

#: The payload's position fields, signed (m): the largest |value| and where the field must lie.
_SIGNED = {"payload_x_m": (3.5, "lie on the truck (between -3.5 and 3.5 m)"),
           "payload_y_m": (0.8, "lie within 0.8 m of the centreline (the bed is 2.2 m wide)")}


@dataclass(frozen=True)
class TruckVariant:
    """Changes to the nominal truck and rig of ``truck_rig.xml``.

    Every field left at ``None`` keeps the value of the XML (its source is in the comment
    beside it there). All values are SI.

    Parameters
    ----------
    payload_kg : float, kg, optional
        Payload mass (the paper's cases: 3640 and 6360 kg). The payload's inertia follows
        from its box geometry. 0 to 40 000 kg: at 40 t (at the XML's position) the leaf springs,
        linear in the model, keep 0.16 m (front) and 0.11 m (rear) of their 0.3 m hanger-to-seat
        gap; beyond it they run towards passing through the frame (a two-axle truck's legal
        payload is below ~15 t).
    payload_x_m : float, m, optional
        Payload centre of mass along x in the chassis frame (mid-wheelbase = 0, forward
        positive; front axle at +2.5, rear at -2.5). The XML places it at -1.3 m (3.8 m
        behind the front axle).
    payload_y_m : float, m, optional
        Payload centre of mass across the truck (left positive), off the centreline where a load is
        stacked or shifted to one side. The XML places it on the centreline (0). At most 0.8 m either
        way: the centre stays inside the 2.2 m wide bed with 0.3 m to its edge, and at 6360 kg and
        0.8 m the lighter side's wheels still carry over a quarter of the truck's weight. A plant
        feature: the calibrated model family holds the payload on the centreline.
    tire_stiffness_front_N_per_m : float, N/m, optional
        Vertical stiffness of each front wheel station (one tire).
    tire_stiffness_rear_N_per_m : float, N/m, optional
        Vertical stiffness of each rear wheel station (a dual pair, both tires together).
        Both 1e5 to 1e8 N/m: a truck tire is 0.8-1.2 MN/m; below 1e5 N/m the static deflection
        under a ~25 kN wheel load passes 0.25 m of the 0.527 m radius (a flat tire; near 3e4 N/m
        the truck finds no rest at all); 1e8 N/m (~50 times a dual pair) is a rigid wheel, and
        with it the lightest pan on its tire, sqrt(1e8 / 50) = 1.4e3 rad/s, stays inside the
        explicit-integration limit 2 / dt = 2e3 rad/s of the coarsest step (1e-3 s).
    tire_damping_front_Ns_per_m, tire_damping_rear_Ns_per_m : float, N s/m, optional
        Vertical damping of each front / rear wheel station. 0 to 5e4 N s/m: a tire's is
        ~1.5 kN s/m (a few % of critical); 5e4 N s/m is above the critical damping of a wheel
        station (2 sqrt(k m) = 35 kN s/m for a steer tire under half the steer axle) and keeps
        c dt / m <= 1 for the lightest pan (50 kg) at the coarsest step (the tire's damping is
        integrated explicitly, stable below 2).
    tire_free_radius_m : float, m, optional
        Unloaded tire radius R0 (all wheel stations).
    spring_friction_front_N, spring_friction_rear_N : float, N, optional
        Interleaf Coulomb friction force of each front / rear leaf spring (0 disables it).
    pan_mass_kg : float, kg, optional
        Mass of each wheelpan with its actuator piston and rod. 50 to 5000 kg: a steel pan that
        carries a dual pair, with piston and rod, weighs hundreds of kg (DYNTRAC estimate 500 kg);
        the lower bound keeps the pan-on-tire mode of the stiffest tire inside the coarsest
        step's explicit limit (see the tire stiffness), the upper one is ten times the estimate,
        heavier than the wheel station the pan carries.
    cab_mount_hz : float, Hz, optional
        Natural frequency of the cab bouncing on its own suspension against a fixed frame,
        sqrt(k / m_cab) / (2 pi). ``None`` (default): the cab is part of the rigid chassis, the
        model of ``truck_rig.xml``. Set: the cab (geom ``cab``) becomes the body
        :data:`rigsim.mjcf.names.CAB_BODY` on the chassis with a vertical slide and a pitch hinge
        through its centre of mass (:data:`rigsim.mjcf.names.CAB_JOINTS`), on springs preloaded to hold
        it at rest at zero deflection, with :data:`rigsim.mjcf.cab.CAB_DAMPING_RATIO` of critical damping; two
        mount pairs :data:`rigsim.mjcf.cab.CAB_MOUNT_SPACING_M` apart give the pitch stiffness. Its mass and
        inertia are taken out of the chassis so that the truck's mass, centre of mass and roll
        and pitch inertia are unchanged. 0.5 to 30 Hz (see :data:`BOUNDS`). This is the plant
        feature a model of the rigid-cab family lacks.
    cab_mass_kg : float, kg, optional
        Mass of the suspended cab (default :data:`rigsim.mjcf.cab.CAB_MASS_KG`; only with ``cab_mount_hz``),
        a uniform box of the cab geom's size. 200 to 1200 kg (see :data:`BOUNDS`).
    tire_progressive_ratio : float, 1, optional
        A progressive tire (every wheel station): beyond :attr:`tire_progressive_onset_m` of
        deflection the stiffness rises from kt to kt (1 + ratio). ``None`` (default): the XML's
        linear tire. Set: a second affine element on each tire tendon
        (:func:`rigsim.mjcf.names.tire_progressive_actuator`), F2 = ratio kt (d - onset) for a deflection
        d = R0 - L beyond the onset and 0 before it (its force range is [0, 1e7] N: unilateral),
        without damping; the tire force sensors (:func:`rigsim.mjcf.names.tire_sensor`) then report the
        sum of the tendon's elements. 0 to 3 (see :data:`BOUNDS`). The calibrated model fits this
        bilinear tire (ratio and onset); :attr:`tire_progressive_spread_m` makes one it cannot.
    tire_progressive_onset_m : float, m, optional
        Deflection at which the progressive element engages (default
        :data:`rigsim.mjcf.tires.TIRE_PROGRESSIVE_ONSET_M`; only with ``tire_progressive_ratio``). 0 to 0.1 m.
    tire_progressive_spread_m : float, m, optional
        Deflection span, centred on the onset, over which the stiffness rises (only with
        ``tire_progressive_ratio``): a tire's stiffness rises smoothly over its working deflection;
        the model family's bilinear tire has one kink. ``None`` or 0: the one kink. s > 0: the ratio
        is split over :data:`rigsim.mjcf.tires.TIRE_PROGRESSIVE_STEPS` (5) equal elements of ratio kt / 5
        at onsets evenly from onset - s/2 to onset + s/2, a piecewise-linear approximation of a
        smooth stiffening. 0 to 0.05 m (see :data:`BOUNDS`), and onset - s/2 >= 0 m. A plant-only
        feature: the calibrated model (ratio and onset fitted) cannot represent it.
    tire_progressive_ratio_rear, tire_progressive_onset_rear_m : float, 1 and m, optional
        The rear tires' own ratio and onset (only with ``tire_progressive_ratio``, which then holds
        for the front tires; ranges as theirs); None: the all-wheel value. A steer tire and a
        rear dual differ in construction and load, and so in where and how much they stiffen.
    payload_z_m : float, m, optional
        Height of the payload's centre of mass in the chassis frame (the XML: 0.56 m, a 0.8 m stack
        on the bed at 0.16 m). 0.2 to 1.6 m. A high load raises the truck's roll and pitch inertia
        about the suspension and its overturning moment. A plant feature.
    axle_mass_front_kg, axle_mass_rear_kg : float, kg, optional
        Mass of each axle with its wheels (the unsprung mass; the XML: 700 and 1200 kg), its
        inertia scaled with it. 400 to 1200 kg front, 700 to 2000 kg rear. Plant features.
    chassis_mass_kg : float, kg, optional
        Mass of the chassis body (frame, cab, engine; the XML: 5200 kg), its inertia kept unless
        given. 3000 to 9000 kg. A plant feature.
    chassis_roll_inertia_kg_m2, chassis_pitch_inertia_kg_m2 : float, kg m^2, optional
        The chassis' roll and pitch moments of inertia about its centre of mass (the XML: 2600 and
        25 200 kg m^2, estimates), half to twice them; the yaw moment, held by the rig, keeps its
        ratio to their sum. Plant features.
    damper_rebound_ratio : float, 1, optional
        Each leaf-spring damper's rebound coefficient over its bump one, their mean kept at the
        spring's viscous damping (:func:`rigsim.mjcf.stations.rebound_coefficients`): a damper valved
        harder in rebound (the spring extending) than in bump, as vehicle dampers are. ``None`` or
        1: the XML's symmetric damper. 1 to 5. A plant feature the linear-damper model lacks: on a
        rough road it also shifts the mean spring force (the damper "jacks down").
    tire_stiffness_factor_fl, tire_stiffness_factor_fr, tire_stiffness_factor_rl, tire_stiffness_factor_rr : float, 1, optional
        One wheel station's tire stiffness over its axle's (``tire_stiffness_front_N_per_m`` or
        the rear one, or the XML's), 0.7 to 1.3: a tire at another pressure, worn, or of another
        make. The progressive tire's ratio applies to the station's own stiffness.
    tire_damping_factor_fl, tire_damping_factor_fr, tire_damping_factor_rl, tire_damping_factor_rr : float, 1, optional
        One station's tire damping over its axle's, 0.5 to 2.
    spring_rate_factor_fl, spring_rate_factor_fr, spring_rate_factor_rl, spring_rate_factor_rr : float, 1, optional
        One leaf spring's rate over the XML's, 0.7 to 1.3 (manufacturing tolerance, a broken leaf);
        its free length kept, so a softer spring sags.
    spring_damping_factor_fl, spring_damping_factor_fr, spring_damping_factor_rl, spring_damping_factor_rr : float, 1, optional
        One spring's viscous damping over the XML's, 0.3 to 2 (a worn or a new damper).
    spring_friction_factor_fl, spring_friction_factor_fr, spring_friction_factor_rl, spring_friction_factor_rr : float, 1, optional
        One spring's interleaf friction over its axle's (``spring_friction_front_N`` or the rear
        one, or the XML's), 0.25 to 4 (lubrication, wear, corrosion). The per-station factors are
        plant features (:mod:`rigsim.mjcf.stations`): the model family holds an axle's stations equal.
    wheelbase_m : float, m, optional
        Distance from the front axle to the rear axle (the XML: 5.0 m), 3 to 7 m. The axles, hangers,
        pans and the chassis' centre of mass move with it (:func:`rigsim.mjcf.description.apply_geometry`),
        and the road reaches the rear wheels a wheelbase after the front ones.
    track_front_m, track_rear_m : float, m, optional
        Distance between an axle's wheel centres (for duals the pairs' centres; the XML: 2.05 and
        1.83 m); the pans follow. 1.6 to 2.3 m front, 1.5 to 2.2 m rear.
    rear_tires : {"dual", "single"}, optional
        The rear wheel stations' tires: a dual pair (the XML) or one wide-base single, whose default
        stiffness and damping are :data:`rigsim.mjcf.description.SINGLE_TIRE_STIFFNESS_N_PER_M` and
        :data:`rigsim.mjcf.description.SINGLE_TIRE_DAMPING_NS_PER_M` unless the rear tire fields give them.
    suspension_front, suspension_rear : {"leaf", "air"}, optional
        Each axle's springs: multi-leaf (the XML) or air springs with levelling valves and dampers
        of their own (:mod:`rigsim.mjcf.description`: no interleaf friction, the ride height levelled at any
        payload, a rate proportional to the load carried).
    spring_rate_front_N_per_m, spring_rate_rear_N_per_m : float, N/m, optional
        Each spring's rate (the XML's leaves: 3e5 and 7e5 N/m); for an air axle its rate at the empty
        truck's load (default :data:`rigsim.mjcf.description.AIR_RATE_N_PER_M`). 2e4 to 3e6 N/m.
    spring_damping_front_Ns_per_m, spring_damping_rear_Ns_per_m : float, N s/m, optional
        Each spring's viscous damper (the XML's leaves: 6e3 and 1e4 N s/m; an air axle's default
        :data:`rigsim.mjcf.description.AIR_DAMPING_NS_PER_M`). 0 to 1e5 N s/m.
    frame_torsion_hz, frame_bending_hz : float, Hz, optional
        A frame that twists and bends (:func:`rigsim.mjcf.frame.add_frame_flex`): the chassis cut at
        mid-wheelbase into two halves on a torsion and a bending hinge whose springs put the frame's
        first torsion and bending modes at these frequencies. Both or neither; 3 to 20 Hz. The model
        family fits them on a described truck, its frame cut at mid-wheelbase with the default damping.
    frame_hinge_share : float, 1, optional
        Where the frame is cut (only with ``frame_torsion_hz``): this share of the wheelbase behind the
        front axle (default :data:`rigsim.mjcf.frame.FRAME_HINGE_SHARE`, 0.5: mid-wheelbase); a frame's
        flexibility concentrates behind the cab or at the body's front mount. 0.25 to 0.75. A plant
        feature: the model family's frame is cut at mid-wheelbase.
    frame_damping_ratio : float, 1, optional
        The frame joints' fraction of critical damping on their own modes (only with
        ``frame_torsion_hz``; default :data:`rigsim.mjcf.frame.FRAME_DAMPING_RATIO`, 0.04). 0.01 to 0.1.
        A plant feature: the model family holds the default.
    engine_mount_hz : float, Hz, optional
        The engine and gearbox on rubber mounts (:func:`rigsim.mjcf.engine.add_engine_mount`), bouncing at
        this frequency on a held frame; 5 to 20 Hz. A plant feature.
    engine_mass_kg : float, kg, optional
        Mass of the mounted engine and gearbox (default :data:`rigsim.mjcf.engine.ENGINE_MASS_KG`; only with
        ``engine_mount_hz``), taken out of the chassis; 300 to 1500 kg.
    damper_digressive_knee_m_per_s, damper_digressive_ratio : float, m/s and 1, optional
        Every spring damper digressive (:func:`rigsim.mjcf.dampers.add_digressive_damping`): its slope falls
        to ``ratio`` of the low-speed one beyond the knee speed. Both or neither; 0.05 to 0.5 m/s,
        0.2 to 1. A plant feature: the model family's dampers are linear.
    timestep_s : float, s, optional
        Integration time step of both tests, 1e-6 to 1e-3 s; by default the road test steps by
        explicit Euler at the XML's 1e-4 s and the rig test by RK4 at 1e-3 s (chosen by
        ``benchmarks/integrator_study.py``; set by ``rigsim.scenarios.core.rig``). Coarser steps do not
        resolve the tire and hydraulic modes; below 1e-6 s a 60 s run is 6e7 steps (hours,
        gigabytes of drive) for no gain.
    """

    payload_kg: float | None = None
    payload_x_m: float | None = None
    payload_y_m: float | None = None
    tire_stiffness_front_N_per_m: float | None = None
    tire_stiffness_rear_N_per_m: float | None = None
    tire_damping_front_Ns_per_m: float | None = None
    tire_damping_rear_Ns_per_m: float | None = None
    tire_free_radius_m: float | None = None
    spring_friction_front_N: float | None = None
    spring_friction_rear_N: float | None = None
    pan_mass_kg: float | None = None
    timestep_s: float | None = None
    cab_mount_hz: float | None = None
    cab_mass_kg: float | None = None
    tire_progressive_ratio: float | None = None
    tire_progressive_onset_m: float | None = None
    tire_progressive_spread_m: float | None = None
    tire_progressive_ratio_rear: float | None = None
    tire_progressive_onset_rear_m: float | None = None
    payload_z_m: float | None = None
    axle_mass_front_kg: float | None = None
    axle_mass_rear_kg: float | None = None
    chassis_mass_kg: float | None = None
    chassis_roll_inertia_kg_m2: float | None = None
    chassis_pitch_inertia_kg_m2: float | None = None
    damper_rebound_ratio: float | None = None
    tire_stiffness_factor_fl: float | None = None
    tire_stiffness_factor_fr: float | None = None
    tire_stiffness_factor_rl: float | None = None
    tire_stiffness_factor_rr: float | None = None
    tire_damping_factor_fl: float | None = None
    tire_damping_factor_fr: float | None = None
    tire_damping_factor_rl: float | None = None
    tire_damping_factor_rr: float | None = None
    spring_rate_factor_fl: float | None = None
    spring_rate_factor_fr: float | None = None
    spring_rate_factor_rl: float | None = None
    spring_rate_factor_rr: float | None = None
    spring_damping_factor_fl: float | None = None
    spring_damping_factor_fr: float | None = None
    spring_damping_factor_rl: float | None = None
    spring_damping_factor_rr: float | None = None
    spring_friction_factor_fl: float | None = None
    spring_friction_factor_fr: float | None = None
    spring_friction_factor_rl: float | None = None
    spring_friction_factor_rr: float | None = None
    wheelbase_m: float | None = None
    track_front_m: float | None = None
    track_rear_m: float | None = None
    rear_tires: str | None = None
    suspension_front: str | None = None
    suspension_rear: str | None = None
    spring_rate_front_N_per_m: float | None = None
    spring_rate_rear_N_per_m: float | None = None
    spring_damping_front_Ns_per_m: float | None = None
    spring_damping_rear_Ns_per_m: float | None = None
    frame_torsion_hz: float | None = None
    frame_bending_hz: float | None = None
    frame_hinge_share: float | None = None
    frame_damping_ratio: float | None = None
    engine_mount_hz: float | None = None
    engine_mass_kg: float | None = None
    damper_digressive_knee_m_per_s: float | None = None
    damper_digressive_ratio: float | None = None

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name in description.CHOICES:
                words = description.CHOICES[f.name]
                if value is not None and value not in words:
                    raise ValueError(f"vehicle.{f.name} must be " + " or ".join(repr(w) for w in words)
                                     + f", got {value!r}")
                continue
            if f.name in _SIGNED:
                limit, where = _SIGNED[f.name]
                if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))
                                          or not math.isfinite(value) or abs(value) > limit):
                    raise ValueError(f"vehicle.{f.name} must {where}, got {value!r}")
                continue
            zero_ok = f.name.startswith(("spring_friction", "tire_damping", "payload_kg", "tire_progressive",
                                         "spring_damping_front", "spring_damping_rear"))
            _positive(f.name, value, allow_zero=zero_ok)
            if value is not None and f.name in BOUNDS:
                lo, hi, unit, why = BOUNDS[f.name]
                if not lo <= value <= hi:
                    raise ValueError(f"vehicle.{f.name} = {value:g} {unit} is outside {lo:g} to {hi:g} {unit}: {why}")
        if self.cab_mass_kg is not None and self.cab_mount_hz is None:
            raise ValueError("vehicle.cab_mass_kg only applies to a suspended cab: set vehicle.cab_mount_hz too "
                             "(without it the cab is part of the chassis' mass)")
        for pair in (("frame_torsion_hz", "frame_bending_hz"),
                     ("damper_digressive_knee_m_per_s", "damper_digressive_ratio")):
            given = [getattr(self, k) is not None for k in pair]
            if any(given) and not all(given):
                missing = pair[given.index(False)]
                raise ValueError(f"vehicle.{pair[given.index(True)]} needs vehicle.{missing} too: give both")
        for k in ("frame_hinge_share", "frame_damping_ratio"):
            if getattr(self, k) is not None and self.frame_torsion_hz is None:
                raise ValueError(f"vehicle.{k} only applies to a flexible frame: set vehicle.frame_torsion_hz and "
                                 "vehicle.frame_bending_hz too")
        if self.engine_mass_kg is not None and self.engine_mount_hz is None:
            raise ValueError("vehicle.engine_mass_kg only applies to an engine on its mounts: set vehicle.engine_mount_hz "
                             "too (without it the engine is part of the chassis' mass)")
        check_progressive(self)
        self._check_stations()

    def _check_stations(self) -> None:
        """Refuse a station factor that takes its tire past the bounds of its axle's given value
        (the time step's stability limit, :data:`BOUNDS`)."""
        for quantity, axle in (("tire_stiffness", "tire_stiffness_{}_N_per_m"), ("tire_damping", "tire_damping_{}_Ns_per_m")):
            for corner in CORNERS:
                factor = getattr(self, station_factor_field(quantity, corner))
                field = axle.format("front" if corner in FRONT else "rear")
                value = getattr(self, field)
                if factor is None or value is None:
                    continue
                lo, hi, unit, why = BOUNDS[field]
                if not lo <= value * factor <= hi:
                    raise ValueError(f"vehicle.{field} x vehicle.{station_factor_field(quantity, corner)} = "
                                     f"{value * factor:g} {unit} is outside {lo:g} to {hi:g} {unit}: {why}; "
                                     "bring the factor nearer 1")

    @classmethod
    def word_fields(cls) -> dict[str, tuple[str, ...]]:
        """The fields whose value is a word, and the words each takes (the first: the XML's)."""
        return dict(description.CHOICES)

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Names of the parameters a scenario may override."""
        return tuple(f.name for f in dataclasses.fields(cls))
