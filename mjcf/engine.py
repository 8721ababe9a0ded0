"""The engine on its mounts: the engine and gearbox as their own body on rubber mounts on the
chassis (``TruckVariant.engine_mount_hz``, ``TruckVariant.engine_mass_kg``).

The XML's chassis carries the engine rigidly in its lumped mass; a truck's engine and gearbox
(about a tonne) ride on rubber mounts whose bounce and pitch modes (6-12 Hz) sit between the body
and the axle modes. :func:`add_engine_mount` takes their mass out of the chassis, keeping the
truck's mass, centre of mass and inertia tensor, and hangs it on a vertical slide and a pitch
hinge with preloaded springs (mjcf/README.md, "Engine on mounts").
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from rigsim.mjcf import names
from rigsim.mjcf.features import box_inertia, check_field, parallel_axis, set_tensor, tensor_of

__all__ = ["ENGINE_MASS_KG", "ENGINE_MOUNT_DAMPING_RATIO", "ENGINE_OFFSET_X_M", "ENGINE_Z_M", "ENGINE_SIZE_M",
           "ENGINE_MOUNT_SPACING_M", "BOUNDS", "add_engine_mount"]

#: kg: the engine's and gearbox's mass when ``TruckVariant.engine_mass_kg`` is not given: an
#: estimate for the 7-9 l six-cylinder diesel (0.6-0.9 t dry) and gearbox (0.2-0.3 t) of a
#: medium/heavy two-axle truck; a 12-13 l heavy-truck engine with its gearbox is 1.2-1.5 t.
ENGINE_MASS_KG = 1000.0
#: Fraction of critical damping of the mounts on the engine's bounce mode (engine alone on its
#: mounts): an estimate. Natural-rubber mounts have a loss factor eta of 0.1-0.25, a damping ratio
#: eta / 2 at resonance of 0.05-0.12 (hydraulic mounts more, near their tuned frequency); 0.1.
ENGINE_MOUNT_DAMPING_RATIO = 0.1
#: m: the engine's centre of mass behind the front axle (chassis x): an estimate, the engine block
#: over and behind the steer axle with its gearbox behind it.
ENGINE_OFFSET_X_M = -0.6
#: m: height of the engine's centre of mass in the chassis frame: an estimate, the crankshaft near
#: the frame rails' top (the rails' centre at -0.06 m, their top at 0.08 m in truck_rig.xml).
ENGINE_Z_M = 0.1
#: m: edge lengths (x, y, z) of the uniform box standing in for engine and gearbox, which sets
#: their pitch inertia: an estimate, a 1.2 m engine and a 0.6 m gearbox in line, 0.8 m wide, 1.0 m high.
ENGINE_SIZE_M = (1.8, 0.8, 1.0)
#: m: fore-aft distance between the front mounts (at the timing case) and the rear ones (at the
#: flywheel housing), each pair taken at the same distance from the centre of mass: an estimate.
ENGINE_MOUNT_SPACING_M = 1.2

#: Bounds of the engine mount's fields: ``{field: (low, high, unit, why)}``, inclusive, SI (the
#: shape of :data:`rigsim.mjcf.variant.BOUNDS`).
BOUNDS: dict[str, tuple[float, float, str, str]] = {
    "engine_mass_kg": (300.0, 1500.0, "kg", "a truck's engine with its gearbox weighs 0.8-1.3 t (estimate: a 5 l "
                       "engine and gearbox 0.5 t, a 13 l one with a 16-speed gearbox 1.5 t)"),
    "engine_mount_hz": (5.0, 20.0, "Hz", "a truck engine's rubber mounts put its bounce at 6-12 Hz (estimate); "
                        "below 5 Hz they would not hold its torque, above 20 Hz it moves with the frame"),
}


def add_engine_mount(spec: mujoco.MjSpec, engine_kg: float, mount_hz: float) -> None:
    """Put the engine and gearbox on their own mounts on the chassis.

    Parameters
    ----------
    spec : mujoco.MjSpec
        A truck spec (:func:`rigsim.mjcf.build.build_spec`), edited in place; apply after every feature
        that sets the chassis' mass (the masses, the geometry), as the engine's mass is taken out of
        the chassis as it finds it.
    engine_kg : float, kg
        Mass of engine and gearbox (``vehicle.engine_mass_kg``, :data:`BOUNDS`).
    mount_hz : float, Hz
        Bounce frequency of the engine alone on its mounts, frame held (``vehicle.engine_mount_hz``).

    Notes
    -----
    The engine (body :data:`rigsim.mjcf.names.ENGINE_BODY`, a uniform box of :data:`ENGINE_SIZE_M`) sits at
    front axle x + :data:`ENGINE_OFFSET_X_M`, z = :data:`ENGINE_Z_M` (chassis frame). The chassis
    keeps the truck's mass, centre of mass and inertia tensor: it loses the engine's mass, its
    centre of mass moves so that chassis and engine together keep the old one, and its tensor about
    its new centre of mass is the old one minus the engine's (own box inertia plus parallel axis)
    minus the parallel-axis term of the shift. Mounts: bounce k = m (2 pi f)^2 with damping
    2 zeta m (2 pi f), zeta :data:`ENGINE_MOUNT_DAMPING_RATIO`; pitch k a^2 and c a^2 with the mount
    pairs at a = :data:`ENGINE_MOUNT_SPACING_M` / 2 from the centre of mass. The slide's spring is
    preloaded (springref g / (2 pi f)^2, k springref = m g) so that the engine rests at zero deflection.
    """
    engine_kg = check_field(BOUNDS, "engine_mass_kg", engine_kg)
    mount_hz = check_field(BOUNDS, "engine_mount_hz", mount_hz)
    if spec.body(names.ENGINE_BODY) is not None:
        raise ValueError("the truck's engine is already on its mounts: add_engine_mount applies once")
    chassis = spec.body("chassis")
    pos = np.array([float(spec.body(names.axle_body("fl")).pos[0]) + ENGINE_OFFSET_X_M, 0.0, ENGINE_Z_M])
    own = box_inertia(engine_kg, ENGINE_SIZE_M)
    total_kg, com, tensor = tensor_of(chassis)
    rest_kg = total_kg - engine_kg
    problem = (f"vehicle.engine_mass_kg = {engine_kg:g} kg leaves the chassis without its engine no rigid body's "
               "mass or inertia; give a lighter engine")
    if rest_kg <= 0:
        raise ValueError(problem)
    rest_com = (total_kg * com - engine_kg * pos) / rest_kg
    about_origin = tensor + parallel_axis(com, total_kg) - np.diag(own) - parallel_axis(pos, engine_kg)
    set_tensor(chassis, rest_kg, rest_com, about_origin - parallel_axis(rest_com, rest_kg), problem)

    engine = chassis.add_body(name=names.ENGINE_BODY, pos=list(pos))
    set_tensor(engine, engine_kg, np.zeros(3), np.diag(own), problem)
    engine.add_geom(name="engine", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.5 * s for s in ENGINE_SIZE_M],
                    contype=0, conaffinity=0, density=0.0, group=2, rgba=[0.25, 0.27, 0.3, 1.0])
    omega = 2.0 * math.pi * mount_hz
    k = engine_kg * omega**2  # N/m, all mounts together
    c = 2.0 * ENGINE_MOUNT_DAMPING_RATIO * engine_kg * omega  # N s/m
    arm2 = (0.5 * ENGINE_MOUNT_SPACING_M) ** 2  # m^2
    g = -float(spec.option.gravity[2])
    for name, kind, axis, stiffness, damping, ref in (
        (names.ENGINE_JOINTS[0], mujoco.mjtJoint.mjJNT_SLIDE, [0, 0, 1], k, c, g / omega**2),  # k ref = m g
        (names.ENGINE_JOINTS[1], mujoco.mjtJoint.mjJNT_HINGE, [0, 1, 0], k * arm2, c * arm2, 0.0),
    ):
        joint = engine.add_joint(name=name, type=kind, axis=axis, pos=[0.0, 0.0, 0.0], springref=ref)
        joint.stiffness = [stiffness] + [0.0] * (len(joint.stiffness) - 1)
        joint.damping = [damping] + [0.0] * (len(joint.damping) - 1)
