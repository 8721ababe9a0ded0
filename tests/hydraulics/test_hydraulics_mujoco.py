"""The hydraulic actuator inside MuJoCo: a single wheelpan on ``pan_fl_z`` with a spring to
ground standing in for the tire, gravity on, explicit Euler at 1e-4 s (the project's step).

Expected values come from statics ((P1 - P2) A = load), Merritt's equations (stall force
(Ps - Pr) A, compliance dP = -beta dV / V), the paper's eq. 4, or definitions (integral action
removes the steady error), never from a previous run.
"""

import math

import mujoco
import numpy as np
import pytest

from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.hydraulics import (ActuatorParams, check_design_station, check_stable, eq4_parameters,
                               equilibrium_activation, events)
from rigsim.hydraulics.bridge import (LayoutError, _find_offsets, _layout, _verify_offsets, activation_slice,
                                      add_hydraulic_actuators, hydraulic_callbacks, params_from_model,
                                      set_activation, single_pan_spec)
from rigsim.hydraulics.model import MPA
from rigsim.hydraulics.params import GRAVITY_M_S2

DEFAULT = ActuatorParams()
TIRE = 1.0e6  # N/m, a soft truck tire (brief: 0.9-1.8 MN/m)
WHEEL = 30.0e3  # N, static wheel load (brief: 15-45 kN)
DT = 1.0e-4


def _rig(params=DEFAULT, *, spring=TIRE, wheel=WHEEL, **kw):
    model = single_pan_spec(params, spring_N_per_m=spring, load_N=wheel, **kw).compile()
    data = mujoco.MjData(model)
    return model, data


def _pan_load(params=DEFAULT, wheel=WHEEL, mass=None):
    return wheel + (params.pan_mass_kg if mass is None else mass) * GRAVITY_M_S2


def _run(model, data, n, fast=True, drive=None):
    """Step n times; returns qpos (n,), act (n, 5), actuator_force (n,)."""
    sl = activation_slice(model, "fl")
    qpos, act, force = np.empty(n), np.empty((n, 5)), np.empty(n)
    with hydraulic_callbacks(model, fast=fast):
        for k in range(n):
            if drive is not None:
                data.ctrl[0] = drive(data.time)
            mujoco.mj_step(model, data)
            qpos[k], act[k], force[k] = data.qpos[0], data.act[sl], data.actuator_force[0]
    return qpos, act, force


def _at_rest(params=DEFAULT, wheel=WHEEL, **kw):
    model, data = _rig(params, wheel=wheel, **kw)
    set_activation(model, data, "fl", equilibrium_activation(params, _pan_load(params, wheel, kw.get("pan_mass_kg"))))
    return model, data


# --- model construction ------------------------------------------------------------------------
def test_actuator_layout_in_the_compiled_model():
    model, _ = _rig()
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, "hyd_fl")
    assert model.actuator_dyntype[i] == mujoco.mjtDyn.mjDYN_USER
    assert model.actuator_gaintype[i] == mujoco.mjtGain.mjGAIN_USER
    assert model.actuator_biastype[i] == mujoco.mjtBias.mjBIAS_USER
    assert model.actuator_actnum[i] == 5 and model.na == 5
    assert model.jnt_qposadr[model.actuator_trnid[i, 0]] == 0
    assert params_from_model(model, "fl") == DEFAULT


def test_add_hydraulic_actuators_checks_its_inputs():
    spec = single_pan_spec(DEFAULT)
    with pytest.raises(ValueError, match="no joint 'pan_fr_z'"):
        add_hydraulic_actuators(spec, DEFAULT, corners=("fr",))
    with pytest.raises(ValueError, match="corner"):
        add_hydraulic_actuators(spec, {"fr": DEFAULT}, corners=("fl",))


