"""Build model variants of the truck on the DYNTRAC rig from the shipped MJCF.

The XML (``truck_rig.xml``) holds the nominal truck with every constant explained; the
variants a scenario asks for (payload, tire stiffness, pan mass, leaf friction...) are
made here by editing an :class:`mujoco.MjSpec`, never by copying XML.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
from dataclasses import dataclass

import mujoco
import numpy as np

from mjcf import names
from mjcf.tires import add_progressive_tire, axle_progressive, check_progressive, set_tire, tire_elements

__all__ = [
    "MODEL_FILE",
    "SCENE_FILE",
    "TruckVariant",
    "BOUNDS",
    "CAB_MASS_KG",
    "CAB_DAMPING_RATIO",
    "CAB_MOUNT_SPACING_M",
    "resource_path",
    "load_spec",
    "build_spec",
    "build_model",
]

MODEL_FILE = "truck_rig.xml"
SCENE_FILE = "scene.xml"


def resource_path(name: str = SCENE_FILE):
    """Return the path of a shipped MJCF file.

    Parameters
    ----------
    name : str
        File name inside the ``mjcf`` package (``"scene.xml"`` or ``"truck_rig.xml"``).

    Returns
    -------
    pathlib.Path
        Absolute path of the file as installed.
    """
    ref = importlib.resources.files("mjcf").joinpath(name)
    if not ref.is_file():
        raise FileNotFoundError(f"MJCF resource {name!r} is not shipped with the mjcf package")
    # The package is installed as plain files (not zipped), so the traversable is a real path.
    import pathlib

    return pathlib.Path(str(ref))


def load_spec(name: str = SCENE_FILE) -> mujoco.MjSpec:
    """Load a shipped MJCF file as an editable :class:`mujoco.MjSpec`."""
    return mujoco.MjSpec.from_file(str(resource_path(name)))


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
    "timestep_s": (1e-6, 1e-3, "s", "coarser steps do not resolve the tire and hydraulic modes, finer ones "
                   "only cost time and memory; the defaults are 1e-4 s (road test) and 1e-3 s (rig test)"),
}


#: kg: the suspended cab's mass when ``TruckVariant.cab_mass_kg`` is not given: an estimate for
#: the steel day cab of a medium/heavy two-axle truck with its interior (0.8-1.5 t; mjcf/README.md).
CAB_MASS_KG = 1000.0
#: Fraction of critical damping of the cab mount's dampers on the cab bounce mode (cab alone on
#: its mounts): an estimate in the 20-40 % of suspended cabs with shock absorbers (mjcf/README.md).
CAB_DAMPING_RATIO = 0.3
#: m: fore-aft distance between the cab's front and rear mount pairs (each 0.2 m inside the
#: 1.8 m long cab), which sets the mounts' pitch stiffness and damping from the bounce ones.
CAB_MOUNT_SPACING_M = 1.4


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
        :data:`mjcf.names.CAB_BODY` on the chassis with a vertical slide and a pitch hinge
        through its centre of mass (:data:`mjcf.names.CAB_JOINTS`), on springs preloaded to hold
        it at rest at zero deflection, with :data:`CAB_DAMPING_RATIO` of critical damping; two
        mount pairs :data:`CAB_MOUNT_SPACING_M` apart give the pitch stiffness. Its mass and
        inertia are taken out of the chassis so that the truck's mass, centre of mass and roll
        and pitch inertia are unchanged. 0.5 to 30 Hz (see :data:`BOUNDS`). This is the plant
        feature a model of the rigid-cab family lacks.
    cab_mass_kg : float, kg, optional
        Mass of the suspended cab (default :data:`CAB_MASS_KG`; only with ``cab_mount_hz``),
        a uniform box of the cab geom's size. 200 to 1200 kg (see :data:`BOUNDS`).
    tire_progressive_ratio : float, 1, optional
        A progressive tire (every wheel station): beyond :attr:`tire_progressive_onset_m` of
        deflection the stiffness rises from kt to kt (1 + ratio). ``None`` (default): the XML's
        linear tire. Set: a second affine element on each tire tendon
        (:func:`mjcf.names.tire_progressive_actuator`), F2 = ratio kt (d - onset) for a deflection
        d = R0 - L beyond the onset and 0 before it (its force range is [0, 1e7] N: unilateral),
        without damping; the tire force sensors (:func:`mjcf.names.tire_sensor`) then report the
        sum of the tendon's elements. 0 to 3 (see :data:`BOUNDS`). The calibrated model fits this
        bilinear tire (ratio and onset); :attr:`tire_progressive_spread_m` makes one it cannot.
    tire_progressive_onset_m : float, m, optional
        Deflection at which the progressive element engages (default
        :data:`mjcf.tires.TIRE_PROGRESSIVE_ONSET_M`; only with ``tire_progressive_ratio``). 0 to 0.1 m.
    tire_progressive_spread_m : float, m, optional
        Deflection span, centred on the onset, over which the stiffness rises (only with
        ``tire_progressive_ratio``): a tire's stiffness rises smoothly over its working deflection;
        the model family's bilinear tire has one kink. ``None`` or 0: the one kink. s > 0: the ratio
        is split over :data:`mjcf.tires.TIRE_PROGRESSIVE_STEPS` (5) equal elements of ratio kt / 5
        at onsets evenly from onset - s/2 to onset + s/2, a piecewise-linear approximation of a
        smooth stiffening. 0 to 0.05 m (see :data:`BOUNDS`), and onset - s/2 >= 0 m. A plant-only
        feature: the calibrated model (ratio and onset fitted) cannot represent it.
    tire_progressive_ratio_rear, tire_progressive_onset_rear_m : float, 1 and m, optional
        The rear tires' own ratio and onset (only with ``tire_progressive_ratio``, which then holds
        for the front tires; ranges as theirs); None: the all-wheel value. A steer tire and a
        rear dual differ in construction and load, and so in where and how much they stiffen.
    timestep_s : float, s, optional
        Integration time step of both tests, 1e-6 to 1e-3 s; by default the road test steps by
        explicit Euler at the XML's 1e-4 s and the rig test by RK4 at 1e-3 s (chosen by
        ``benchmarks/integrator_study.py``; set by ``scenarios.core.rig``). Coarser steps do not
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

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name in _SIGNED:
                limit, where = _SIGNED[f.name]
                if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))
                                          or not math.isfinite(value) or abs(value) > limit):
                    raise ValueError(f"vehicle.{f.name} must {where}, got {value!r}")
                continue
            zero_ok = f.name.startswith(("spring_friction", "tire_damping", "payload_kg", "tire_progressive"))
            _positive(f.name, value, allow_zero=zero_ok)
            if value is not None and f.name in BOUNDS:
                lo, hi, unit, why = BOUNDS[f.name]
                if not lo <= value <= hi:
                    raise ValueError(f"vehicle.{f.name} = {value:g} {unit} is outside {lo:g} to {hi:g} {unit}: {why}")
        if self.cab_mass_kg is not None and self.cab_mount_hz is None:
            raise ValueError("vehicle.cab_mass_kg only applies to a suspended cab: set vehicle.cab_mount_hz too "
                             "(without it the cab is part of the chassis' mass)")
        check_progressive(self)

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Names of the parameters a scenario may override."""
        return tuple(f.name for f in dataclasses.fields(cls))


