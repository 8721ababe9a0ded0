"""The suspended cab: the cab of the chassis put on its own mounts (``TruckVariant.cab_mount_hz``).

The XML's cab is part of the rigid chassis; a real truck's cab rides on its own springs and
dampers. :func:`add_cab_mount` edits a truck spec so that it does, keeping the truck's mass,
centre of mass and roll and pitch inertia (mjcf/README.md, "Suspended cab").
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from rigsim.mjcf import names

__all__ = ["CAB_MASS_KG", "CAB_DAMPING_RATIO", "CAB_MOUNT_SPACING_M", "add_cab_mount"]

#: kg: the suspended cab's mass when ``TruckVariant.cab_mass_kg`` is not given: an estimate for
#: the steel day cab of a medium/heavy two-axle truck with its interior (0.8-1.5 t; mjcf/README.md).
CAB_MASS_KG = 1000.0
#: Fraction of critical damping of the cab mount's dampers on the cab bounce mode (cab alone on
#: its mounts): an estimate in the 20-40 % of suspended cabs with shock absorbers (mjcf/README.md).
CAB_DAMPING_RATIO = 0.3
#: m: fore-aft distance between the cab's front and rear mount pairs (each 0.2 m inside the
#: 1.8 m long cab), which sets the mounts' pitch stiffness and damping from the bounce ones.
CAB_MOUNT_SPACING_M = 1.4



def _parallel_axis(offset: np.ndarray, mass: float) -> np.ndarray:
    """Inertia (kg m^2, 3x3) of a point ``mass`` (kg) at ``offset`` (m) about the origin."""
    return mass * (float(offset @ offset) * np.eye(3) - np.outer(offset, offset))


def add_cab_mount(spec: mujoco.MjSpec, hz: float, cab_kg: float) -> None:
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
