"""Tests of the flexible frame (:func:`rigsim.mjcf.frame.add_frame_flex`), a plant feature the calibrated
rigid-frame model family lacks.

References, independent of the code under test: the rigid truck compiled by MuJoCo (masses,
``subtree_com``, the joint-space mass matrix ``mj_fullM``, site positions and tendon lengths); the
two halves' rigid-body reduced inertia written out here by hand from MuJoCo's per-body masses,
centres of mass and inertias (parallel-axis sums about the rig's and the frame's axes, not
MuJoCo's Jacobians or mass matrix), omega^2 = k (M^-1)_jj for one spring on joint j; MuJoCo's
modal analysis of the truck with the suspension removed; statics (the total weight on the tires).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from rigsim.mjcf import names
from rigsim.mjcf.build import build_spec
from rigsim.mjcf.frame import BOUNDS, FRAME_DAMPING_RATIO, add_frame_flex
from rigsim.mjcf.physics import OPTIONAL_JOINTS, TRUCK_JOINTS, RigIndex, tire_forces
from rigsim.mjcf.modes import modal_analysis
from rigsim.mjcf.variant import TruckVariant

OBJ = mujoco.mjtObj
BODIES = names.TRUCK_BODIES + (names.FRAME_REAR_BODY,)


def _flex(payload_kg=3640.0, pans="fixed", torsion_hz=8.0, bending_hz=8.0, **variant):
    spec = build_spec(TruckVariant(payload_kg=payload_kg, **variant), pans=pans)
    rigid = spec.compile()
    add_frame_flex(spec, torsion_hz, bending_hz)
    return rigid, spec


def _forward(model):
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return data


def _id(model, kind, name):
    return mujoco.mj_name2id(model, kind, name)


def _remove_suspension(spec):
    """Springs, dampers and tires to zero, gravity off: the frame's spring is the only one left."""
    for corner in names.CORNERS:
        spring = spec.tendon(names.spring_tendon(corner))
        spring.stiffness, spring.damping, spring.frictionloss = [0.0] * 3, [0.0] * 3, 0.0
        spec.actuator(names.tire_actuator(corner)).biasprm = [0.0] * 10
    spec.option.gravity = [0.0, 0.0, 0.0]


def _hand_mass_matrix(model, data, axis: int):
    """Mass matrix (SI) of the rig's rotation about ``axis`` (0: x, roll; 1: y, pitch; with heave for
    pitch) and the frame joint about the same axis, by parallel-axis sums over the bodies.

    Rigid parts (welded to the chassis or the rear half) count whole; an axle counts only in what its
    joints (vertical slide, roll hinge through its centre of mass) tie to the frame: for roll its
    sideways velocity, for pitch its fore-aft velocity and its pitch rotation."""
    rig = model.jnt_dofadr[_id(model, OBJ.mjOBJ_JOINT, ("chassis_roll", "chassis_pitch")[axis])]
    joint = _id(model, OBJ.mjOBJ_JOINT, names.FRAME_JOINTS[axis])
    rear = _id(model, OBJ.mjOBJ_BODY, names.FRAME_REAR_BODY)
    halves = (_id(model, OBJ.mjOBJ_BODY, "chassis"), rear)
    e = np.eye(3)[axis]
    anchors = [data.xanchor[model.dof_jntid[rig]], data.xanchor[joint]]
    n = 2 if axis == 0 else 3
    mass = np.zeros((n, n))
    for b in range(1, model.nbody):
        rigid = model.body_weldid[b] in halves
        axle = model.body_weldid[b] in [_id(model, OBJ.mjOBJ_BODY, names.axle_body(c)) for c in ("fl", "rl")]
        if not (rigid or axle):
            continue
        on_rear = rear in (b, model.body_parentid[b], model.body_parentid[model.body_parentid[b]])
        c, m = data.xipos[b], model.body_mass[b]
        rot = data.ximat[b].reshape(3, 3)
        inertia = (rot @ np.diag(model.body_inertia[b]) @ rot.T)[axis, axis]
        twists = [(np.cross(e, c - anchors[0]), 1.0), (np.cross(e, c - anchors[1]) * on_rear, float(on_rear))]
        if axis == 1:
            twists.insert(0, (np.array([0.0, 0.0, 1.0]), 0.0))  # heave
        keep = np.ones(3) if rigid else (np.array([0.0, 1.0, 0.0]) if axis == 0 else np.array([1.0, 0.0, 0.0]))
        rotates = rigid or axis == 1  # an axle's roll is its own joint's, its pitch the frame's
        for i, (vi, wi) in enumerate(twists):
            for j, (vj, wj) in enumerate(twists):
                mass[i, j] += m * (vi * keep) @ (vj * keep) + (inertia * wi * wj if rotates else 0.0)
    return mass


