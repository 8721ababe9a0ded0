"""The road test: prescribed pans (mocap bodies) stepped by RK4 at 1e-3 s in ``mujoco.rollout``.

The choice is measured by ``benchmarks/road_integrator_study.py`` (docs/road_integrator_study.md);
these tests pin the pieces it rests on: the tire force the record reports is MuJoCo's own force
law (:func:`rigsim.mjcf.physics.tire_law` against ``actuator_force``, a progressive tire's two elements
summed), the pan velocity reaches the tire's
damping through ``ctrl``, and a run agrees with a fine explicit-Euler reference (the XML's
integrator at a quarter of its 1e-4 s step), the reference being independent of the mid-step
hold and of the force reconstruction.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rigsim.mjcf import names
from rigsim.mjcf.build import build_spec
from rigsim.mjcf.variant import TruckVariant
from rigsim.mjcf.physics import RigIndex, static_equilibrium, tire_law
from rigsim.scenarios.core.config import parse_scenario
from rigsim.scenarios.core.rig import Rig

SHORT = {"name": "road-short", "speed_kmh": 72.0, "duration_s": 2.0, "lead_in_s": 1.0, "seed": 5,
         "road": {"roughness": "C"}}


def _sensor(model, name_of):
    return np.array([model.sensor_adr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, name_of(c))]
                     for c in names.CORNERS])


@pytest.mark.parametrize("variant", [None, TruckVariant(tire_progressive_ratio=0.5, tire_progressive_onset_m=0.027)])
def test_tire_law_is_mujocos_force_with_the_pan_velocity_in_ctrl(variant):
    """With pans as mocap bodies the force MuJoCo applies is kt (R0 - L) - ct (dL/dt_truck - v_pan),
    clamped at 0 (lift-off): ``tire_law`` of the sensed length and truck-side rate minus the pan
    velocity fed as ``ctrl`` gives ``actuator_force`` to rounding, in contact and lifted off.
    With a progressive tire (its onset 2.7 cm: between the front tires' deflections of the two pan
    positions below, so that it is engaged at one and not at the other) ``tire_law`` is the sum of
    both elements' ``actuator_force`` and the tire force sensor (the tendon's actuator force)."""
    model = build_spec(variant, pans="mocap").compile()
    idx = RigIndex.of(model)
    assert idx.pan_qpos.size == 0 and idx.pan_mocap.size == 4
    assert idx.tire_extra.size == (0 if variant is None else 4)
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    rng = np.random.default_rng(1)
    data.qvel[idx.truck_dof] = rng.normal(0.0, 0.2, idx.truck_dof.size)
    pan_v = np.array([0.3, -0.2, 0.1, -0.4])
    engaged = []
    for dz in (np.array([4e-3, 3e-3, 1e-3, 0.0]), np.array([-5e-3, -3e-3, -1e-3, 2e-3]),
               np.array([-0.2, 0.0, 0.0, 0.0])):  # the last lifts fl off
        data.mocap_pos[idx.pan_mocap, 2] = model.body_pos[idx.pan_body, 2] + dz
        data.ctrl[idx.tire_actuator] = pan_v
        mujoco.mj_forward(model, data)
        length = data.sensordata[_sensor(model, names.tire_length_sensor)]
        rate = data.sensordata[_sensor(model, names.tire_rate_sensor)]
        force = data.actuator_force[idx.tire_actuator].copy()
        extra = np.zeros(4)
        extra[idx.tire_extra_corner] = data.actuator_force[idx.tire_extra]
        engaged.append(extra > 0)
        np.testing.assert_allclose(tire_law(model, idx, length, rate - pan_v), force + extra, rtol=1e-12, atol=1e-6)
        np.testing.assert_allclose(data.sensordata[_sensor(model, names.tire_sensor)], force + extra, rtol=1e-12,
                                   atol=1e-6)
        # The damping of the pan's own velocity is in the force: the same state with the pan at rest differs by ct v.
        ct = -model.actuator_biasprm[idx.tire_actuator, 2]
        on = force > 0
        np.testing.assert_allclose((force + extra - tire_law(model, idx, length, rate))[on], (ct * pan_v)[on],
                                   rtol=1e-9)
    assert force[0] == 0.0 and np.all(force[1:] > 0)
    if variant is not None:  # the progressive element was engaged and idle at the front tires
        front = np.array([c in names.FRONT for c in names.CORNERS])
        assert engaged[0][front].all() and not engaged[1][front].any() and not engaged[2][0]


def test_road_test_agrees_with_a_fine_explicit_euler_reference():
    """RK4 at 1e-3 s (pans held at mid-step, the force reconstructed at the output instants)
    against explicit Euler at 2.5e-5 s (the XML's integrator, at a quarter
    of its 1e-4 s step): the wheel forces agree to 0.5 % of their standard deviation and the DLC
    to 0.1 % (the goal of the integrator study). A force not moved to the output instant (the
    pan at mid-step) would miss by ~3 % (measured in the study), so this test can fail."""
    sc = parse_scenario(SHORT)
    fine_sc = parse_scenario({**SHORT, "vehicle": {"timestep_s": 2.5e-5}})
    rig, fine = Rig(sc, hydraulic=False), Rig(fine_sc, hydraulic=False)
    assert rig.model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4 and rig.dt_s == 1e-3
    fine.model.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    a = rig.run(rig.road_source(), rate_hz=1000.0)
    b = fine.run(fine.road_source(), rate_hz=1000.0)
    np.testing.assert_allclose(a.t_s, b.t_s, atol=1e-9)
    np.testing.assert_allclose(a.pan_m, b.pan_m, atol=1e-9)
    fa, fb = a.tire_force_N, b.tire_force_N
    nrmse = np.sqrt(np.mean((fa - fb) ** 2, axis=0)) / fb.std(axis=0)
    assert np.all(nrmse < 5e-3), nrmse
    dlc = lambda f: f.std(axis=0) / f.mean(axis=0)  # noqa: E731
    assert np.all(np.abs(dlc(fa) / dlc(fb) - 1) < 1e-3)


def test_road_poses_show_the_pans_where_the_drive_puts_them():
    """A recording's pan poses are the prescribed pan heights at the frame instants."""
    sc = parse_scenario({**SHORT, "duration_s": 0.5})
    rig = Rig(sc, hydraulic=False)
    drive = rig.road_drive()
    rec = rig.run(drive, rate_hz=1000.0, pose_rate_hz=50.0)
    track = rec.poses
    pans = [list(track.bodies).index(names.pan_body(c)) for c in names.CORNERS]
    k = np.array([drive.first_step(t - 1e-9) for t in track.t_s])
    assert k.size > 10 and np.abs(drive.z_m[k]).max() > 1e-3  # frames where the pans have moved
    np.testing.assert_allclose(track.position_m[:, pans, 2], drive.z_m[k], atol=1e-12)