def _prescribe_pan(spec: mujoco.MjSpec, corner: str) -> None:
    """Make ``corner``'s pan (its joint already removed) a mocap body whose motion the caller sets.

    A mocap body has no velocity in MuJoCo, so the tire's damping would not see the pan's own
    velocity: the tire's gain becomes its damping (N s/m), so that ``ctrl`` carries the pan's
    vertical velocity (m/s, + up). The force stays the XML's affine law, clamped to the same
    range: kt (R0 - L) - ct (dL/dt) with dL/dt = (truck side) - v_pan, for the near-vertical
    tendon. Two sensors report the tendon's length (m) and its truck-side rate (m/s), from
    which the force at any other pan position follows (:func:`mjcf.physics.tire_law`).
    """
    spec.body(names.pan_body(corner)).mocap = True
    for act in tire_elements(spec, corner):  # each element's gain is its own damping (the progressive one: 0)
        gain = list(act.gainprm)
        gain[0] = -act.biasprm[2]
        act.gainprm = gain
    tendon = names.tire_tendon(corner)
    for name, kind in ((names.tire_length_sensor(corner), mujoco.mjtSensor.mjSENS_TENDONPOS),
                       (names.tire_rate_sensor(corner), mujoco.mjtSensor.mjSENS_TENDONVEL)):
        spec.add_sensor(name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_TENDON, objname=tendon)