# --- statics ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("fast", [True, False])
def test_rest_pressures_carry_the_load_and_stay_put(fast):
    model, data = _at_rest()
    load = _pan_load()
    a0 = data.act.copy()
    assert (a0[2] - a0[3]) * MPA * DEFAULT.piston_area_m2 == pytest.approx(load, rel=5e-3)
    qpos, act, force = _run(model, data, 10_000, fast=fast)  # 1 s
    assert force[0] == pytest.approx(load, rel=5e-3)
    assert np.max(np.abs(qpos)) < 1e-7  # m
    assert np.max(np.abs(act[:, 2:4] - a0[2:4])) < 1e-6  # MPa
    assert np.max(np.abs(act[:, 0] - a0[0])) < 1e-6


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_stall_force_of_a_blocked_pan_with_the_valve_wide_open(direction):
    # Pan blocked by a huge mass (1e9 kg, no gravity); a 50 mm position error opens the valve to
    # its limit: P1 -> Ps, P2 -> Pr (or the reverse), force -> (Ps - Pr) A (Merritt's stall force).
    model, data = _rig(spring=0.0, wheel=0.0, pan_mass_kg=1e9, gravity=False)
    set_activation(model, data, "fl", equilibrium_activation(DEFAULT, 0.0))
    qpos, act, force = _run(model, data, 3000, drive=lambda t: direction * 0.05)
    stall = (DEFAULT.supply_pressure_Pa - DEFAULT.return_pressure_Pa) * DEFAULT.piston_area_m2
    assert direction * force[-1] == pytest.approx(stall, rel=0.02)
    assert np.max(np.abs(qpos)) < 1e-5
    assert events(act[-1], DEFAULT)["spool_saturation"]


@pytest.mark.parametrize("fast", [True, False])
def test_continuity_valve_closed_no_leakage(fast):
    # Merritt ch. 2 with the valve closed and no leakage: dP1 = -beta A dx / V1, so
    # P1 - P10 = -beta ln(V1(x)/V1(0)) exactly and ~ -beta (A dx) / V0 for small dx.
    p = DEFAULT.replace(null_opening=0.0, leakage_m3_s_Pa=0.0, kp_per_m=0.0, kdp_per_Pa=0.0)
    model, data = _rig(p, spring=0.0, wheel=0.0, pan_mass_kg=1e9, gravity=False)
    set_activation(model, data, "fl", [0.0, 0.0, 10.0, 10.0, 0.0])
    data.qvel[0] = 0.01  # m/s: 0.5 mm in 0.05 s, nearly constant (1e9 kg)
    qpos, act, _ = _run(model, data, 500, fast=fast)
    # Euler: act_(k+1) = act_k + dt f(q_k, v_k) and q_(k+1) = q_k + dt v_(k+1); with v constant
    # both have advanced by (k+1) dt v, so act[-1] pairs with qpos[-1].
    dx = qpos[-1]
    v0, beta, area = p.mid_volume_m3, p.bulk_modulus_Pa, p.piston_area_m2
    dp1 = (act[-1, 2] - 10.0) * MPA
    dp2 = (act[-1, 3] - 10.0) * MPA
    assert dp1 == pytest.approx(-beta * math.log((v0 + area * dx) / v0), rel=1e-4)
    assert dp2 == pytest.approx(-beta * math.log((v0 - area * dx) / v0), rel=1e-4)
    assert -dp1 == pytest.approx(beta * area * dx / v0, rel=2 * area * dx / v0)
    assert np.all(act[:, 0] == 0.0)


# --- closed loop ---------------------------------------------------------------------------------
def test_small_step_settles_on_the_reference_within_stroke():
    # Integral action (Ti = 1 s): the steady position error of a 1 mm step is zero.
    model, data = _at_rest()
    qpos, act, _ = _run(model, data, 30_000, drive=lambda t: 1e-3)  # 3 s
    assert np.max(np.abs(qpos)) < DEFAULT.half_stroke_m
    assert qpos[-1] == pytest.approx(1e-3, abs=1e-5)  # within 1 % of the step
    assert abs(np.mean(qpos[-1000:]) - 1e-3) < 1e-5
    assert np.max(qpos) < 1.5e-3  # bounded overshoot
    assert not np.any(events(act, DEFAULT)["cavitation"])


