"""Tests of the suspended cab (``TruckVariant.cab_mount_hz``), the plant feature the calibrated
rigid-cab model family lacks.

References, independent of the code under test: the XML compiled directly by MuJoCo (the
model without the mount); MuJoCo's own composite quantities (body masses, ``subtree_com``,
the joint-space mass matrix ``mj_fullM``) of the rigid-cab model; the cab alone on its
springs with the frame held, f = sqrt(k / m) / (2 pi) with k = m (2 pi f_mount)^2, and in
pitch sqrt(k a^2 / I) / (2 pi) with the mounts at a = spacing / 2 and the uniform box's
I = m (l^2 + h^2) / 12 of the cab geom in truck_rig.xml (1.8 m long, 1.9 m high); the total
weight (sum of body masses times g) for the mean wheel forces of a run.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from rigsim.mjcf import names
from rigsim.mjcf.build import build_model, build_spec, resource_path
from rigsim.mjcf.cab import CAB_DAMPING_RATIO, CAB_MASS_KG, CAB_MOUNT_SPACING_M
from rigsim.mjcf.variant import TruckVariant
from rigsim.mjcf.physics import TRUCK_JOINTS, RigIndex, static_equilibrium, tire_forces
from rigsim.mjcf.modes import modal_analysis
from rigsim.scenarios.core.config import ScenarioError, load_scenario, parse_scenario

G = 9.81  # m/s^2, the model's gravity
CAB_LENGTH_M, CAB_HEIGHT_M = 1.8, 1.9  # the cab geom of truck_rig.xml (half sizes 0.9 and 0.95 m)


def _rest_of(model):
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    return model, data


def _rest(variant: TruckVariant, pans: str = "slide"):
    return _rest_of(build_model(variant, pans=pans))


def _truck_body_ids(model) -> list[int]:
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in names.TRUCK_BODIES + (names.CAB_BODY,)]
    return [i for i in ids if i >= 0]


def test_without_the_mount_the_model_is_the_xml_as_shipped():
    """cab_mount_hz = None: the compiled model equals the XML compiled by MuJoCo directly."""
    xml = mujoco.MjModel.from_xml_path(str(resource_path("scene.xml")))
    built = build_model(TruckVariant(cab_mount_hz=None))
    for n in ("nbody", "nq", "nv", "njnt", "ngeom"):
        assert getattr(built, n) == getattr(xml, n), n
    for field in ("body_mass", "body_inertia", "body_ipos", "body_iquat", "jnt_stiffness", "dof_damping"):
        assert np.array_equal(getattr(built, field), getattr(xml, field)), field
    assert mujoco.mj_name2id(built, mujoco.mjtObj.mjOBJ_BODY, names.CAB_BODY) == -1
    geom = mujoco.mj_name2id(built, mujoco.mjtObj.mjOBJ_GEOM, "cab")
    assert built.geom_bodyid[geom] == mujoco.mj_name2id(built, mujoco.mjtObj.mjOBJ_BODY, "chassis")
    f_xml = tire_forces(*_rest_of(xml))
    f_built = tire_forces(*_rest(TruckVariant()))
    assert np.array_equal(f_xml, f_built)


@pytest.mark.parametrize("payload_kg,cab_kg", [(3640.0, None), (6360.0, None), (3640.0, 200.0), (6360.0, 1200.0)])
def test_mount_keeps_mass_centre_of_mass_inertia_and_wheel_loads(payload_kg, cab_kg, same_rigid_truck):
    rigid = build_model(TruckVariant(payload_kg=payload_kg))
    mounted = build_model(TruckVariant(payload_kg=payload_kg, cab_mount_hz=2.0, cab_mass_kg=cab_kg))
    cab = mujoco.mj_name2id(mounted, mujoco.mjtObj.mjOBJ_BODY, names.CAB_BODY)
    assert mounted.body_mass[cab] == pytest.approx(cab_kg or CAB_MASS_KG)
    # Mass, centre of mass (MuJoCo's subtree_com of the chassis) and, with the cab at rest on its
    # mounts, the mass matrix of the rigid truck's joints (heave, pitch, roll, axles), both at qpos0.
    same_rigid_truck(rigid, mounted, names.TRUCK_BODIES + (names.CAB_BODY,))
    # Static wheel loads: within 0.1 % of the rigid-cab truck's.
    f_rigid = tire_forces(*_rest(TruckVariant(payload_kg=payload_kg)))
    model, data = _rest(TruckVariant(payload_kg=payload_kg, cab_mount_hz=2.0, cab_mass_kg=cab_kg))
    assert tire_forces(model, data) == pytest.approx(f_rigid, rel=1e-3)
    assert tire_forces(model, data).sum() == pytest.approx(model.body_mass[_truck_body_ids(model)].sum() * G, rel=1e-3)


def test_truck_with_cab_mount_starts_at_rest():
    """The springs' preload holds the cab at zero deflection, and nothing moves from rest."""
    model, data = _rest(TruckVariant(cab_mount_hz=2.0), pans="fixed")
    idx = RigIndex.of(model)
    cab_q = idx.truck_qpos[len(TRUCK_JOINTS):]
    assert len(cab_q) == 2 and np.max(np.abs(data.qpos[cab_q])) < 1e-6  # m and rad
    assert np.max(np.abs(data.qacc)) < 1e-8
    mujoco.mj_step(model, data, int(round(1.0 / model.opt.timestep)))
    assert all(w.number == 0 for w in data.warning)
    assert np.max(np.abs(data.qvel)) < 1e-6