@pytest.mark.parametrize("field,value", [("frame_torsion_hz", 2.9), ("frame_torsion_hz", 20.5),
                                         ("frame_bending_hz", float("nan")), ("frame_bending_hz", "8"),
                                         ("frame_torsion_hz", True)])
def test_bad_values_name_the_field(field, value):
    spec = build_spec(TruckVariant(), pans="fixed")
    args = {"torsion_hz": 8.0, "bending_hz": 8.0, field.replace("frame_", ""): value}
    with pytest.raises(ValueError, match=f"vehicle.{field}") as err:
        add_frame_flex(spec, **args)
    assert "\n" not in str(err.value)
    assert BOUNDS[field][:3] == (3.0, 20.0, "Hz")


def test_applies_once():
    _, spec = _flex()
    with pytest.raises(ValueError, match="already flexible"):
        add_frame_flex(spec, 8.0, 8.0)


@pytest.mark.parametrize("pans", ["slide", "mocap", "fixed"])
def test_names_places_and_tendons_are_kept(pans):
    """Every named element of the rigid truck exists under its name, every site where it was, every
    tendon as long, every moved body with its own mass and inertia; the rear axle, the rear hangers
    and the payload (x = -1.3 m) ride on the rear half, the front axle on the chassis."""
    rigid, spec = _flex(pans=pans, damper_rebound_ratio=2.0)
    flex = spec.compile()
    d_rigid, d_flex = _forward(rigid), _forward(flex)
    for kind, count in ((OBJ.mjOBJ_BODY, rigid.nbody), (OBJ.mjOBJ_JOINT, rigid.njnt), (OBJ.mjOBJ_GEOM, rigid.ngeom),
                        (OBJ.mjOBJ_SITE, rigid.nsite), (OBJ.mjOBJ_TENDON, rigid.ntendon),
                        (OBJ.mjOBJ_ACTUATOR, rigid.nu), (OBJ.mjOBJ_SENSOR, rigid.nsensor)):
        for i in range(count):
            assert _id(flex, kind, mujoco.mj_id2name(rigid, kind, i)) >= 0, mujoco.mj_id2name(rigid, kind, i)
    assert flex.nbody == rigid.nbody + 1 and flex.njnt == rigid.njnt + 2
    for i in range(rigid.nsite):
        j = _id(flex, OBJ.mjOBJ_SITE, mujoco.mj_id2name(rigid, OBJ.mjOBJ_SITE, i))
        assert np.allclose(d_flex.site_xpos[j], d_rigid.site_xpos[i], atol=1e-12)
    for i in range(rigid.ntendon):
        j = _id(flex, OBJ.mjOBJ_TENDON, mujoco.mj_id2name(rigid, OBJ.mjOBJ_TENDON, i))
        assert d_flex.ten_length[j] == pytest.approx(d_rigid.ten_length[i], abs=1e-12)
        for field in ("tendon_stiffness", "tendon_damping", "tendon_frictionloss"):
            assert getattr(flex, field)[j] == getattr(rigid, field)[i]
    for body in ("rear_axle", "front_axle", "payload"):
        i, j = _id(rigid, OBJ.mjOBJ_BODY, body), _id(flex, OBJ.mjOBJ_BODY, body)
        for field in ("body_mass", "body_inertia", "body_pos"):
            assert np.array_equal(getattr(flex, field)[j], getattr(rigid, field)[i]), (body, field)
    parent = {b: mujoco.mj_id2name(flex, OBJ.mjOBJ_BODY, flex.body_parentid[_id(flex, OBJ.mjOBJ_BODY, b)])
              for b in ("rear_axle", "payload", "front_axle")}
    assert parent == {"rear_axle": names.FRAME_REAR_BODY, "payload": names.FRAME_REAR_BODY, "front_axle": "chassis"}
    rear = _id(flex, OBJ.mjOBJ_BODY, names.FRAME_REAR_BODY)
    assert all(flex.site_bodyid[_id(flex, OBJ.mjOBJ_SITE, f"hanger_{c}")] == rear for c in names.REAR)
    assert "frame_flex_" not in spec.to_xml()


