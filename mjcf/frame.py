"""The flexible frame: the chassis as two rigid halves that twist and bend between the axles
(``TruckVariant.frame_torsion_hz``, ``TruckVariant.frame_bending_hz``).

The XML's chassis is one rigid body; a truck's ladder frame twists about its length and bends in
its vertical plane, in first modes at 5-12 Hz with its cab and body on it, within the band the rig
excites. :func:`add_frame_flex` cuts the chassis between the axles (at mid-wheelbase unless
``TruckVariant.frame_hinge_share`` puts the cut elsewhere) into a front half (the body ``chassis``,
its joints on the rig kept) and a rear half (:data:`rigsim.mjcf.names.FRAME_REAR_BODY`) on a torsion
and a bending hinge (:data:`rigsim.mjcf.names.FRAME_JOINTS`) with rotational springs and light
damping (:data:`FRAME_DAMPING_RATIO` unless ``TruckVariant.frame_damping_ratio`` gives another),
keeping the truck's mass, centre of mass and inertia tensor (mjcf/README.md, "Flexible frame").
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from rigsim.mjcf import names
from rigsim.mjcf.features import check_field, set_tensor, tensor_of

__all__ = ["FRAME_DAMPING_RATIO", "FRAME_HINGE_SHARE", "BOUNDS", "RAIL_GEOM", "frame_split", "reduced_inertia", "add_frame_flex"]

#: Fraction of critical damping of each frame joint on its own mode: an estimate. A welded steel
#: beam alone keeps under 1 %; a truck's ladder frame loses more in the friction of its bolted and
#: riveted cross-member joints and the cab's and body's fixings, 2-5 % in its first modes; 0.04.
FRAME_DAMPING_RATIO = 0.04
#: Where the frame is cut: the share of the wheelbase behind the front axle (1; 0.5: mid-wheelbase).
#: A real frame's flexibility concentrates where its section or its load changes, behind the cab or
#: at the body's front mount (``TruckVariant.frame_hinge_share`` moves the cut there); mid-wheelbase
#: assumes nothing of the frame.
FRAME_HINGE_SHARE = 0.5
#: The geom whose centre height (chassis frame, m) puts the frame's hinges at the rails' centre
#: line, near a ladder frame's shear centre and neutral axis (truck_rig.xml: z = -0.06 m).
RAIL_GEOM = "rail_left"

#: Bounds of the flexible frame's fields: ``{field: (low, high, unit, why)}``, inclusive, SI (the
#: shape of :data:`rigsim.mjcf.variant.BOUNDS`).
BOUNDS: dict[str, tuple[float, float, str, str]] = {
    "frame_torsion_hz": (3.0, 20.0, "Hz", "a truck's ladder frame with its cab and body twists in its first mode "
                         "at 5-12 Hz (estimate); below 3 Hz it would twist with the body's roll (0.9 Hz on rigid "
                         "pans), above 20 Hz it is rigid for the road's input"),
    "frame_bending_hz": (3.0, 20.0, "Hz", "a loaded truck frame bends vertically in its first mode at 5-12 Hz "
                         "(estimate); below 3 Hz it would bend with the body's bounce and pitch (1.8 and 2.5 Hz on "
                         "rigid pans), above 20 Hz it is rigid for the road's input"),
    "frame_hinge_share": (0.25, 0.75, "1", "a ladder frame's flexibility concentrates where its section or load "
                          "changes, behind the cab or at the body's front mount, some 0.3-0.5 of the wheelbase "
                          "behind the front axle (estimate), or near mid-wheelbase on a uniform frame; a cut nearer "
                          "an axle leaves one half little more than that axle's hangers"),
    "frame_damping_ratio": (0.01, 0.1, "1", "a welded steel beam alone keeps under 1 %; a ladder frame with bolted "
                            "and riveted cross-members and its cab's and body's fixings 2-5 % in its first modes "
                            "(estimate); beyond 10 % is a frame with dampers of its own"),
}

_COPYING = "frame_flex_copy_"  # prefix of a subtree's copy while it moves (:func:`_move_body`)
_MOVED = "frame_flex_moved_"  # prefix of the original while it is deleted
_REFERRERS = ("tendons", "actuators", "sensors", "equalities", "excludes", "pairs", "keys", "tuples")
_SUBTREE = (mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_GEOM, mujoco.mjtObj.mjOBJ_SITE,
            mujoco.mjtObj.mjOBJ_CAMERA, mujoco.mjtObj.mjOBJ_LIGHT, mujoco.mjtObj.mjOBJ_FRAME)


def frame_split(mass: float, com: np.ndarray, tensor: np.ndarray, x_joint: float) -> list[tuple] | None:
    """The chassis' lumped mass cut in two at ``x_joint``.

    The chassis' second moment along x (S_xx = sum m x^2 about its centre of mass, from its inertia
    tensor I: S = tr(I) / 2 - I) is that of a uniform bar of length L = sqrt(12 S_xx / m) centred on
    its centre of mass: each half takes the bar's piece on its side, its mass, its x centre (the
    piece's middle) and own S_xx = m_i l_i^2 / 12. Across and above the frame, the mass follows x as
    the chassis' products say: with b = (S_xy, S_xz) / S_xx (the regression of y and z on x), a half's
    centre lies b dx_i off the chassis' centre in y and z (dx_i its x offset), its own products are
    b S_xx,i, and its own (y, z) block is b b^T S_xx,i plus its mass share of the block's remainder
    (the Schur complement C - b b^T S_xx, C the chassis' (y, z) block). Each half's S is then positive
    semi-definite (a rigid body's) wherever the chassis' is, and the halves' masses, first moments and
    second moments about the old centre of mass add up to the chassis' exactly.

    Parameters
    ----------
    mass : float, kg
    com : numpy.ndarray, m, (3,)
        Centre of mass in the chassis frame.
    tensor : numpy.ndarray, kg m^2, (3, 3)
        Inertia tensor about ``com``, chassis axes.
    x_joint : float, m
        Where the frame is cut (chassis x).

    Returns
    -------
    list of (float, numpy.ndarray, numpy.ndarray) or None
        (mass kg, centre of mass m, tensor kg m^2 about it) of the rear half, then the front half;
        None when the bar does not reach across ``x_joint``.
    """
    second = 0.5 * np.trace(tensor) * np.eye(3) - tensor
    length = math.sqrt(12.0 * second[0, 0] / mass)
    tail = float(com[0]) - 0.5 * length
    share = (x_joint - tail) / length
    if not 0.0 < share < 1.0:
        return None
    slope = second[0, 1:] / second[0, 0]  # b: y and z per unit x
    schur = second[1:, 1:] - np.outer(slope, slope) * second[0, 0]
    parts = []
    for frac, lo, hi in ((share, tail, x_joint), (1.0 - share, x_joint, tail + length)):
        m_i = frac * mass
        s_xx = m_i * (hi - lo) ** 2 / 12.0
        dx = 0.5 * (lo + hi) - float(com[0])
        own = np.zeros((3, 3))
        own[0, 0] = s_xx
        own[0, 1:] = own[1:, 0] = slope * s_xx
        own[1:, 1:] = np.outer(slope, slope) * s_xx + frac * schur
        centre = np.array(com, dtype=float) + dx * np.concatenate([[1.0], slope])
        parts.append((m_i, centre, np.trace(own) * np.eye(3) - own))
    return parts


def _move_body(spec: mujoco.MjSpec, body, parent) -> None:
    """Re-parent ``body`` and its subtree under ``parent`` (whose frame is the old parent's), every
    element keeping its name and its pose.

    MuJoCo 4.0's spec has no move: :meth:`mujoco.MjsFrame.attach_body` of a body of the same spec
    makes a deep copy (with ``copy_during_attach``) under a name prefix, together with copies of the
    tendons, actuators and sensors that name its elements. Those copies are deleted, the original
    subtree renamed (a referrer resolves its target by name when compiled, so the tendons follow
    the name), the copy given the original names, and the original deleted."""
    before = {kind: len(getattr(spec, kind)) for kind in _REFERRERS}
    spec.copy_during_attach = True
    try:
        copy = parent.add_frame().attach_body(body, _COPYING, "")
    finally:
        spec.copy_during_attach = False
    for kind in _REFERRERS:
        for element in list(getattr(spec, kind))[before[kind]:]:
            spec.delete(element)
    for root, prefix, strip in ((body, _MOVED, ""), (copy, "", _COPYING)):
        for element in [root] + [e for kind in _SUBTREE for e in root.find_all(kind)]:
            if element.name:
                element.name = prefix + element.name[len(strip):]
    spec.delete(body)


def _move_site(spec: mujoco.MjSpec, site, parent) -> None:
    """Re-create ``site`` on ``parent`` (whose frame is the old body's) under its name; the old one
    is renamed (the tendons through it follow the name) and deleted."""
    new = parent.add_site(pos=list(site.pos), quat=list(site.quat), size=list(site.size), type=site.type,
                          rgba=list(site.rgba), group=site.group, material=site.material, fromto=list(site.fromto))
    new.classname = site.classname
    for attr in ("type", "axisangle", "euler", "xyaxes", "zaxis"):
        setattr(new.alt, attr, getattr(site.alt, attr))
    name = site.name
    site.name = _MOVED + name
    new.name = name
    spec.delete(site)


def reduced_inertia(model: mujoco.MjModel) -> dict[str, float]:
    """Each frame joint's reduced inertia: the inertia its spring turns against.

    With a spring k on frame joint j and no other spring (suspension, tires, mounts removed), the
    one non-zero eigenvalue of M^-1 K is omega^2 = k (M^-1)_jj, M the joint-space mass matrix
    (``mujoco.mj_fullM``): the reduced inertia is 1 / (M^-1)_jj. It holds the two halves' rigid
    parts (the chassis' halves, a payload) about the joint's axis as the rig's joints let them move
    (for two bodies on one hinge, I_f I_r / (I_f + I_r)), and of the bodies on springs of their own
    (axles, a cab, an engine) only what their joints tie to the frame: an axle's sideways motion
    when the frame twists about an axis above it, not its roll or hop.

    Parameters
    ----------
    model : mujoco.MjModel
        The truck compiled with the frame cut (:data:`rigsim.mjcf.names.FRAME_JOINTS` present), taken at qpos0.

    Returns
    -------
    dict[str, float], kg m^2
        Reduced inertia per frame joint name.
    """
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    inverse = np.linalg.inv(mass)
    dofs = [int(model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n)]) for n in names.FRAME_JOINTS]
    return {name: 1.0 / inverse[d, d] for name, d in zip(names.FRAME_JOINTS, dofs)}


def add_frame_flex(spec: mujoco.MjSpec, torsion_hz: float, bending_hz: float, hinge_share: float | None = None,
                   damping_ratio: float | None = None) -> None:
    """Cut the chassis between the axles into two rigid halves on a torsion and a bending hinge.

    Parameters
    ----------
    spec : mujoco.MjSpec
        A truck spec (:func:`rigsim.mjcf.build.build_spec`), edited in place; apply after every feature
        that sets the chassis' mass or moves its children (the payload, the geometry, a cab or an
        engine mount), since the cut takes the chassis as it finds it.
    torsion_hz : float, Hz
        First torsion mode of the frame (``vehicle.frame_torsion_hz``, :data:`BOUNDS`).
    bending_hz : float, Hz
        First vertical bending mode of the frame (``vehicle.frame_bending_hz``).
    hinge_share : float, 1, optional
        Where the joints sit: this share of the way from the front axle's x to the rear axle's
        (``vehicle.frame_hinge_share``, :data:`BOUNDS`); None: :data:`FRAME_HINGE_SHARE`, halfway.
    damping_ratio : float, 1, optional
        Each joint's fraction of critical damping on its own mode (``vehicle.frame_damping_ratio``,
        :data:`BOUNDS`); None: :data:`FRAME_DAMPING_RATIO`.

    Notes
    -----
    The joints sit ``hinge_share`` of the way from the front axle's x to the rear one's, at the
    rails' centre height (:data:`RAIL_GEOM`).
    The chassis' mass splits by :func:`frame_split`; the rear half carries every child body of the
    chassis (the rear axle, a payload, ...) and every site (the rear hangers) behind the joints,
    each at the same place. Each spring k = (2 pi f)^2 I_red with I_red of :func:`reduced_inertia`
    (the frame's mode with the suspension removed); damping 2 zeta (2 pi f) I_red with zeta
    ``damping_ratio``. The chassis' geoms (rails, bed, cab) are drawing only and stay on
    the front half. The springs are not preloaded: the frame sags under its load as a real one does.
    """
    torsion_hz = check_field(BOUNDS, "frame_torsion_hz", torsion_hz)
    bending_hz = check_field(BOUNDS, "frame_bending_hz", bending_hz)
    share = FRAME_HINGE_SHARE if hinge_share is None else check_field(BOUNDS, "frame_hinge_share", hinge_share)
    zeta = FRAME_DAMPING_RATIO if damping_ratio is None else check_field(BOUNDS, "frame_damping_ratio", damping_ratio)
    if spec.body(names.FRAME_REAR_BODY) is not None:
        raise ValueError("the truck's frame is already flexible: add_frame_flex applies once")
    chassis = spec.body("chassis")
    # (1 - s) x_f + s x_r: at s = 0.5 the midpoint 0.5 (x_f + x_r) to the bit (halving is exact)
    x_joint = ((1.0 - share) * float(spec.body(names.axle_body("fl")).pos[0])
               + share * float(spec.body(names.axle_body("rl")).pos[0]))
    anchor = [x_joint, 0.0, float(spec.geom(RAIL_GEOM).pos[2])]
    parts = frame_split(*tensor_of(chassis), x_joint)
    if parts is None:
        raise ValueError("vehicle.chassis_pitch_inertia_kg_m2 is too small for the chassis' mass to reach from its "
                         f"centre of mass to x = {x_joint:g} m, where the frame is cut")
    rear = chassis.add_body(name=names.FRAME_REAR_BODY, pos=[0.0, 0.0, 0.0])
    problem = ("vehicle.chassis_roll_inertia_kg_m2 leaves a half of the cut frame no rigid body's inertia; "
               "give the chassis a larger roll inertia")
    for body, (mass, com, tensor) in zip((rear, chassis), parts):
        set_tensor(body, mass, com, tensor, problem)
    for child in [b for b in chassis.bodies if b.name != names.FRAME_REAR_BODY and float(b.pos[0]) < x_joint]:
        _move_body(spec, child, rear)
    for site in [s for s in chassis.sites if float(s.pos[0]) < x_joint]:
        _move_site(spec, site, rear)
    joints = [rear.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis, pos=anchor)
              for name, axis in zip(names.FRAME_JOINTS, ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]))]
    inertia = reduced_inertia(spec.copy().compile())
    for joint, hz in zip(joints, (torsion_hz, bending_hz)):
        omega, i_red = 2.0 * math.pi * hz, inertia[joint.name]
        joint.stiffness = [omega**2 * i_red] + [0.0] * (len(joint.stiffness) - 1)
        joint.damping = [2.0 * zeta * omega * i_red] + [0.0] * (len(joint.damping) - 1)