@pytest.mark.parametrize("hz", [0.5, 2.0, 10.0])
def test_cab_modes_on_a_held_frame_match_the_single_mass_reference(hz, held_frame_modes):
    """Chassis held (its joints removed): the cab on its springs alone."""
    modes = held_frame_modes(build_spec(TruckVariant(cab_mount_hz=hz), pans="fixed"))
    m_cab = CAB_MASS_KG
    k = m_cab * (2 * math.pi * hz) ** 2
    f_bounce = math.sqrt(k / m_cab) / (2 * math.pi)
    inertia = m_cab * (CAB_LENGTH_M**2 + CAB_HEIGHT_M**2) / 12
    f_pitch = math.sqrt(k * (CAB_MOUNT_SPACING_M / 2) ** 2 / inertia) / (2 * math.pi)
    print(f"\nframe held, mount {hz} Hz: cab bounce {modes['cab bounce'].frequency_hz:.3f} Hz "
          f"(ref {f_bounce:.3f}), cab pitch {modes['cab pitch'].frequency_hz:.3f} Hz (ref {f_pitch:.3f})")
    assert modes["cab bounce"].frequency_hz == pytest.approx(f_bounce, rel=0.01)
    assert modes["cab bounce"].damping_ratio == pytest.approx(CAB_DAMPING_RATIO, rel=0.02)
    assert modes["cab pitch"].frequency_hz == pytest.approx(f_pitch, rel=0.01)