@pytest.mark.parametrize("payload_kg,payload_x_m", [(3640.0, None), (6360.0, None), (0.0, None), (3640.0, 0.5)])
def test_mass_centre_of_mass_and_inertia_are_kept(payload_kg, payload_x_m, same_rigid_truck):
    """Truck mass, centre of mass (MuJoCo's subtree_com) and the mass matrix of the rigid truck's
    joints with the frame straight are those of the rigid model; a payload ahead of the cut stays on
    the chassis."""
    rigid, spec = _flex(payload_kg=payload_kg, payload_x_m=payload_x_m)
    flex = spec.compile()
    same_rigid_truck(rigid, flex, BODIES)
    payload_parent = flex.body_parentid[_id(flex, OBJ.mjOBJ_BODY, "payload")]
    expected = "chassis" if payload_x_m else names.FRAME_REAR_BODY
    assert mujoco.mj_id2name(flex, OBJ.mjOBJ_BODY, payload_parent) == expected


def test_a_chassis_without_its_cab_and_engine_is_cut_into_rigid_halves(same_rigid_truck):
    """A suspended cab and an engine on mounts taken out first leave the chassis' lumped tensor a large
    x-z product (the tall cab came off its front); the halves follow it (frame_split's regression of z
    on x) and stay rigid bodies, and the truck's mass, centre of mass and mass matrix are the uncut
    truck's: a 4.0 m truck on rear air springs with a 1.25 t engine, at the least roll inertia the fleet
    suite gives a truck with both (rigsim.scenarios.studies.model_suite.fleet.CAB_AND_ENGINE_ROLL_KG_M2)."""
    variant = dict(wheelbase_m=4.0, suspension_rear="air", cab_mount_hz=2.0, engine_mount_hz=8.0,
                   engine_mass_kg=1250.0, chassis_roll_inertia_kg_m2=3200.0)
    rigid, spec = _flex(payload_kg=6000.0, **variant)
    flex = spec.compile()
    same_rigid_truck(rigid, flex, BODIES + (names.CAB_BODY, names.ENGINE_BODY))
    for body in ("chassis", names.FRAME_REAR_BODY):
        i = flex.body_inertia[_id(flex, OBJ.mjOBJ_BODY, body)]
        assert np.all(i > 0) and 2 * i.max() <= i.sum() + 1e-9  # a rigid body's principal moments


def test_joints_are_halfway_between_the_axles_at_the_rails():
    """With the front axle moved to x = 3.0 m (wheelbase 5.5 m) the cut moves to x = 0.25 m."""
    spec = build_spec(TruckVariant(), pans="fixed")
    spec.body("front_axle").pos = [3.0, 0.0, -0.5]
    add_frame_flex(spec, 8.0, 8.0)
    model = spec.compile()
    for name in names.FRAME_JOINTS:
        j = _id(model, OBJ.mjOBJ_JOINT, name)
        assert np.allclose(model.jnt_pos[j], [0.25, 0.0, -0.06])  # rail centre height, truck_rig.xml
    assert RigIndex.of(model).truck_qpos.size == len(TRUCK_JOINTS) + len(names.FRAME_JOINTS)


@pytest.mark.parametrize("torsion_hz,bending_hz", [(5.0, 7.0), (8.0, 8.0), (12.0, 10.0)])
def test_springs_give_the_requested_modes_without_the_suspension(torsion_hz, bending_hz):
    """Two-body reference: with the springs, dampers and tires removed, each frame joint's spring
    alone gives omega^2 = k (M^-1)_jj, M written out here by parallel-axis sums; MuJoCo's modal
    analysis of that truck finds both modes there (0.5 %: the finite-difference linearization and
    the discrete-to-continuous map at dt 1e-4 s), damped at FRAME_DAMPING_RATIO."""
    _, spec = _flex(torsion_hz=torsion_hz, bending_hz=bending_hz)
    _remove_suspension(spec)
    model = spec.compile()
    data = _forward(model)
    modes = {m.name: m for m in modal_analysis(model, data)}
    for axis, (name, hz) in enumerate(zip(names.FRAME_JOINTS, (torsion_hz, bending_hz))):
        k = model.jnt_stiffness[_id(model, OBJ.mjOBJ_JOINT, name)]
        f_hand = math.sqrt(k * np.linalg.inv(_hand_mass_matrix(model, data, axis))[-1, -1]) / (2 * math.pi)
        assert f_hand == pytest.approx(hz, rel=1e-6), name
        mode = modes[name.replace("_", " ")]
        assert mode.frequency_hz == pytest.approx(hz, rel=5e-3), name
        assert mode.damping_ratio == pytest.approx(FRAME_DAMPING_RATIO, rel=0.02), name