def _parallel_axis(offset: np.ndarray, mass: float) -> np.ndarray:
    """Inertia (kg m^2, 3x3) of a point ``mass`` (kg) at ``offset`` (m) about the origin."""
    return mass * (float(offset @ offset) * np.eye(3) - np.outer(offset, offset))


def _add_cab_mount(spec: mujoco.MjSpec, hz: float, cab_kg: float) -> None:
    """Put the cab (geom ``cab`` of the chassis) on its own mounts; see ``TruckVariant.cab_mount_hz``.

    The chassis keeps the truck's mass and centre of mass: it loses the cab's mass, its CoM moves
    so that chassis and cab together keep the old one, and its inertia about its new CoM is the
    old inertia minus the cab's (own box inertia plus parallel axis) minus the parallel-axis term
    of the shift, in the roll, pitch and roll-pitch entries (the only ones in the mass matrix of
    the rig's heave, pitch and roll). The yaw entries, held by the rig, would turn unphysical (a
    tall cab taken out of the flat lumped tensor): the yaw moment is set to the pitch one and the
    yaw products to 0, which only touches the roll-rate x pitch-rate terms (the dropped product
    of inertia is ~2900 kg m^2 at 1000 kg: 29 N m at 0.1 rad/s each, against spring moments of
    1e4 N m).
    """
    chassis, geom = spec.body("chassis"), spec.geom("cab")
    total_kg, com = float(chassis.mass), np.array(chassis.ipos, dtype=float)
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, np.asarray(chassis.iquat, dtype=float))
    rot = rot.reshape(3, 3)
    inertia = rot @ np.diag(np.asarray(chassis.inertia, dtype=float)) @ rot.T  # about com, chassis axes
    pos, side = np.array(geom.pos, dtype=float), 2.0 * np.array(geom.size, dtype=float)
    cab_inertia = cab_kg / 12.0 * np.array([side[1] ** 2 + side[2] ** 2, side[0] ** 2 + side[2] ** 2,
                                            side[0] ** 2 + side[1] ** 2])
    rest_kg = total_kg - cab_kg
    rest_com = (total_kg * com - cab_kg * pos) / rest_kg
    about_origin = inertia + _parallel_axis(com, total_kg) - np.diag(cab_inertia) - _parallel_axis(pos, cab_kg)
    rest = about_origin - _parallel_axis(rest_com, rest_kg)
    rest[2, 2], rest[0, 2], rest[2, 0] = rest[1, 1], 0.0, 0.0
    moments, axes = np.linalg.eigh(rest)
    # A body's principal moments obey the triangle inequality (its sum m r r^T is positive definite).
    if np.linalg.eigvalsh(0.5 * moments.sum() * np.eye(3) - np.diag(moments))[0] <= 0:
        raise ValueError(f"vehicle.cab_mass_kg = {cab_kg:g} kg leaves the chassis without its cab a negative roll "
                         "inertia; give a lighter cab")
    axes = axes * np.sign(np.linalg.det(axes))  # a rotation, not a reflection
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, axes.reshape(9))
    chassis.mass, chassis.ipos, chassis.iquat, chassis.inertia = rest_kg, rest_com, quat, moments

    looks = dict(type=geom.type, size=list(geom.size), rgba=list(geom.rgba), group=geom.group)
    spec.delete(geom)
    cab = chassis.add_body(name=names.CAB_BODY, pos=pos, mass=cab_kg, ipos=[0.0, 0.0, 0.0], inertia=cab_inertia)
    cab.add_geom(name="cab", pos=[0.0, 0.0, 0.0], contype=0, conaffinity=0, density=0.0, **looks)
    omega = 2.0 * math.pi * float(hz)
    k = cab_kg * omega**2  # N/m, all four mounts together
    c = 2.0 * CAB_DAMPING_RATIO * cab_kg * omega  # N s/m
    arm2 = (0.5 * CAB_MOUNT_SPACING_M) ** 2  # m^2: each mount pair at half the spacing from the CoM
    g = -float(spec.option.gravity[2])
    for name, kind, axis, stiffness, damping, ref in (
        (names.CAB_JOINTS[0], mujoco.mjtJoint.mjJNT_SLIDE, [0, 0, 1], k, c, g / omega**2),  # preload: k ref = m g
        (names.CAB_JOINTS[1], mujoco.mjtJoint.mjJNT_HINGE, [0, 1, 0], k * arm2, c * arm2, 0.0),
    ):
        joint = cab.add_joint(name=name, type=kind, axis=axis, pos=[0.0, 0.0, 0.0], springref=ref)
        joint.stiffness = [stiffness] + [0.0] * (len(joint.stiffness) - 1)
        joint.damping = [damping] + [0.0] * (len(joint.damping) - 1)