def test_cab_modes_of_the_whole_truck():
    """On rigid pans the cab couples with the body modes: the cab sits 3.3 m ahead of the sprung
    mass' centre, where the frame's apparent mass is only ~2.3 t, so the cab bounce splits into
    a pair around the mount frequency. The cab pitch (hinge through the cab's centre of mass)
    stays near its held-frame value; the roll and axle modes, which the cab does not enter,
    keep the rigid truck's frequencies."""
    rigid = {m.name: m for m in modal_analysis(*_rest(TruckVariant(), pans="fixed"))}
    modes = modal_analysis(*_rest(TruckVariant(cab_mount_hz=2.0), pans="fixed"))
    print("\nwhole truck on rigid pans, mount 2 Hz:")
    for m in modes:
        print(f"  {m.name:16s} {m.frequency_hz:6.3f} Hz  damping ratio {m.damping_ratio:.3f}")
    names = [m.name for m in modes]
    assert len(set(names)) == len(names), names  # a coupled mode is named after its two largest joints
    bounce = [m.frequency_hz for m in modes if m.name.startswith("cab bounce with ")]
    assert "cab bounce with body pitch" in names and "body bounce" in " ".join(names)
    pitch = [m.frequency_hz for m in modes if m.name == "cab pitch"]
    assert bounce and min(bounce) < 2.0 < max(bounce) < 4.0
    f_pitch_held = 2.0 * (CAB_MOUNT_SPACING_M / 2) / math.sqrt((CAB_LENGTH_M**2 + CAB_HEIGHT_M**2) / 12)
    assert len(pitch) == 1 and pitch[0] == pytest.approx(f_pitch_held, rel=0.05)
    by_name = {m.name: m for m in modes}
    for name in ("body roll", "front axle roll", "rear axle roll", "front axle hop", "rear axle hop"):
        assert by_name[name].frequency_hz == pytest.approx(rigid[name].frequency_hz, rel=0.01), name


SCENARIO = {"name": "cab", "speed_kmh": 72.0, "duration_s": 2.0, "seed": 3, "road": {"roughness": "C"}}


def test_scenario_key_and_bad_values(tmp_path):
    path = tmp_path / "cab.toml"
    path.write_text('name = "cab"\nspeed_kmh = 72.0\nduration_s = 2.0\n[road]\nroughness = "C"\n'
                    "[vehicle]\ncab_mount_hz = 2.0\n")
    assert load_scenario(path).vehicle.cab_mount_hz == 2.0
    both = parse_scenario({**SCENARIO, "vehicle": {"cab_mount_hz": 2.0, "cab_mass_kg": 900.0}})
    assert both.vehicle.cab_mass_kg == 900.0
    bad = {
        "cab_mount_hz": {"cab_mount_hz": 0.1},
        "cab_mount_hz ": {"cab_mount_hz": 50.0},
        "cab_mass_kg": {"cab_mount_hz": 2.0, "cab_mass_kg": 3000.0},
        "cab_mass_kg ": {"cab_mass_kg": 900.0},  # a mass without a mount
    }
    for field, vehicle in bad.items():
        with pytest.raises(ScenarioError, match=f"vehicle.{field.strip()}") as err:
            parse_scenario({**SCENARIO, "vehicle": vehicle})
        assert "\n" not in str(err.value)


@pytest.fixture(scope="module")
def runs():
    from rigsim.scenarios.core.run import run

    out = {}
    for label, vehicle in (("rigid", {}), ("cab", {"cab_mount_hz": 2.0})):
        for mode in ("road", "rig"):
            out[label, mode] = run(parse_scenario({**SCENARIO, "vehicle": vehicle}), mode)
    return out


@pytest.mark.parametrize("mode", ["road", "rig"])
def test_runs_with_the_mount_differ_a_little_from_the_rigid_cab(runs, mode):
    """The mount changes the tire forces (it does something) but keeps a plausible truck: each
    wheel's DLC within 10 % of the rigid cab's; the mean forces still carry the whole weight."""
    rigid, cab = runs["rigid", mode].statistics(), runs["cab", mode].statistics()
    dlc_rigid = np.array([rigid[c]["dlc"] for c in names.CORNERS])
    dlc_cab = np.array([cab[c]["dlc"] for c in names.CORNERS])
    change = dlc_cab / dlc_rigid - 1
    print(f"\n{mode}: DLC rigid {np.round(dlc_rigid, 4)}, cab 2 Hz {np.round(dlc_cab, 4)}, "
          f"change {np.round(change, 3)}")
    assert np.max(np.abs(change)) > 0.01
    assert np.max(np.abs(change)) < 0.10
    model = build_model(TruckVariant(cab_mount_hz=2.0))
    weight = model.body_mass[_truck_body_ids(model)].sum() * G
    assert sum(cab[c]["mean_force_N"] for c in names.CORNERS) == pytest.approx(weight, rel=0.01)
