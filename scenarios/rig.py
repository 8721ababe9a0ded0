"""Rig-test mode: the wheelpans are driven by the nonlinear hydraulic actuators.

The drive signal (the high-passed road profile, identical to road mode) is the actuator
reference x_ref in ``ctrl``; the actuator states live in MuJoCo's activation vector and
are advanced by the callbacks of :mod:`hydraulics.bridge`, installed for this run only.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
from mujoco import rollout

from hydraulics.bridge import add_hydraulic_actuators, hydraulic_callbacks
from hydraulics.equilibrium import equilibrium_activation
from hydraulics.params import STATE_NAMES, ActuatorParams
from mjcf.build import CORNERS, build_spec
from mjcf.physics import RigIndex, static_equilibrium
from scenarios.config import Scenario, ScenarioError

__all__ = ["actuator_params", "rig_model", "rest_state", "plant_poles", "check_plant_stable", "run_rig"]

MPA = 1e6


def actuator_params(scenario: Scenario) -> ActuatorParams:
    """The scenario's actuator parameters (defaults with the ``[actuator]`` overrides)."""
    try:
        return ActuatorParams(**dict(scenario.actuator))
    except (TypeError, ValueError) as exc:
        raise ScenarioError(str(exc)) from None


def rig_model(scenario: Scenario, params: ActuatorParams) -> mujoco.MjModel:
    """Compile the truck on the rig with the hydraulic actuators added.

    The pan mass is one physical quantity with two homes (the MuJoCo pan body and the
    actuator parameters used by the linear models): a rig run uses the actuator's value
    unless the scenario sets ``vehicle.pan_mass_kg``, and refuses two different values.
    """
    variant = scenario.vehicle
    if variant.pan_mass_kg is None:
        variant = dataclasses.replace(variant, pan_mass_kg=params.pan_mass_kg)
    elif "pan_mass_kg" in scenario.actuator and scenario.actuator["pan_mass_kg"] != variant.pan_mass_kg:
        raise ScenarioError(
            f"vehicle.pan_mass_kg ({variant.pan_mass_kg:g} kg) and actuator.pan_mass_kg "
            f"({scenario.actuator['pan_mass_kg']:g} kg) disagree; set only one of them"
        )
    spec = build_spec(variant)
    add_hydraulic_actuators(spec, params, CORNERS)
    return spec.compile()


def _hyd_ids(model: mujoco.MjModel) -> np.ndarray:
    return np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"hyd_{c}") for c in CORNERS])


def rest_state(model: mujoco.MjModel, params: ActuatorParams) -> mujoco.MjData:
    """MjData at static rest: truck in equilibrium on the pans at mid-stroke, each actuator's
    pressures carrying its tire load plus the pan's weight, spool at the flow balance."""
    data = mujoco.MjData(model)
    static_equilibrium(model, data, pan_z_m=np.zeros(len(CORNERS)))
    idx = RigIndex.of(model)
    tire = data.actuator_force[idx.tire_actuator]
    g = -model.opt.gravity[2]
    hyd = _hyd_ids(model)
    for i, act_id in enumerate(hyd):
        body = model.jnt_bodyid[model.actuator_trnid[act_id, 0]]
        load = float(tire[i] + model.body_mass[body] * g)
        adr, dim = model.actuator_actadr[act_id], model.actuator_actnum[act_id]
        data.act[adr: adr + dim] = equilibrium_activation(params, load)
        data.ctrl[act_id] = 0.0
    mujoco.mj_forward(model, data)
    return data


def plant_poles(model: mujoco.MjModel, data: mujoco.MjData, eps: float = 1e-6) -> np.ndarray:
    """Continuous-time poles (rad/s) of the closed-loop plant (truck + pans + hydraulics)
    linearized about the state in ``data`` with ``mujoco.mjd_transitionFD``.

    The callbacks are installed for the linearization only; leaf-spring dry friction is
    off (it locks the springs at rest and has no derivative). Each discrete eigenvalue mu
    maps to lambda = log(mu) / dt.
    """
    from mjcf.physics import friction_disabled

    n = 2 * model.nv + model.na
    a = np.zeros((n, n))
    with hydraulic_callbacks(model), friction_disabled(model):
        mujoco.mjd_transitionFD(model, data, eps, True, a, None, None, None)
    mu = np.linalg.eigvals(a)
    return np.log(mu.astype(complex)) / model.opt.timestep


def check_plant_stable(model: mujoco.MjModel, data: mujoco.MjData) -> None:
    """Refuse a rig whose linearized closed loop under this truck is unstable.

    The actuator parameters check their loop under one reference wheel station on
    construction; this checks the real plant (every wheel station, the truck's coupling
    and MuJoCo's Euler step) before a run starts.

    Raises
    ------
    ScenarioError
        Naming the unstable pole and the parameters to change.
    """
    lam = plant_poles(model, data)
    worst = lam[np.argmax(lam.real)]
    # A growth rate below 1e-3 1/s is numerical noise of the finite differences around
    # the neutrally stable integrator states, not an instability over a run of minutes.
    if worst.real > 1e-3:
        raise ScenarioError(
            f"the rig's closed loop under this truck is unstable: pole {worst.real:.3g} "
            f"{'+-' if worst.imag else ''}{abs(worst.imag):.4g}j rad/s ({abs(worst.imag) / (2 * np.pi):.1f} Hz); "
            "raise actuator.kdp_per_Pa, lower actuator.kp_per_m or raise actuator.spool_hz"
        )