@pytest.mark.parametrize("hz", [5.0, 8.0, 12.0])
def test_modes_of_the_truck_on_rigid_pans(hz, at_rest):
    """On rigid pans each frame mode is one mode named after its joint, near the requested frequency.
    Above it: the suspension and tires also hold each half to the ground, with the stiffness that
    gives the rigid truck its body modes (at most f_g = its body pitch, 2.5 Hz), which adds up to
    about f_g^2 to f^2; below it: the axle hop and roll modes (9.3-10.9 Hz) repel a frame mode just
    under them (measured -1.8 % at 10 Hz), 3 % allowed."""
    rigid = modal_analysis(*at_rest(build_spec(TruckVariant(payload_kg=3640.0), pans="fixed").compile()))
    f_g = max(m.frequency_hz for m in rigid if m.name.startswith("body"))
    _, spec = _flex(torsion_hz=hz, bending_hz=hz)
    modes = modal_analysis(*at_rest(spec.compile()))
    print(f"\nframe {hz} Hz on rigid pans: " + ", ".join(f"{m.name} {m.frequency_hz:.2f}" for m in modes))
    for name in ("frame torsion", "frame bending"):
        found = [m for m in modes if m.name.startswith(name)]
        assert len(found) == 1, name
        assert 0.97 * hz <= found[0].frequency_hz <= 1.01 * math.sqrt(hz**2 + f_g**2), name


@pytest.mark.parametrize("pans", ["slide", "mocap"])
def test_rests_on_pans_at_mid_stroke(pans, at_rest):
    """static_equilibrium solves the frame joints too: every truck joint at rest, all four tires
    loaded, the loads those of the rigid truck (statics: a two-axle truck's axle loads follow from
    its weight and centre of mass alone; 0.1 % for the millimetres the frame sags), their sum the
    weight (1e-4: the sag swings the rear axle ~2 mm aft about the bending hinge 0.44 m above it,
    tilting the rear tire tendons by ~4 mrad); nothing moves in 0.5 s from rest."""
    rigid, spec = _flex(pans=pans)
    model, data = at_rest(spec.compile(), np.zeros(4))
    idx = RigIndex.of(model)
    assert idx.truck_qpos.size == len(TRUCK_JOINTS) + len(OPTIONAL_JOINTS[1])
    assert np.max(np.abs(data.qacc[idx.truck_dof])) < 1e-8
    loads = tire_forces(model, data)
    assert np.all(loads > 0)
    assert loads == pytest.approx(tire_forces(*at_rest(rigid, np.zeros(4))), rel=1e-3)
    weight = sum(model.body_mass[_id(model, OBJ.mjOBJ_BODY, b)] for b in BODIES) * 9.81
    assert loads.sum() == pytest.approx(weight, rel=1e-4)
    if pans == "slide":
        return
    mujoco.mj_step(model, data, int(round(0.5 / model.opt.timestep)))
    assert all(w.number == 0 for w in data.warning)
    assert np.max(np.abs(data.qvel)) < 1e-6


def _frame_joint(model, name):
    j = _id(model, OBJ.mjOBJ_JOINT, name)
    return model.jnt_pos[j], model.jnt_stiffness[j], model.dof_damping[model.jnt_dofadr[j]]


def test_the_defaults_are_the_frame_cut_at_mid_wheelbase_damped_at_the_ratio():
    """A frame without a cut or a damping given, and one given mid-wheelbase (0.5) and FRAME_DAMPING_RATIO, are
    the same model to the bit (masses, inertias, joints, springs, dampers, mass matrix) and have the same
    modes on rigid pans; the joints sit at the mean of the axle bodies' x, and each damper over its spring is
    2 zeta / omega (a damped oscillator's c / k) at zeta = 0.04."""
    base = dict(payload_kg=3640.0, wheelbase_m=5.6, frame_torsion_hz=7.0, frame_bending_hz=10.0)
    default = build_spec(TruckVariant(**base), pans="fixed").compile()
    given = build_spec(TruckVariant(**base, frame_hinge_share=0.5, frame_damping_ratio=FRAME_DAMPING_RATIO),
                       pans="fixed").compile()
    for field in ("body_mass", "body_pos", "body_ipos", "body_inertia", "body_parentid", "jnt_pos", "jnt_stiffness",
                  "dof_damping", "site_pos", "site_bodyid", "tendon_stiffness", "tendon_damping"):
        assert np.array_equal(getattr(default, field), getattr(given, field)), field
    mass = []
    for model in (default, given):
        data = _forward(model)
        m = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, m)
        mass.append(m)
    assert np.array_equal(*mass)
    rigid = build_spec(TruckVariant(payload_kg=3640.0, wheelbase_m=5.6), pans="fixed").compile()
    x_axles = [rigid.body_pos[_id(rigid, OBJ.mjOBJ_BODY, names.axle_body(c))][0] for c in ("fl", "rl")]
    for name, hz in zip(names.FRAME_JOINTS, (7.0, 10.0)):
        pos, k, c = _frame_joint(default, name)
        assert pos[0] == 0.5 * (x_axles[0] + x_axles[1])
        assert c / k == pytest.approx(2 * FRAME_DAMPING_RATIO / (2 * math.pi * hz), rel=1e-12)