def test_fast_and_reference_paths_agree_over_one_second():
    drive = lambda t: 2e-3 * math.sin(2 * math.pi * 7.0 * t) + (1e-3 if t > 0.2 else 0.0)  # noqa: E731
    runs = []
    for fast in (True, False):
        model, data = _at_rest()
        runs.append(_run(model, data, 10_000, fast=fast, drive=drive))
    (q_f, a_f, f_f), (q_r, a_r, f_r) = runs
    assert np.max(np.abs(q_f - q_r)) <= 1e-9 * np.max(np.abs(q_r))
    scale = np.max(np.abs(a_r), axis=0)
    assert np.all(np.max(np.abs(a_f - a_r), axis=0) <= 1e-9 * scale)
    assert np.max(np.abs(f_f - f_r)) <= 1e-9 * np.max(np.abs(f_r))
    assert np.ptp(q_r) > 3e-3  # the run really moved the pan


# --- callback hygiene ----------------------------------------------------------------------------
def _installed():
    return (mujoco.get_mjcb_act_dyn(), mujoco.get_mjcb_act_gain(), mujoco.get_mjcb_act_bias())


@pytest.mark.parametrize("fast", [True, False])
def test_callbacks_removed_after_the_block_and_on_error(fast):
    model, data = _at_rest()
    assert _installed() == (None, None, None)
    with hydraulic_callbacks(model, fast=fast):
        assert all(cb is not None for cb in _installed())
        with pytest.raises(RuntimeError, match="already installed"):
            with hydraulic_callbacks(model, fast=fast):
                pass  # pragma: no cover
        assert all(cb is not None for cb in _installed())
    assert _installed() == (None, None, None)
    with pytest.raises(ZeroDivisionError):
        with hydraulic_callbacks(model, fast=fast):
            mujoco.mj_step(model, data)
            1 / 0
    assert _installed() == (None, None, None)


def test_two_runs_in_one_process_are_bit_identical():
    drive = lambda t: 1e-3 * math.sin(2 * math.pi * 11.0 * t)  # noqa: E731
    runs = []
    for _ in range(2):
        model, data = _at_rest()
        runs.append(_run(model, data, 5000, drive=drive))
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


def test_model_without_hydraulics_is_refused():
    model = mujoco.MjModel.from_xml_string(
        "<mujoco><worldbody><body><joint name='j' type='slide'/><geom size='.1' mass='1'/></body>"
        "</worldbody><actuator><motor joint='j'/></actuator></mujoco>")
    with pytest.raises(ValueError, match="no hydraulic actuator"):
        with hydraulic_callbacks(model):
            pass  # pragma: no cover
    assert _installed() == (None, None, None)


def test_compiled_callbacks_ignore_foreign_user_actuators():
    # Callbacks are process-global: a model stepped in the block whose user actuator does not
    # carry a packed row must be left alone (act_dot 0, force 0), not crash.
    foreign = mujoco.MjModel.from_xml_string(
        "<mujoco><option timestep='1e-4'/><worldbody><body><joint name='j' type='slide'/>"
        "<geom size='.1' mass='1'/></body></worldbody><actuator><general joint='j' dyntype='user' "
        "gaintype='user' biastype='user' actdim='5'/></actuator></mujoco>")
    fd = mujoco.MjData(foreign)
    fd.act[:] = [1, 2, 3, 4, 5]
    model, _ = _at_rest()
    with hydraulic_callbacks(model, fast=True):
        mujoco.mj_step(foreign, fd, 10)
    assert np.array_equal(fd.act, [1, 2, 3, 4, 5]) and fd.actuator_force[0] == 0.0


def test_layout_check_rejects_wrong_offsets():
    model, data = _at_rest()
    good = _find_offsets(model, data)
    m_off, _, _ = _layout(mujoco.introspect.structs.STRUCTS["mjModel"].fields)
    d_off, _, _ = _layout(mujoco.introspect.structs.STRUCTS["mjData"].fields)
    shifted = dict(d_off, act=d_off["act"] + 8)
    with pytest.raises(LayoutError, match="fast=False"):
        _verify_offsets(good, m_off, shifted, model, data)