def run_rig(scenario: Scenario, drive, progress=None, *, pose_rate_hz: float | None = None) -> dict:
    """Run the rig test; returns the recorded per-wheel signals and the events.

    The rig model is built here (the truck with the actuators added and the actuator's pan
    mass); ``drive`` is any :class:`scenarios.runner.Drive` on the simulation's time step.
    """
    from hydraulics.events import events as hydraulic_events
    from scenarios.runner import SimulationError, Watch, output_schedule

    params = actuator_params(scenario)
    model = rig_model(scenario, params)
    data = rest_state(model, params)
    check_plant_stable(model, data)
    idx = RigIndex.of(model)
    hyd = _hyd_ids(model)
    qa = idx.pan_qpos
    adr = model.actuator_actadr[hyd]
    dim = int(model.actuator_actnum[hyd[0]])
    act_index = (adr[:, None] + np.arange(dim)[None, :])  # (4, dim)
    k0, decim, n_out = output_schedule(drive, model.opt.timestep, scenario.output_rate_hz)
    pan = np.empty((n_out, 4))
    force = np.empty((n_out, 4))
    states = np.empty((n_out, 4, dim))

    def diverged(data_: mujoco.MjData, t: float) -> None:
        if not np.all(np.isfinite(data_.act)):
            raise SimulationError(
                f"the hydraulic states diverged by t = {t:.4f} s of simulated time; "
                "the actuator parameters make the loop unstable"
            )

    watch = Watch(drive, model.opt.timestep, progress, extra=diverged)
    # Stepping in C: mujoco.rollout over chunks of one watch interval (10 ms), the drive as
    # the open-loop control of the hyd_<c> actuators, the constraint warm start carried from
    # chunk to chunk; bit-identical to a Python loop of mj_step, about twice as fast.
    spec_state = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec_state))
    mujoco.mj_getState(model, data, state, spec_state)
    q0, a0 = 1, 1 + model.nq + model.nv  # offsets of qpos and act in a FULLPHYSICS state
    sensors = np.array([model.sensor_adr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, f"tire_force_{c}")]
                        for c in CORNERS])
    n = drive.t_s.size
    chunk = watch.check
    poses = scratch = None
    if pose_rate_hz is not None:
        from scenarios.recording import PoseRecorder  # numpy only, no rerun import

        poses = PoseRecorder(model, drive.t_s, pose_rate_hz, every=decim)
        scratch = mujoco.MjData(model)
        frames = set(int(k) for k in poses.steps)
    ctrl = np.zeros((chunk, model.nu))
    with hydraulic_callbacks(model):
        for k in range(0, n, chunk):
            kk = min(chunk, n - k)
            ctrl[:kk, hyd] = drive.z_m[k:k + kk]
            out_state, out_sensor = rollout.rollout(
                model, data, state, ctrl[:kk], initial_warmstart=data.qacc_warmstart.copy()
            )
            # Output samples in this chunk: pre-step state of step k+i is the chunk's initial
            # state (i = 0) or the state after step k+i-1; forces are those of step k+i.
            steps = np.arange(k, k + kk)
            rows = steps[(steps >= k0) & ((steps - k0) % decim == 0)]
            if rows.size:
                i = rows - k
                j = (rows - k0) // decim
                pre = np.where((i == 0)[:, None], state[None, :], out_state[0, np.maximum(i - 1, 0)])
                pan[j] = pre[:, q0 + qa]
                states[j] = pre[:, a0 + act_index]
                force[j] = out_sensor[0, i][:, sensors]
                if poses is not None:
                    for row, k_row in zip(pre, rows):
                        if int(k_row) in frames:
                            scratch.qpos[:] = row[q0:q0 + model.nq]
                            mujoco.mj_kinematics(model, scratch)
                            poses(scratch, int(k_row))
            state = out_state[0, -1].copy()
            watch.tick(data, k + kk - 1)
        watch.finish(data)
    names = list(STATE_NAMES)
    spool = states[:, :, names.index("spool")]
    p1 = states[:, :, names.index("p1_MPa")] * MPA
    p2 = states[:, :, names.index("p2_MPa")] * MPA
    ev = hydraulic_events(states, params)
    t_out = drive.t_s[k0::decim]
    events = {}
    for name, mask in ev.items():
        mask = np.asarray(mask)
        per = {}
        for i, c in enumerate(CORNERS):
            m_c = mask[:, i] if mask.ndim == 2 else mask
            if np.any(m_c):
                per[c] = {"samples": int(np.sum(m_c)), "first_time_s": float(t_out[np.argmax(m_c)])}
        if per:
            events[name] = per
    return {
        "pan_m": pan,
        "tire_force_N": force,
        "spool": spool,
        "p1_Pa": p1,
        "p2_Pa": p2,
        "events": events,
        **({"poses": poses.track()} if poses is not None else {}),
    }
