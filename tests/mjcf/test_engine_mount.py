"""Tests of the engine on its mounts (:func:`rigsim.mjcf.engine.add_engine_mount`), a plant feature the
calibrated model family (engine rigid in the chassis) lacks.

References, independent of the code under test: the rigid truck compiled by MuJoCo (masses,
``subtree_com``, the joint-space mass matrix ``mj_fullM``, its static rest); the engine alone on its
springs with the frame held, f = sqrt(k / m) / (2 pi) and in pitch sqrt(k a^2 / I) / (2 pi), the
mounts at a = spacing / 2 and the uniform box's I = m (l^2 + h^2) / 12; on the whole truck, two
masses on a spring, omega^2 = k (1 / m_e + 1 / m_app), with m_app the sprung body's apparent mass
at the engine (1 / m_app = 1 / M + d^2 / I, written out here from MuJoCo's per-body data).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from rigsim.mjcf import names
from rigsim.mjcf.build import build_spec
from rigsim.mjcf.cab import add_cab_mount
from rigsim.mjcf.engine import (BOUNDS, ENGINE_MOUNT_DAMPING_RATIO, ENGINE_MOUNT_SPACING_M, ENGINE_SIZE_M, add_engine_mount)
from rigsim.mjcf.frame import add_frame_flex
from rigsim.mjcf.physics import TRUCK_JOINTS, RigIndex, tire_forces
from rigsim.mjcf.modes import modal_analysis
from rigsim.mjcf.variant import TruckVariant

OBJ = mujoco.mjtObj
BODIES = names.TRUCK_BODIES + (names.ENGINE_BODY, names.CAB_BODY, names.FRAME_REAR_BODY)


def _id(model, kind, name):
    return mujoco.mj_name2id(model, kind, name)


def _specs(payload_kg=3640.0, pans="fixed", engine_kg=1000.0, hz=8.0, cab_hz=None):
    spec = build_spec(TruckVariant(payload_kg=payload_kg), pans=pans)
    if cab_hz:
        add_cab_mount(spec, cab_hz, 1000.0)
    rigid = spec.compile()
    add_engine_mount(spec, engine_kg, hz)
    return rigid, spec


def _truck_ids(model):
    return [i for i in (_id(model, OBJ.mjOBJ_BODY, n) for n in BODIES) if i >= 0]


@pytest.mark.parametrize("field,value", [("engine_mass_kg", 250.0), ("engine_mass_kg", 1600.0),
                                         ("engine_mount_hz", 4.0), ("engine_mount_hz", float("inf")),
                                         ("engine_mount_hz", None)])
def test_bad_values_name_the_field(field, value):
    spec = build_spec(TruckVariant(), pans="fixed")
    argument = {"engine_mass_kg": "engine_kg", "engine_mount_hz": "mount_hz"}[field]
    args = {"engine_kg": 1000.0, "mount_hz": 8.0, argument: value}
    with pytest.raises(ValueError, match=f"vehicle.{field}") as err:
        add_engine_mount(spec, **args)
    assert "\n" not in str(err.value)
    assert BOUNDS["engine_mass_kg"][:3] == (300.0, 1500.0, "kg") and BOUNDS["engine_mount_hz"][:3] == (5.0, 20.0, "Hz")


def test_applies_once():
    _, spec = _specs()
    with pytest.raises(ValueError, match="already on its mounts"):
        add_engine_mount(spec, 1000.0, 8.0)


@pytest.mark.parametrize("payload_kg,engine_kg,cab_hz", [(3640.0, 1000.0, None), (6360.0, 1500.0, None),
                                                          (0.0, 300.0, None), (3640.0, 1200.0, 2.0)])
def test_mass_centre_of_mass_and_inertia_are_kept(payload_kg, engine_kg, cab_hz, same_rigid_truck):
    """With the engine at rest on its mounts the truck has the rigid model's mass, centre of mass and
    mass matrix in the rigid truck's joints (and the cab's, when it has one)."""
    rigid, spec = _specs(payload_kg, engine_kg=engine_kg, cab_hz=cab_hz)
    model = spec.compile()
    assert model.body_mass[_id(model, OBJ.mjOBJ_BODY, names.ENGINE_BODY)] == engine_kg
    same_rigid_truck(rigid, model, BODIES)


@pytest.mark.parametrize("pans", ["slide", "mocap"])
def test_rests_on_pans_at_mid_stroke_as_the_rigid_truck(pans, at_rest):
    """The preload holds the engine at zero deflection, so the truck rests as the rigid one: same
    truck joints, same four (loaded) tire forces; nothing moves in 0.5 s from rest. The deflection
    left, 7e-9 m: the slide tilts with the chassis' rest pitch theta (1.9 mrad), which takes
    g theta^2 / 2 off the engine's weight along it, g theta^2 / (2 omega^2) = 7e-9 m at 8 Hz."""
    rigid, spec = _specs(pans=pans)
    model, data = at_rest(spec.compile(), np.zeros(4))
    _, d_rigid = at_rest(rigid, np.zeros(4))
    idx, idx_rigid = RigIndex.of(model), RigIndex.of(rigid)
    engine_q = idx.truck_qpos[len(TRUCK_JOINTS):]
    assert engine_q.size == 2 and np.max(np.abs(data.qpos[engine_q])) < 2e-8  # m and rad
    assert np.allclose(data.qpos[idx.truck_qpos[: len(TRUCK_JOINTS)]], d_rigid.qpos[idx_rigid.truck_qpos], atol=1e-9)
    loads = tire_forces(model, data)
    assert np.all(loads > 0) and loads == pytest.approx(tire_forces(rigid, d_rigid), rel=1e-9)
    if pans == "mocap":
        mujoco.mj_step(model, data, int(round(0.5 / model.opt.timestep)))
        assert all(w.number == 0 for w in data.warning)
        assert np.max(np.abs(data.qvel)) < 1e-6