def test_refined_and_every_are_exact_for_a_cubic():
    """``Drive.refined`` is the cubic Hermite interpolant (exact for a cubic polynomial, value
    and derivative), ``Drive.every`` takes the coarse steps back with their exact mid-step values."""
    from rigsim.scenarios.core.drive import Drive

    t = -3e-3 + np.arange(11) * 1e-3
    coef = np.array([0.3, -2.0, 0.5, 1e-3])
    z_of = lambda tt: np.polyval(coef, tt)[:, None] * np.array([1.0, -1.0, 2.0, 0.5])  # noqa: E731
    v_of = lambda tt: np.polyval(np.polyder(coef), tt)[:, None] * np.array([1.0, -1.0, 2.0, 0.5])  # noqa: E731
    d = Drive(t, z_of(t), v_of(t))
    fine = d.refined(10)
    assert fine.n_steps == 101 and np.array_equal(fine.t_s[::10], t)
    np.testing.assert_allclose(fine.z_m, z_of(fine.t_s), rtol=0, atol=1e-15)
    np.testing.assert_allclose(fine.v_mps, v_of(fine.t_s), rtol=0, atol=1e-13)
    back = fine.every(10)
    assert np.array_equal(back.t_s, t) and np.array_equal(back.z_m, d.z_m)
    np.testing.assert_allclose(back.held(0, 10), z_of(t[:-1] + 5e-4), rtol=0, atol=1e-15)


def test_linear_pans_run_on_the_models_own_step():
    """A road run's pans through the linearized plant (``PlantLinearization.pan_drive``): the
    plant runs at its 1e-4 s step on the refined drive, so the pan motion at the run's 1e-3 s
    steps equals the plant simulated directly on the drive made at 1e-4 s (an independent
    route: the road drive sampled finely) to 0.1 % of its range."""
    sc = parse_scenario(SHORT)
    plant = Rig(sc).linearize()
    coarse = Rig(sc, hydraulic=False).road_source().drive()
    fine = Rig(parse_scenario({**SHORT, "vehicle": {"timestep_s": 1e-4}}), hydraulic=False).road_source().drive()
    assert plant.dt_s == pytest.approx(fine.dt_s) == 1e-4 and coarse.dt_s == pytest.approx(1e-3)
    via = plant.pan_drive(coarse)
    direct = plant.simulate(fine.held(0, fine.n_steps))[::10, :4]
    assert np.array_equal(via.t_s, coarse.t_s)
    np.testing.assert_allclose(via.z_m, direct, rtol=0, atol=1e-3 * np.ptp(direct))