def build_spec(variant: TruckVariant | None = None, *, pans: str = "slide", scene: bool = True) -> mujoco.MjSpec:
    """Return an editable spec of the truck on the rig with ``variant`` applied.

    Parameters
    ----------
    variant : TruckVariant, optional
        Changes to the nominal model; ``None`` gives the XML as shipped.
    pans : {"slide", "mocap", "fixed"}
        ``"slide"``: each pan moves on its vertical slide joint (the rig test: the actuators
        drive it). ``"mocap"``: the pans are mocap bodies whose motion the caller prescribes
        (the road test, :func:`_prescribe_pans`). ``"fixed"``: the pan joints are removed, the
        pans are welded to the ground (modal analysis of the truck alone on rigid supports).
    scene : bool
        Load ``scene.xml`` (floor, light, cameras) instead of the bare model file.

    Returns
    -------
    mujoco.MjSpec
    """
    if pans not in ("slide", "mocap", "fixed"):
        raise ValueError(f"pans must be 'slide', 'mocap' or 'fixed', got {pans!r}")
    v = variant or TruckVariant()
    spec = load_spec(SCENE_FILE if scene else MODEL_FILE)

    if v.payload_kg is not None:
        spec.geom("payload_box").mass = float(v.payload_kg)
    if v.payload_x_m is not None or v.payload_y_m is not None:
        body = spec.body("payload")
        x = body.pos[0] if v.payload_x_m is None else float(v.payload_x_m)
        y = body.pos[1] if v.payload_y_m is None else float(v.payload_y_m)
        body.pos = [x, y, body.pos[2]]
    for corner in names.CORNERS:
        front = corner in names.FRONT
        set_tire(
            spec,
            corner,
            v.tire_stiffness_front_N_per_m if front else v.tire_stiffness_rear_N_per_m,
            v.tire_damping_front_Ns_per_m if front else v.tire_damping_rear_Ns_per_m,
            v.tire_free_radius_m,
        )
        stiffening = axle_progressive(v, front)
        if stiffening is not None:
            add_progressive_tire(spec, corner, *stiffening, v.tire_progressive_spread_m)
        friction = v.spring_friction_front_N if front else v.spring_friction_rear_N
        if friction is not None:
            spec.tendon(names.spring_tendon(corner)).frictionloss = float(friction)
        if v.pan_mass_kg is not None:
            spec.body(names.pan_body(corner)).mass = float(v.pan_mass_kg)
        if pans in ("fixed", "mocap"):
            spec.delete(spec.joint(names.pan_joint(corner)))
        if pans == "mocap":
            _prescribe_pan(spec, corner)
    if v.timestep_s is not None:
        spec.option.timestep = float(v.timestep_s)
    if v.cab_mount_hz is not None:
        _add_cab_mount(spec, v.cab_mount_hz, CAB_MASS_KG if v.cab_mass_kg is None else float(v.cab_mass_kg))
    return spec


def build_model(variant: TruckVariant | None = None, *, pans: str = "slide") -> mujoco.MjModel:
    """Compile the truck on the rig with ``variant`` applied (see :func:`build_spec`)."""
    return build_spec(variant, pans=pans).compile()