@pytest.mark.parametrize("engine_kg,hz", [(1000.0, 8.0), (300.0, 5.0), (1500.0, 20.0)])
def test_modes_on_a_held_frame_match_the_single_mass_reference(engine_kg, hz, held_frame_modes):
    """Chassis held (its joints removed): the engine alone on its mounts."""
    modes = held_frame_modes(_specs(engine_kg=engine_kg, hz=hz)[1])
    k = engine_kg * (2 * math.pi * hz) ** 2
    length, _, height = ENGINE_SIZE_M
    inertia = engine_kg * (length**2 + height**2) / 12
    f_pitch = math.sqrt(k * (ENGINE_MOUNT_SPACING_M / 2) ** 2 / inertia) / (2 * math.pi)
    assert modes["engine bounce"].frequency_hz == pytest.approx(math.sqrt(k / engine_kg) / (2 * math.pi), rel=0.01)
    assert modes["engine bounce"].damping_ratio == pytest.approx(ENGINE_MOUNT_DAMPING_RATIO, rel=0.02)
    assert modes["engine pitch"].frequency_hz == pytest.approx(f_pitch, rel=0.01)


@pytest.mark.parametrize("hz", [6.0, 8.0, 12.0])
def test_engine_bounce_on_the_truck_on_rigid_pans(hz, at_rest):
    """Above the body modes the sprung body moves as a free mass under the engine: two masses on
    the mounts' spring, omega^2 = k (1/m_e + 1/m_app), m_app the body's apparent mass at the
    engine's x (its heave and its pitch about its centre of mass). 3 %: the suspension's springs
    and tires, which hold the body too, and the axle hop modes (9.3-10.4 Hz) the engine couples
    with through the frame."""
    engine_kg = 1000.0
    _, spec = _specs(engine_kg=engine_kg, hz=hz)
    model, data = at_rest(spec.compile())
    sprung = [_id(model, OBJ.mjOBJ_BODY, n) for n in ("chassis", "payload")]
    mass = model.body_mass[sprung].sum()
    com = (model.body_mass[sprung, None] * data.xipos[sprung]).sum(axis=0) / mass
    pitch = sum(model.body_mass[b] * ((data.xipos[b, 0] - com[0]) ** 2 + (data.xipos[b, 2] - com[2]) ** 2)
                + (data.ximat[b].reshape(3, 3) @ np.diag(model.body_inertia[b]) @ data.ximat[b].reshape(3, 3).T)[1, 1]
                for b in sprung)
    engine = _id(model, OBJ.mjOBJ_BODY, names.ENGINE_BODY)
    apparent = 1.0 / (1.0 / mass + (data.xipos[engine, 0] - com[0]) ** 2 / pitch)
    f_ref = hz * math.sqrt(1.0 + engine_kg / apparent)
    found = [m for m in modal_analysis(model, data) if m.name.startswith("engine bounce")]
    print(f"\nengine {hz} Hz on the truck: {found[0].name} {found[0].frequency_hz:.3f} Hz, two-mass {f_ref:.3f} Hz")
    assert len(found) == 1 and found[0].frequency_hz == pytest.approx(f_ref, rel=0.03)


def test_composes_with_the_flexible_frame_and_the_cab(at_rest):
    """Cab, engine and flexible frame on one truck: it rests on all four tires carrying its weight."""
    spec = build_spec(TruckVariant(payload_kg=3640.0), pans="slide")
    add_cab_mount(spec, 2.0, 1000.0)
    add_engine_mount(spec, 1000.0, 8.0)
    add_frame_flex(spec, 8.0, 8.0)
    model, data = at_rest(spec.compile(), np.zeros(4))
    assert RigIndex.of(model).truck_qpos.size == len(TRUCK_JOINTS) + 6
    assert model.body_parentid[_id(model, OBJ.mjOBJ_BODY, names.ENGINE_BODY)] == _id(model, OBJ.mjOBJ_BODY, "chassis")
    loads = tire_forces(model, data)
    assert np.all(loads > 0)
    assert loads.sum() == pytest.approx(model.body_mass[_truck_ids(model)].sum() * 9.81, rel=1e-4)
