"""Fixtures shared by the tests of the plant features (the suspended cab, the flexible frame, the
engine mount)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rigsim.mjcf.physics import TRUCK_JOINTS, RigIndex, static_equilibrium
from rigsim.mjcf.modes import modal_analysis


def _at_rest(model, pan_z_m=None):
    data = mujoco.MjData(model)
    static_equilibrium(model, data, pan_z_m=pan_z_m)
    return model, data


def _same_rigid_truck(rigid, model, bodies) -> None:
    def ids(m):
        return [i for i in (mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, n) for n in bodies) if i >= 0]

    assert model.body_mass[ids(model)].sum() == pytest.approx(rigid.body_mass[ids(rigid)].sum(), rel=1e-12)
    d_rigid, d_model = mujoco.MjData(rigid), mujoco.MjData(model)
    mujoco.mj_forward(rigid, d_rigid)
    mujoco.mj_forward(model, d_model)
    chassis = mujoco.mj_name2id(rigid, mujoco.mjtObj.mjOBJ_BODY, "chassis")
    assert np.allclose(d_model.subtree_com[chassis], d_rigid.subtree_com[chassis], atol=1e-9)
    m_rigid, m_model = np.zeros((rigid.nv, rigid.nv)), np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(rigid, d_rigid, m_rigid)
    mujoco.mj_fullM(model, d_model, m_model)
    dof_r = RigIndex.of(rigid).truck_dof
    # the same joints by name (a feature's joint group may come between the rigid truck's groups)
    joints = [mujoco.mj_id2name(rigid, mujoco.mjtObj.mjOBJ_JOINT, int(rigid.dof_jntid[d])) for d in dof_r]
    dof_m = np.array([model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j)] for j in joints])
    assert dof_r.size >= len(TRUCK_JOINTS)
    assert np.allclose(m_model[np.ix_(dof_m, dof_m)], m_rigid[np.ix_(dof_r, dof_r)], rtol=1e-9, atol=1e-6)


def _held_frame_modes(spec) -> dict:
    for joint in TRUCK_JOINTS[:3]:  # chassis_z, chassis_pitch, chassis_roll
        spec.delete(spec.joint(joint))
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return {m.name: m for m in modal_analysis(model, data)}


@pytest.fixture()
def held_frame_modes():
    """``held_frame_modes(spec) -> {name: Mode}``: the modes of ``spec``'s truck (edited: its
    chassis' joints deleted) with the chassis held, about qpos0 (:func:`rigsim.mjcf.modes.modal_analysis`)."""
    return _held_frame_modes


@pytest.fixture()
def at_rest():
    """``at_rest(model, pan_z_m=None) -> (model, data)``: ``data`` at the truck's static rest
    (:func:`rigsim.mjcf.physics.static_equilibrium`, the pans at ``pan_z_m``, default mid-stroke)."""
    return _at_rest


@pytest.fixture()
def same_rigid_truck():
    """``same_rigid_truck(rigid, model, bodies)``: assert that ``model`` (a plant feature added to
    ``rigid``'s spec), at qpos0, keeps ``rigid``'s truck mass (the masses of those of ``bodies`` each
    model has), its centre of mass (MuJoCo's ``subtree_com`` of the chassis) and the mass matrix
    (``mj_fullM``) of ``rigid``'s truck joints (:class:`rigsim.mjcf.physics.RigIndex`, a cab's included)."""
    return _same_rigid_truck
