"""Step rate of the rig with hydraulics in the loop versus bare MuJoCo with the same pan motion.

1. rig: the model with one hydraulic user actuator per pan (compiled numba callbacks), started at
   the static equilibrium, driven by a multi-sine x_ref, N steps with ``mujoco.rollout``; an
   ``actuatorfrc`` sensor records the force each actuator applied at every step;
2. bare: the same model with a plain ``motor`` per pan instead (no callbacks, no activation
   states), replaying the recorded forces as controls: the pans follow the same motion, so the
   ratio measures the hydraulics and not the contact solver.

Both runs are repeated alternately; the fastest of each is printed as one JSON line:
``{"bare_steps_per_s", "rig_steps_per_s", "ratio", ...}``.

Usage::

    python benchmarks/step_rate.py [--model truck|four|single] [--steps N] [--repeats R]
    python benchmarks/step_rate.py --spec package.module:function

``--model truck`` (the default) is the project's truck on the four pans (mjcf/), at its static
equilibrium; ``four``/``single`` are stand-in quarter trucks.

``--spec`` names a function returning an ``mujoco.MjSpec`` that contains the slide joints
``pan_<c>_z`` (and no hydraulic actuators); its first keyframe, if any, is the static state.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import pathlib
import sys
import time

import mujoco
import numpy as np
from mujoco import rollout

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from hydraulics import ActuatorParams, equilibrium_activation  # noqa: E402
from hydraulics.bridge import activation_slice, add_hydraulic_actuators, hydraulic_callbacks  # noqa: E402
from mjcf.names import CORNERS  # noqa: E402

PARAMS = ActuatorParams()
STATE_SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS
#: Integrations to compare: RK4 at 1e-3 s (both tests', scenarios.core.rig), explicit Euler at
#: 1e-4 s (their former one); ``--integration`` picks one for both models.
INTEGRATIONS = {"rk4": (mujoco.mjtIntegrator.mjINT_RK4, 1e-3), "euler": (mujoco.mjtIntegrator.mjINT_EULER, 1e-4)}
#: The bare model's pan servos under RK4, N/m and N s/m: 316 rad/s on a 500 kg pan, 70 % of critical
#: damping, well inside RK4's region at 1e-3 s; they hold the tire load with a 0.6 mm error.
SERVO_KP, SERVO_KV = 5e7, 2.2e5


def bare_controls(rig, bare, corners, state, sensordata) -> np.ndarray:
    """What the bare model replays to move its pans as the rig's did, (steps, bare.nu).

    Explicit Euler: the force each hydraulic actuator applied (its ``actuatorfrc`` sensor): the
    pans then move exactly as in the rig. RK4 evaluates the forces at four stages per step, so a
    replayed per-step force lets the pans drift off (measured: 0.1 m in 20 000 steps); the bare
    model then has a stiff position servo per pan (built-in, no callback) fed the rig's recorded
    pan positions instead, which keeps the same motion to within a millimetre.
    """
    hyd = [mujoco.mj_name2id(rig, mujoco.mjtObj.mjOBJ_ACTUATOR, f"hyd_{c}") for c in corners]
    out = np.zeros((state.shape[1], bare.nu))
    if rig.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4:
        qadr = [int(rig.jnt_qposadr[mujoco.mj_name2id(rig, mujoco.mjtObj.mjOBJ_JOINT, f"pan_{c}_z")]) for c in corners]
        out[:, hyd] = state[0][:, [1 + a for a in qadr]]
    else:
        sens = [int(rig.sensor_adr[mujoco.mj_name2id(rig, mujoco.mjtObj.mjOBJ_SENSOR, f"force_{c}")]) for c in corners]
        out[:, hyd] = sensordata[0][:, sens]
    return out


def quarter_truck_spec(corners=CORNERS, *, tire=1.0e6, unsprung=450.0, sprung=2500.0,
                       suspension=3.0e5, damping=1.5e4) -> mujoco.MjSpec:
    """Per corner: pan (slide) -> tire spring -> unsprung mass -> suspension -> quarter of the
    sprung mass, each a slide joint with joint stiffness, at static equilibrium at qpos 0."""
    g = 9.81
    spec = mujoco.MjSpec()
    spec.modelname = "quarter_trucks"
    spec.option.timestep = 1.0e-4
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    for i, c in enumerate(corners):
        pan = spec.worldbody.add_body(name=f"pan_{c}", pos=[2.0 * i, 0, 0])
        pan.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.5, 0.3, 0.05], mass=PARAMS.pan_mass_kg,
                     contype=0, conaffinity=0)
        pan.add_joint(name=f"pan_{c}_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1],
                      range=[-PARAMS.half_stroke_m, PARAMS.half_stroke_m],
                      limited=mujoco.mjtLimited.mjLIMITED_TRUE)
        axle = pan.add_body(name=f"axle_{c}", pos=[0, 0, 0.5])
        axle.add_geom(type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[0.5, 0.3], mass=unsprung,
                      contype=0, conaffinity=0)
        axle.add_joint(name=f"tire_{c}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1],
                       stiffness=tire, springref=(unsprung + sprung) * g / tire)
        body = axle.add_body(name=f"sprung_{c}", pos=[0, 0, 0.8])
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.5, 0.5, 0.3], mass=sprung,
                      contype=0, conaffinity=0)
        body.add_joint(name=f"susp_{c}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1],
                       stiffness=suspension, springref=sprung * g / suspension, damping=damping)
    return spec


def truck_spec() -> mujoco.MjSpec:
    """The project's truck on the rig (pan mass from the actuator parameters) with a keyframe
    at its static equilibrium on the pans at mid-stroke."""
    from mjcf.build import TruckVariant, build_spec
    from mjcf.physics import static_equilibrium

    variant = TruckVariant(pan_mass_kg=PARAMS.pan_mass_kg)
    model = build_spec(variant).compile()
    data = mujoco.MjData(model)
    qpos = static_equilibrium(model, data)
    spec = build_spec(variant)
    spec.add_key(name="rest", qpos=qpos)
    return spec


def _spec_from(args) -> tuple[mujoco.MjSpec, tuple]:
    if args.model == "truck" and not args.spec:
        return truck_spec(), CORNERS
    if args.spec:
        module, _, func = args.spec.partition(":")
        spec = getattr(importlib.import_module(module), func)()
        corners = tuple(c for c in CORNERS if spec.joint(f"pan_{c}_z") is not None)
        return spec, corners
    corners = CORNERS if args.model == "four" else ("fl",)
    return quarter_truck_spec(corners), corners


def _add_force_sensors(spec, corners):
    for c in corners:
        spec.add_sensor(name=f"force_{c}", type=mujoco.mjtSensor.mjSENS_ACTUATORFRC,
                        objtype=mujoco.mjtObj.mjOBJ_ACTUATOR, objname=f"hyd_{c}")


def build_models(args):
    """(rig model, bare model, corners): identical but for the actuators."""
    spec_rig, corners = _spec_from(args)
    spec_bare, _ = _spec_from(args)
    add_hydraulic_actuators(spec_rig, PARAMS, corners)
    servo = getattr(args, "integration", "rk4") == "rk4"
    for c in corners:
        a = spec_bare.add_actuator(name=f"hyd_{c}", target=f"pan_{c}_z",
                                   trntype=mujoco.mjtTrn.mjTRN_JOINT)
        if servo:  # RK4: see bare_controls
            a.set_to_position(kp=SERVO_KP, kv=SERVO_KV)
        else:
            a.set_to_motor()
        a.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    _add_force_sensors(spec_rig, corners)
    _add_force_sensors(spec_bare, corners)
    rig, bare = spec_rig.compile(), spec_bare.compile()
    integrator, dt = INTEGRATIONS[getattr(args, "integration", "rk4")]
    for m in (rig, bare):
        m.opt.integrator, m.opt.timestep = integrator, dt
    return rig, bare, corners


def static_loads(model: mujoco.MjModel, corners) -> dict:
    """Force each pan joint must supply to hold the model at rest (first keyframe or qpos0)."""
    data = mujoco.MjData(model)
    if model.nkey:
        mujoco.mj_resetDataKeyframe(model, data, 0)
    data.qvel[:] = 0.0
    data.qacc[:] = 0.0
    mujoco.mj_inverse(model, data)
    out = {}
    for c in corners:
        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"pan_{c}_z")
        out[c] = float(data.qfrc_inverse[model.jnt_dofadr[j]])  # bias - passive - constraint
    return out


def drive_signal(n, dt, corners) -> np.ndarray:
    """Multi-sine x_ref (m) per corner: 1 mm at 3 Hz, 0.5 mm at 11 Hz, 0.2 mm at 23 Hz."""
    t = np.arange(n) * dt
    cols = []
    for i, _ in enumerate(corners):
        ph = 0.7 * i
        cols.append(1e-3 * np.sin(2 * math.pi * 3 * t + ph) + 5e-4 * np.sin(2 * math.pi * 11 * t + 2 * ph)
                    + 2e-4 * np.sin(2 * math.pi * 23 * t + 3 * ph))
    return np.stack(cols, axis=1)


def initial_state(model, corners, loads, hydraulic: bool) -> np.ndarray:
    data = mujoco.MjData(model)
    if model.nkey:
        mujoco.mj_resetDataKeyframe(model, data, 0)
    if hydraulic:
        for c in corners:
            data.act[activation_slice(model, c)] = equilibrium_activation(PARAMS, loads[c])
    state = np.empty(mujoco.mj_stateSize(model, STATE_SPEC))
    mujoco.mj_getState(model, data, state, STATE_SPEC)
    return state


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", choices=("truck", "four", "single"), default="truck")
    ap.add_argument("--spec", help="module:function returning an MjSpec with pan_<c>_z joints")
    ap.add_argument("--integration", choices=tuple(INTEGRATIONS), default="rk4",
                    help="rk4: RK4 at 1e-3 s (both tests'); euler: explicit Euler at 1e-4 s (their former)")
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)

    rig, bare, corners = build_models(args)
    loads = static_loads(bare, corners)
    n = args.steps
    hyd = [mujoco.mj_name2id(rig, mujoco.mjtObj.mjOBJ_ACTUATOR, f"hyd_{c}") for c in corners]
    x_ref = np.zeros((n, rig.nu))  # other actuators (the tires) take no control
    x_ref[:, hyd] = drive_signal(n, rig.opt.timestep, corners)
    d_rig, d_bare = mujoco.MjData(rig), mujoco.MjData(bare)
    s_rig = initial_state(rig, corners, loads, True)
    s_bare = initial_state(bare, corners, loads, False)

    rig_times, bare_times = [], []
    forces = qpos_rig = None
    with hydraulic_callbacks(rig, fast=True):
        rollout.rollout(rig, d_rig, s_rig, x_ref[:10])  # warm-up (first call allocates)
    for _ in range(args.repeats):
        with hydraulic_callbacks(rig, fast=True):
            t0 = time.perf_counter()
            state, sensordata = rollout.rollout(rig, d_rig, s_rig, x_ref)
            rig_times.append(time.perf_counter() - t0)
        forces = bare_controls(rig, bare, corners, state, sensordata)
        qpos_rig = state[0, :, 1:1 + rig.nq]
        t0 = time.perf_counter()
        state_b, _ = rollout.rollout(bare, d_bare, s_bare, forces)
        bare_times.append(time.perf_counter() - t0)
    qpos_bare = state_b[0, :, 1:1 + bare.nq]
    # The fastest of the repeats is the least disturbed by other processes (2-core machines);
    # the ratio of the medians is reported alongside.
    rig_rate = n / float(np.min(rig_times))
    bare_rate = n / float(np.min(bare_times))
    result = {
        "model": args.spec or args.model,
        "integration": args.integration,
        "steps": n,
        "repeats": args.repeats,
        "bare_steps_per_s": round(bare_rate, 1),
        "rig_steps_per_s": round(rig_rate, 1),
        "ratio": round(rig_rate / bare_rate, 4),
        "ratio_of_medians": round(float(np.median(bare_times) / np.median(rig_times)), 4),
        "max_pan_motion_m": float(np.max(np.abs(qpos_rig))),
        "max_qpos_diff_m": float(np.max(np.abs(qpos_rig - qpos_bare))),
    }
    print(json.dumps(result))
    return result


if __name__ == "__main__":
    main()