# --- stability and linearization ---------------------------------------------------------------
def _transition_matrices(params, *, static_load=True, spring=TIRE):
    """mjd_transitionFD (centred, eps 1e-6) at the static rest point of the single-pan rig."""
    wheel = WHEEL if static_load else -params.pan_mass_kg * GRAVITY_M_S2  # spring holds the pan
    model, data = _rig(params, spring=spring, wheel=wheel)
    set_activation(model, data, "fl", equilibrium_activation(params, _pan_load(params, wheel)))
    nx = 2 * model.nv + model.na
    a = np.zeros((nx, nx))
    b = np.zeros((nx, model.nu))
    with hydraulic_callbacks(model, fast=True):
        mujoco.mj_forward(model, data)
        mujoco.mjd_transitionFD(model, data, 1e-6, 1, a, b, None, None)
    return model, a, b


def test_default_loop_is_stable_in_the_discrete_model():
    _, a, _ = _transition_matrices(DEFAULT)
    assert np.max(np.abs(np.linalg.eigvals(a))) < 1.0


@pytest.mark.parametrize("change, field", [
    ({"kdp_per_Pa": 0.0}, "kdp_per_Pa"),  # no differential-pressure feedback
    ({"spool_hz": 40.0}, "spool_hz"),      # valve well below the ~110 Hz oil-column mode
])
def test_unstable_parameter_sets_are_refused_and_really_unstable(change, field):
    p = DEFAULT.replace(**change)  # plain data: construction checks values, not the loop
    with pytest.raises(ValueError, match=field):
        check_design_station(p)  # what the rig builder runs (stability on the design station)
    with pytest.raises(ValueError, match="unstable"):
        check_stable(p, TIRE, 450.0, gain_margin=1.0)
    _, a, _ = _transition_matrices(p)
    assert np.max(np.abs(np.linalg.eigvals(a))) > 1.0  # MuJoCo's own linearization agrees


def test_transition_fd_reproduces_eq4():
    # mjd_transitionFD of the rig (static valve, Ti = 1 s, tire to ground, unloaded so the valve
    # sits at null) converted to continuous time must give the paper's eq. 4 frequency response.
    # Euler: v' = v + dt a(x), act' = act + dt f(x), so the v and act rows of A and B are
    # I + dt * (continuous Jacobian) exactly; q' = q + dt v' gives dq/dt = v.
    p = DEFAULT.replace(spool_hz=math.inf)
    model, a, b = _transition_matrices(p, static_load=False)
    nv, nx = model.nv, a.shape[0]
    ac = np.zeros_like(a)
    ac[:nv, nv:2 * nv] = np.eye(nv)
    ac[nv:] = (a[nv:] - np.eye(nx)[nv:]) / DT
    bc = np.zeros_like(b)
    bc[nv:] = b[nv:] / DT
    num, den = eq4_coefficients_from(**eq4_parameters(p, TIRE))
    hz = np.geomspace(0.1, 200.0, 30)
    h = np.array([np.linalg.solve(2j * np.pi * f * np.eye(nx) - ac, bc)[0, 0] for f in hz])
    s = 2j * np.pi * hz
    h4 = np.polyval(num, s) / np.polyval(den, s)
    assert np.max(np.abs(h / h4 - 1.0)) < 1e-6


def test_python_loop_linearization_matches_mujoco():
    # rigsim.hydraulics.loop (central differences of the reference equations, MuJoCo's Euler map built
    # by hand) and mjd_transitionFD of the compiled rig must have the same discrete eigenvalues:
    # pins the loop model used by check_stable to what MuJoCo integrates.
    from rigsim.hydraulics.loop import euler_map, loop_matrices

    model, a_fd, _ = _transition_matrices(DEFAULT)
    a, _, _, names = loop_matrices(DEFAULT, TIRE, math.inf, load_N=_pan_load())
    ev_fd = np.sort_complex(np.linalg.eigvals(a_fd))
    ev_py = np.sort_complex(np.linalg.eigvals(euler_map(a, names, DT)))
    assert ev_fd.shape == ev_py.shape == (7,)
    assert np.max(np.abs(ev_fd - ev_py)) < 1e-6
