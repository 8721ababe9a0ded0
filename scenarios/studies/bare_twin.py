"""The rig and its bare twin: the physics' own cost, without the hydraulics in the loop.

The twin is the same MuJoCo model with the hydraulic user actuators (compiled callbacks,
activation states) replaced by plain built-in actuators that move the pans as the rig's did: a
motor replaying the forces the hydraulic actuators applied (explicit Euler), or a stiff position
servo replaying the rig's pan positions (RK4, see :func:`bare_controls`). Stepping the twin
costs what the multibody physics costs, with no callback and no Python between steps.
``benchmarks/step_rate.py`` (the rig's step rate against the twin's) and
``benchmarks/paper_overhead.py`` (``rigsim paper`` against bare stepping) measure with it.
"""

from __future__ import annotations

import importlib
import math

import mujoco
import numpy as np

from rigsim.hydraulics import ActuatorParams, equilibrium_activation
from rigsim.hydraulics.bridge import activation_slice, add_hydraulic_actuators
from rigsim.mjcf.names import CORNERS

__all__ = ["PARAMS", "STATE_SPEC", "INTEGRATIONS", "SERVO_KP", "SERVO_KV", "bare_controls", "quarter_truck_spec",
           "truck_spec", "build_models", "static_loads", "drive_signal", "initial_state"]

#: The hydraulic actuators' parameters (the defaults).
PARAMS = ActuatorParams()
#: The state :func:`initial_state` gives (what ``mujoco.rollout`` starts from).
STATE_SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS
#: Integrations (integrator, step in s): RK4 at 1e-3 s (the road and rig tests',
#: :mod:`rigsim.scenarios.core.rig`), explicit Euler at 1e-4 s; :func:`build_models` sets one on both models.
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
    from rigsim.mjcf.build import build_spec
    from rigsim.mjcf.variant import TruckVariant
    from rigsim.mjcf.physics import static_equilibrium

    variant = TruckVariant(pan_mass_kg=PARAMS.pan_mass_kg)
    model = build_spec(variant).compile()
    data = mujoco.MjData(model)
    qpos = static_equilibrium(model, data)
    spec = build_spec(variant)
    spec.add_key(name="rest", qpos=qpos)
    return spec


def _spec_of(model: str, spec: str | None) -> tuple[mujoco.MjSpec, tuple]:
    if model == "truck" and not spec:
        return truck_spec(), CORNERS
    if spec:
        module, _, func = spec.partition(":")
        made = getattr(importlib.import_module(module), func)()
        corners = tuple(c for c in CORNERS if made.joint(f"pan_{c}_z") is not None)
        return made, corners
    corners = CORNERS if model == "four" else ("fl",)
    return quarter_truck_spec(corners), corners


def _add_force_sensors(spec, corners):
    for c in corners:
        spec.add_sensor(name=f"force_{c}", type=mujoco.mjtSensor.mjSENS_ACTUATORFRC,
                        objtype=mujoco.mjtObj.mjOBJ_ACTUATOR, objname=f"hyd_{c}")


def build_models(model: str = "truck", spec: str | None = None, integration: str = "rk4"):
    """The rig and its bare twin, identical but for the pans' actuators.

    Parameters
    ----------
    model : str
        "truck": the project's truck on the four pans (:func:`truck_spec`); "four" / "single":
        stand-in quarter trucks on four pans / one pan (:func:`quarter_truck_spec`).
    spec : str, optional
        ``package.module:function`` returning an ``mujoco.MjSpec`` with the slide joints
        ``pan_<c>_z`` (and no hydraulic actuators), in place of ``model``; its first keyframe,
        if any, is the static state.
    integration : str
        A key of :data:`INTEGRATIONS`, for both models.

    Returns
    -------
    tuple
        (rig model with one hydraulic user actuator ``hyd_<c>`` per pan, bare model with a
        position servo (RK4) or a motor (Euler) ``hyd_<c>`` per pan, the corners), both with an
        ``actuatorfrc`` sensor ``force_<c>`` per pan.
    """
    spec_rig, corners = _spec_of(model, spec)
    spec_bare, _ = _spec_of(model, spec)
    add_hydraulic_actuators(spec_rig, PARAMS, corners)
    servo = integration == "rk4"
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
    integrator, dt = INTEGRATIONS[integration]
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
    """The full physics state at rest (first keyframe or qpos0); ``hydraulic``: each pan's
    actuator at the equilibrium activation holding ``loads`` (corner -> N, :func:`static_loads`)."""
    data = mujoco.MjData(model)
    if model.nkey:
        mujoco.mj_resetDataKeyframe(model, data, 0)
    if hydraulic:
        for c in corners:
            data.act[activation_slice(model, c)] = equilibrium_activation(PARAMS, loads[c])
    state = np.empty(mujoco.mj_stateSize(model, STATE_SPEC))
    mujoco.mj_getState(model, data, state, STATE_SPEC)
    return state