def test_the_defaults_leave_the_modes_on_rigid_pans_as_they_were(at_rest):
    base = dict(payload_kg=3640.0, frame_torsion_hz=8.0, frame_bending_hz=8.0)
    default = modal_analysis(*at_rest(build_spec(TruckVariant(**base), pans="fixed").compile()))
    given = modal_analysis(*at_rest(build_spec(TruckVariant(**base, frame_hinge_share=0.5,
                                                            frame_damping_ratio=FRAME_DAMPING_RATIO),
                                               pans="fixed").compile()))
    assert [(m.name, m.frequency_hz, m.damping_ratio) for m in default] == \
        [(m.name, m.frequency_hz, m.damping_ratio) for m in given]


@pytest.mark.parametrize("share,zeta", [(0.35, 0.02), (0.65, 0.06)])
def test_a_cut_elsewhere_keeps_the_truck_and_gives_the_requested_modes(share, zeta, same_rigid_truck):
    """The cut at ``share`` of the way from the front axle to the rear one: the joints there; mass, centre
    of mass and the rigid truck's mass matrix kept; with the suspension removed each mode at its
    frequency (0.5 %, as at mid-wheelbase) damped at ``zeta``. A payload ahead of the cut rides on the
    front half."""
    spec = build_spec(TruckVariant(payload_kg=3640.0), pans="fixed")
    rigid = spec.compile()
    add_frame_flex(spec, 6.0, 11.0, hinge_share=share, damping_ratio=zeta)
    flex = spec.compile()
    same_rigid_truck(rigid, flex, BODIES)
    x_f, x_r = (rigid.body_pos[_id(rigid, OBJ.mjOBJ_BODY, names.axle_body(c))][0] for c in ("fl", "rl"))
    for name in names.FRAME_JOINTS:
        assert _frame_joint(flex, name)[0][0] == pytest.approx(x_f + share * (x_r - x_f), abs=1e-12)
    payload_parent = mujoco.mj_id2name(flex, OBJ.mjOBJ_BODY, flex.body_parentid[_id(flex, OBJ.mjOBJ_BODY, "payload")])
    assert payload_parent == ("chassis" if x_f + share * (x_r - x_f) < -1.3 else names.FRAME_REAR_BODY)
    _remove_suspension(spec)
    model = spec.compile()
    modes = {m.name: m for m in modal_analysis(model, _forward(model))}
    for name, hz in zip(names.FRAME_JOINTS, (6.0, 11.0)):
        mode = modes[name.replace("_", " ")]
        assert mode.frequency_hz == pytest.approx(hz, rel=5e-3), name
        assert mode.damping_ratio == pytest.approx(zeta, rel=0.02), name


@pytest.mark.parametrize("field,value", [("frame_hinge_share", 0.2), ("frame_hinge_share", 0.8),
                                         ("frame_damping_ratio", 0.005), ("frame_damping_ratio", float("inf"))])
def test_a_bad_cut_or_damping_names_the_field(field, value):
    with pytest.raises(ValueError, match=f"vehicle.{field}") as err:
        TruckVariant(frame_torsion_hz=8.0, frame_bending_hz=8.0, **{field: value})
    assert "\n" not in str(err.value)
    with pytest.raises(ValueError, match=f"vehicle.{field}"):
        add_frame_flex(build_spec(TruckVariant(), pans="fixed"), 8.0, 8.0, **{field.replace("frame_", ""): value})
    with pytest.raises(ValueError, match=f"vehicle.{field} only applies to a flexible frame"):
        TruckVariant(**{field: 0.5 if field == "frame_hinge_share" else 0.04})
