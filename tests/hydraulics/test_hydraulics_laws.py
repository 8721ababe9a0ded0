"""One named test per law of the actuator equations (hydraulics/model.py), each against a hand
computation written here from first principles, each law isolated by the parameters or the state.

References (Merritt, *Hydraulic Control Systems*, Wiley 1967):

- orifice flow through a metering land, ch. 2 and 5: ``Q = Cd w x sqrt(2 dp / rho)``, i.e.
  ``Q = kv x sqrt(dp)`` for a normalised opening ``x``; the rating fixes ``kv``: the rated flow
  passes two lands in series at the rated valve drop, each land dropping half of it, so
  ``kv = Q_rated / sqrt(dp_rated / 2)``;
- the four-way valve, ch. 5: a positive spool connects supply to chamber 1 (``Ps - P1`` drives
  oil in) and chamber 2 to the tank (``P2 - Pr`` drives oil out); a negative spool the reverse;
- chamber continuity, ch. 2 (the continuity equation of a control volume): ``dP/dt = beta / V (sum Q_in - dV/dt)``
  with ``V1 = V_dead + A (L/2 + x)`` and ``V2 = V_dead + A (L/2 - x)``, so the piston takes
  ``A v`` from chamber 1 and gives ``A v`` to chamber 2 when it moves up at ``v``;
- cross-piston (internal) leakage, ch. 5: laminar, ``Q_l = C_ip (P1 - P2)`` from chamber 1 to 2;
- the relief and the cavitation floor, and the valve, controller and spool, as the parameters'
  docstrings (hydraulics/params.py) define them.

No module-level object is built (nothing here can break collection): every test builds its own
parameters, so a wrong law fails the test named after it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigsim.hydraulics import ActuatorParams, actuator_derivatives, actuator_force, pack
from rigsim.hydraulics.model import (bulk_factor, chamber_flows, land_openings, orifice_root, orifice_root_slope,
                                     smooth_opening, smooth_opening_slope, soft_clip, soft_clip_slope)

MPA = 1e6  # Pa per MPa (the states hold pressures in MPa: hydraulics/params.py STATE_NAMES)


def _ideal(**changes) -> ActuatorParams:
    """Critically lapped valve (no null flow), no leakage, no relief flow, no controller: every
    flow term off unless a test turns it on."""
    base = dict(null_opening=0.0, leakage_m3_s_Pa=0.0, relief_conductance_m3_s_Pa=0.0,
                kp_per_m=0.0, kdp_per_Pa=0.0, friction_N_s_m=0.0)
    base.update(changes)
    return ActuatorParams().replace(**base)


def _kv(p: ActuatorParams) -> float:
    """Land coefficient from the rating (two lands in series, each dropping half the rated drop)."""
    return p.rated_flow_m3_s / math.sqrt(p.rated_valve_drop_Pa / 2.0)


def _volumes(p: ActuatorParams, xa: float) -> tuple[float, float]:
    half = p.stroke_m / 2.0
    return p.dead_volume_m3 + p.piston_area_m2 * max(half + xa, 0.0), \
        p.dead_volume_m3 + p.piston_area_m2 * max(half - xa, 0.0)


def _dp_dt(p, spool, p1_Pa, p2_Pa, xa=0.0, va=0.0, xref=0.0, integ=0.0, rate=0.0):
    """(dP1/dt, dP2/dt) in Pa/s and the full derivative vector, from the public function."""
    d = actuator_derivatives(0.0, [spool, rate, p1_Pa / MPA, p2_Pa / MPA, integ], [xref, xa, va], p)
    return d[2] * MPA, d[3] * MPA, d


# --- valve: the four metering-land flows ------------------------------------------------------------
# Drops chosen above laminar_drop_Pa (2 MPa), where the land follows the square-root law exactly.
P1, P2 = 12.0e6, 6.0e6  # Pa


def test_supply_flow_into_chamber_1_is_kv_x_sqrt_ps_minus_p1():
    p = _ideal()
    q1, _ = chamber_flows(0.4, P1, P2, pack(p))
    assert q1 == pytest.approx(_kv(p) * 0.4 * math.sqrt(p.supply_pressure_Pa - P1), rel=1e-13)
    assert q1 > 0  # supply -> chamber 1 (Ps > P1)


def test_return_flow_out_of_chamber_2_is_kv_x_sqrt_p2_minus_pr():
    p = _ideal()
    _, q2 = chamber_flows(0.4, P1, P2, pack(p))
    assert q2 == pytest.approx(-_kv(p) * 0.4 * math.sqrt(P2 - p.return_pressure_Pa), rel=1e-13)
    assert q2 < 0  # chamber 2 -> tank


def test_supply_flow_into_chamber_2_is_kv_x_sqrt_ps_minus_p2():
    p = _ideal()
    _, q2 = chamber_flows(-0.3, P1, P2, pack(p))
    assert q2 == pytest.approx(_kv(p) * 0.3 * math.sqrt(p.supply_pressure_Pa - P2), rel=1e-13)
    assert q2 > 0


def test_return_flow_out_of_chamber_1_is_kv_x_sqrt_p1_minus_pr():
    p = _ideal()
    q1, _ = chamber_flows(-0.3, P1, P2, pack(p))
    assert q1 == pytest.approx(-_kv(p) * 0.3 * math.sqrt(P1 - p.return_pressure_Pa), rel=1e-13)
    assert q1 < 0


def test_valve_flow_reverses_when_the_chamber_is_above_supply():
    # Orifice law with a reversed drop: oil leaves chamber 1 towards the supply port if P1 > Ps.
    p = _ideal()
    p1 = p.supply_pressure_Pa + 3.0e6
    q1, _ = chamber_flows(0.5, p1, P2, pack(p))
    assert q1 == pytest.approx(-_kv(p) * 0.5 * math.sqrt(3.0e6), rel=1e-13)


def test_null_flow_of_the_smoothed_lands():
    # params: each land opens (x + sqrt(x^2 + w^2)) / 2; at x = 0 both lands of a side are w/2 open,
    # so Q1 = kv w/2 (sqrt(Ps - P1) - sqrt(P1 - Pr)) and Q2 likewise (Merritt's null leakage).
    w = 0.02
    p = _ideal(null_opening=w)
    ps, pr = p.supply_pressure_Pa, p.return_pressure_Pa
    q1, q2 = chamber_flows(0.0, 15e6, 5e6, pack(p))
    assert q1 == pytest.approx(_kv(p) * w / 2 * (math.sqrt(ps - 15e6) - math.sqrt(15e6 - pr)), rel=1e-12)
    assert q2 == pytest.approx(_kv(p) * w / 2 * (math.sqrt(ps - 5e6) - math.sqrt(5e6 - pr)), rel=1e-12)


@pytest.mark.parametrize("xv", [0.7, 0.01, 0.0, -0.01, -0.7])
def test_land_openings_follow_the_smoothed_edge_formula(xv):
    w = 0.05
    edge = lambda x: 0.5 * (x + math.sqrt(x * x + w * w))  # noqa: E731 (params docstring)
    a_pos, a_neg = land_openings(xv, w)
    assert a_pos == pytest.approx(edge(xv), rel=1e-12)
    assert a_neg == pytest.approx(edge(-xv), rel=1e-12)
    assert smooth_opening(xv, w) == pytest.approx(edge(xv), rel=1e-12)
    assert smooth_opening(-xv, w) == pytest.approx(edge(-xv), rel=1e-12)
    # slope: the derivative of that formula, 0.5 (1 + x / sqrt(x^2 + w^2))
    assert smooth_opening_slope(xv, w) == pytest.approx(0.5 * (1 + xv / math.sqrt(xv * xv + w * w)), rel=1e-12)


def test_land_openings_keep_their_accuracy_far_from_null():
    # A wide-open land with a narrow null region: (x + sqrt(x^2 + w^2)) / 2 -> x (relative 1e-12), and
    # the closed land w^2 / (2 (r + |x|)) -> w^2 / (4 |x|) (its form without cancellation: the direct
    # (x + r) / 2 with x < 0 loses every digit, as would w^2 / (2 (r - x)) for x > 0).
    w, x = 1e-6, 1.0
    closed = 0.5 * w * w / (math.sqrt(x * x + w * w) + x)
    assert smooth_opening(x, w) == pytest.approx(1.0, rel=1e-15)
    assert smooth_opening(-x, w) == pytest.approx(closed, rel=1e-12, abs=0)
    for xv in (x, -x):
        a_pos, a_neg = land_openings(xv, w)
        assert (a_pos, a_neg) == pytest.approx((1.0, closed) if xv > 0 else (closed, 1.0), rel=1e-12, abs=0)


@pytest.mark.parametrize("xv", [0.3, 0.0, -0.3])
def test_sharp_lands_open_on_one_side_only(xv):
    # Critically lapped valve (w = 0): the land opens max(x, 0), its slope is the step (0.5 at 0).
    assert land_openings(xv, 0.0) == (max(xv, 0.0), max(-xv, 0.0))
    assert smooth_opening(xv, 0.0) == max(xv, 0.0)
    assert smooth_opening_slope(xv, 0.0) == {0.3: 1.0, 0.0: 0.5, -0.3: 0.0}[xv]


@pytest.mark.parametrize("dp", [-1.9e6, -0.5e6, 0.0, 0.7e6, 1.5e6])
def test_laminar_core_of_the_orifice_law(dp):
    # model docstring: dp (1.25 - 0.25 (dp/lam)^2) / sqrt(lam) below lam; its slope by differentiation.
    lam = 2e6
    z = dp / lam
    assert orifice_root(dp, lam) == pytest.approx(dp * (1.25 - 0.25 * z * z) / math.sqrt(lam), rel=1e-14, abs=1e-300)
    assert orifice_root_slope(dp, lam) == pytest.approx((1.25 - 0.75 * z * z) / math.sqrt(lam), rel=1e-14)


@pytest.mark.parametrize("dp", [-9e6, -2e6, 3e6])
def test_turbulent_slope_of_the_orifice_law(dp):
    # d sqrt(|dp|) / d dp = 1 / (2 sqrt(|dp|)) on either side.
    assert orifice_root_slope(dp, 2e6) == pytest.approx(0.5 / math.sqrt(abs(dp)), rel=1e-14)


# --- chamber continuity, one term at a time ------------------------------------------------------------
def test_continuity_of_chamber_1_with_valve_inflow():
    # dP1/dt = beta / V1 * Q1, V1 = V_dead + A (L/2 + x): valve open to chamber 1, pan at rest.
    p = _ideal()
    xa = 0.02
    d1, _, _ = _dp_dt(p, 0.4, P1, P2, xa=xa)
    v1, _ = _volumes(p, xa)
    q1 = _kv(p) * 0.4 * math.sqrt(p.supply_pressure_Pa - P1)
    assert d1 == pytest.approx(p.bulk_modulus_Pa / v1 * q1, rel=1e-12)


def test_continuity_of_chamber_2_with_valve_outflow():
    # dP2/dt = beta / V2 * Q2 with Q2 = -kv x sqrt(P2 - Pr) < 0: chamber 2 drains to the tank.
    p = _ideal()
    xa = 0.02
    _, d2, _ = _dp_dt(p, 0.4, P1, P2, xa=xa)
    _, v2 = _volumes(p, xa)
    q2 = -_kv(p) * 0.4 * math.sqrt(P2 - p.return_pressure_Pa)
    assert d2 == pytest.approx(p.bulk_modulus_Pa / v2 * q2, rel=1e-12)


def test_continuity_of_chamber_1_with_piston_displacement():
    # Closed valve, no leakage: dP1/dt = -beta A v / V1 (the piston moving up enlarges chamber 1).
    p = _ideal()
    xa, va = -0.03, 0.2
    d1, _, _ = _dp_dt(p, 0.0, P1, P2, xa=xa, va=va)
    v1, _ = _volumes(p, xa)
    assert d1 == pytest.approx(-p.bulk_modulus_Pa * p.piston_area_m2 * va / v1, rel=1e-12)


def test_continuity_of_chamber_2_with_piston_displacement():
    # Closed valve, no leakage: dP2/dt = +beta A v / V2 (the piston moving up squeezes chamber 2).
    p = _ideal()
    xa, va = -0.03, 0.2
    _, d2, _ = _dp_dt(p, 0.0, P1, P2, xa=xa, va=va)
    _, v2 = _volumes(p, xa)
    assert d2 == pytest.approx(p.bulk_modulus_Pa * p.piston_area_m2 * va / v2, rel=1e-12)


def test_chamber_volume_stops_at_the_dead_volume_beyond_the_stroke():
    # Beyond the end of stroke a chamber keeps its dead volume (V = V_dead + A max(L/2 +- x, 0)).
    p = _ideal()
    xa, va = -(p.stroke_m / 2 + 0.01), 0.1
    d1, d2, _ = _dp_dt(p, 0.0, P1, P2, xa=xa, va=va)
    a, beta = p.piston_area_m2, p.bulk_modulus_Pa
    assert d1 == pytest.approx(-beta * a * va / p.dead_volume_m3, rel=1e-12)
    assert d2 == pytest.approx(beta * a * va / (p.dead_volume_m3 + a * (p.stroke_m + 0.01)), rel=1e-12)


def test_cross_piston_leakage_flows_from_chamber_1_to_chamber_2():
    # Q_l = C (P1 - P2) leaves chamber 1 and enters chamber 2 (Merritt's C_ip); closed valve, at rest:
    # dP1/dt = -beta Q_l / V1, dP2/dt = +beta Q_l / V2, and the oil is conserved: V1 dP1 + V2 dP2 = 0.
    c = 3e-11
    p = _ideal(leakage_m3_s_Pa=c)
    xa = 0.01
    d1, d2, _ = _dp_dt(p, 0.0, P1, P2, xa=xa)
    v1, v2 = _volumes(p, xa)
    ql = c * (P1 - P2)
    assert d1 == pytest.approx(-p.bulk_modulus_Pa * ql / v1, rel=1e-12)
    assert d2 == pytest.approx(p.bulk_modulus_Pa * ql / v2, rel=1e-12)
    assert v1 * d1 + v2 * d2 == pytest.approx(0.0, abs=1e-9 * abs(v1 * d1))


def test_relief_vents_chamber_1_above_its_cracking_pressure():
    # Relief flow C_r (P - P_relief) out of the chamber above the cracking pressure, none below.
    cr = 2e-9
    p = _ideal(relief_conductance_m3_s_Pa=cr)
    p1 = p.relief_pressure_Pa + 1.5e6
    d1, d2, _ = _dp_dt(p, 0.0, p1, P2)
    v1, v2 = _volumes(p, 0.0)
    assert d1 == pytest.approx(-p.bulk_modulus_Pa * cr * 1.5e6 / v1, rel=1e-12)
    assert d2 == 0.0  # chamber 2 below its cracking pressure: no relief flow


def test_relief_vents_chamber_2_above_its_cracking_pressure():
    cr = 2e-9
    p = _ideal(relief_conductance_m3_s_Pa=cr)
    p2 = p.relief_pressure_Pa + 0.5e6
    d1, d2, _ = _dp_dt(p, 0.0, P1, p2)
    _, v2 = _volumes(p, 0.0)
    assert d2 == pytest.approx(-p.bulk_modulus_Pa * cr * 0.5e6 / v2, rel=1e-12)
    assert d1 == 0.0


def test_relief_is_shut_below_its_cracking_pressure():
    p = _ideal(relief_conductance_m3_s_Pa=2e-9)
    d1, d2, _ = _dp_dt(p, 0.0, p.relief_pressure_Pa - 1e3, p.relief_pressure_Pa - 2e6)
    assert d1 == 0.0 and d2 == 0.0


# --- cavitation: the bulk modulus near the floor ---------------------------------------------------------
def test_bulk_factor_is_one_then_a_smoothstep_then_a_linear_tail():
    # params docstring: 1 above p_cav + band; fmin + (1 - fmin) (3 z^2 - 2 z^3) inside the band;
    # below p_cav a linear fall from fmin to 0 over 1 % of the band; 0 below that floor.
    pc, band, fmin = -0.08e6, 2e6, 0.01
    assert bulk_factor(pc + band, pc, band, fmin) == 1.0
    assert bulk_factor(pc + 5 * band, pc, band, fmin) == 1.0
    for z in (0.1, 0.5, 0.9):
        expected = fmin + (1 - fmin) * (3 * z * z - 2 * z ** 3)
        assert bulk_factor(pc + z * band, pc, band, fmin) == pytest.approx(expected, rel=1e-12)
    assert bulk_factor(pc, pc, band, fmin) == pytest.approx(fmin, rel=1e-12)
    tail = 0.01 * band
    assert bulk_factor(pc - 0.25 * tail, pc, band, fmin) == pytest.approx(0.75 * fmin, rel=1e-9)
    assert bulk_factor(pc - tail, pc, band, fmin) == pytest.approx(0.0, abs=1e-15)
    assert bulk_factor(pc - 1.5 * tail, pc, band, fmin) == 0.0  # never negative below the floor
    assert bulk_factor(pc - 3 * tail, pc, band, fmin) == 0.0


def test_a_cavitated_chamber_refills_at_the_cavitation_stiffness():
    # params (cavitation_min_fraction): a chamber whose net inflow is positive uses at least fmin of
    # beta even below p_cav; one that keeps emptying uses the tail's smaller fraction.
    p = _ideal()
    pc, band, fmin = p.cavitation_pressure_Pa, p.cavitation_band_Pa, p.cavitation_min_fraction
    p1 = pc - 0.5 * 0.01 * band  # halfway down the tail: fraction fmin / 2
    v1, _ = _volumes(p, 0.0)
    beta = p.bulk_modulus_Pa
    d1, _, _ = _dp_dt(p, 0.2, p1, P2)  # valve fills chamber 1
    q1 = _kv(p) * 0.2 * math.sqrt(p.supply_pressure_Pa - p1)
    assert d1 == pytest.approx(fmin * beta * q1 / v1, rel=1e-9)
    va = 0.05  # closed valve, pan rising: chamber 1 keeps emptying
    d1, _, _ = _dp_dt(p, 0.0, p1, P2, va=va)
    assert d1 == pytest.approx(-0.5 * fmin * beta * p.piston_area_m2 * va / v1, rel=1e-9)


def test_chamber_2_sees_its_own_bulk_factor():
    # Chamber 2 in the smoothstep band (z = 0.5), chamber 1 stiff: dP2/dt = beta f(P2) Q2 / V2.
    p = _ideal()
    pc, band, fmin = p.cavitation_pressure_Pa, p.cavitation_band_Pa, p.cavitation_min_fraction
    p2 = pc + 0.5 * band
    va = -0.05  # pan falling, closed valve: chamber 2 expands
    _, d2, _ = _dp_dt(p, 0.0, P1, p2, va=va)
    _, v2 = _volumes(p, 0.0)
    f = fmin + (1 - fmin) * 0.5
    assert d2 == pytest.approx(f * p.bulk_modulus_Pa * p.piston_area_m2 * va / v2, rel=1e-12)


# --- controller, command clip, spool ---------------------------------------------------------------------
def _command(p, xref, xa, integ, p1, p2):
    """Hand-written controller of params: Kp (e + integral / Ti) - Kdp (P1 - P2), times Ksv."""
    inv_ti = 0.0 if math.isinf(p.ti_s) else 1.0 / p.ti_s
    return p.ksv * (p.kp_per_m * ((xref - xa) + integ * inv_ti) - p.kdp_per_Pa * (p1 - p2))


@pytest.mark.parametrize("ti", [0.5, math.inf])
def test_pi_controller_with_pressure_feedback_sets_the_static_valve(ti):
    # Static valve (spool_hz = inf): the states follow the command with a 1 ms lag, so
    # d spool/dt = (cmd - spool) / 1e-3 s and d rate/dt = -rate / 1e-3 s.
    p = ActuatorParams(spool_hz=math.inf, ti_s=ti, ksv=0.9, kp_per_m=40.0, kdp_per_Pa=1e-8)
    xref, xa, integ, spool, rate = 0.004, -0.002, 0.003, 0.05123, 7.3456
    d = actuator_derivatives(0.0, [spool, rate, P1 / MPA, P2 / MPA, integ], [xref, xa, 0.0], p)
    cmd = _command(p, xref, xa, integ, P1, P2)
    assert abs(cmd / p.ksv) < 0.8 * p.command_limit  # linear part of the clip
    assert d[0] == pytest.approx((cmd - spool) / 1e-3, rel=1e-12)
    assert d[1] == pytest.approx(-rate / 1e-3, rel=1e-12)


def test_static_valve_meters_the_command_not_the_spool_state():
    p = _ideal(spool_hz=math.inf, kp_per_m=50.0, ti_s=math.inf)
    xref = 0.006  # cmd = 50 * 0.006 = 0.3 with the pan at 0
    d1, d2, _ = _dp_dt(p, -0.5, P1, P2, xref=xref)
    v1, v2 = _volumes(p, 0.0)
    kv, beta = _kv(p), p.bulk_modulus_Pa
    assert d1 == pytest.approx(beta / v1 * kv * 0.3 * math.sqrt(p.supply_pressure_Pa - P1), rel=1e-12)
    assert d2 == pytest.approx(-beta / v2 * kv * 0.3 * math.sqrt(P2 - p.return_pressure_Pa), rel=1e-12)


def test_spool_is_a_second_order_lag_of_the_command():
    # x'' = wn^2 (cmd - x) - 2 zeta wn x', wn = 2 pi f (servovalve data-sheet model).
    p = ActuatorParams(spool_hz=120.0, spool_damping=0.6, kp_per_m=30.0, kdp_per_Pa=1.5e-8, ti_s=2.0)
    xref, xa, integ, spool, rate = 0.003, 0.001, -0.002, 0.02, 4.0
    d = actuator_derivatives(0.0, [spool, rate, P1 / MPA, P2 / MPA, integ], [xref, xa, 0.0], p)
    wn = 2 * math.pi * 120.0
    cmd = _command(p, xref, xa, integ, P1, P2)
    assert d[0] == rate
    assert d[1] == pytest.approx(wn * wn * (cmd - spool) - 2 * 0.6 * wn * rate, rel=1e-12)


def test_integral_state_integrates_the_position_error():
    p = ActuatorParams()
    d = actuator_derivatives(0.0, [0.0, 0.0, 10.0, 10.0, 0.0], [0.012, -0.005, 0.3], p)
    assert d[4] == pytest.approx(0.012 - (-0.005), rel=1e-15)


@pytest.mark.parametrize("u", [0.9, 1.0, 2.5, -1.3])
def test_command_clip_beyond_the_knee_is_the_exponential_approach(u):
    # params (command_limit): linear to 0.8 L, then L - 0.2 L exp(-(|u| - 0.8 L) / (0.2 L)), odd.
    lim = 1.5
    knee, span = 0.8 * lim, 0.2 * lim
    a = abs(u * lim)
    expected = math.copysign(lim - span * math.exp(-(a - knee) / span), u)
    assert soft_clip(u * lim, lim) == pytest.approx(expected, rel=1e-14)
    assert soft_clip_slope(u * lim, lim) == pytest.approx(math.exp(-(a - knee) / span), rel=1e-14)
    assert soft_clip(0.7 * lim, lim) == 0.7 * lim and soft_clip_slope(-0.7 * lim, lim) == 1.0


def test_force_friction_opposes_the_velocity():
    # F = A (P1 - P2) - b v: at equal pressures only the viscous friction, against the motion.
    p = ActuatorParams(friction_N_s_m=4e3)
    assert actuator_force([0, 0, 8.0, 8.0, 0], 0.25, p) == pytest.approx(-1e3, rel=1e-14)
    assert actuator_force([0, 0, 8.0, 8.0, 0], -0.25, pack(p)) == pytest.approx(1e3, rel=1e-14)


def test_public_functions_refuse_wrong_shapes():
    p = ActuatorParams()
    with pytest.raises(ValueError, match="5 states and u 3 inputs"):
        actuator_derivatives(0.0, np.zeros(4), np.zeros(3), p)
    with pytest.raises(ValueError, match="5 states and u 3 inputs"):
        actuator_derivatives(0.0, np.zeros(5), np.zeros(2), p)
    with pytest.raises(ValueError, match="packed vector of length"):
        actuator_derivatives(0.0, np.zeros(5), np.zeros(3), np.zeros(7))


def test_every_scalar_helper_compiles_with_numba_and_agrees_with_python():
    # model docstring: the scalar kernels are register_jitable so rigsim.hydraulics.kernels compiles the
    # very same source; a helper numba cannot compile would break the compiled path only. Reference:
    # the plain-Python value of each helper at the same arguments.
    from numba import njit

    from rigsim.hydraulics import model

    names = ("smooth_opening", "smooth_opening_slope", "orifice_root", "orifice_root_slope", "soft_clip",
             "soft_clip_slope")
    args = {"smooth_opening": (0.3, 0.02), "smooth_opening_slope": (-0.3, 0.02), "orifice_root": (-1e6, 2e6),
            "orifice_root_slope": (5e6, 2e6), "soft_clip": (0.95, 1.0), "soft_clip_slope": (0.95, 1.0)}
    for name in names:
        fn = getattr(model, name)
        compiled = njit(lambda a, b, fn=fn: fn(a, b))
        assert compiled(*args[name]) == pytest.approx(fn(*args[name]), rel=1e-15), name
    assert njit(lambda: model.land_openings(-0.4, 0.05))() == pytest.approx(land_openings(-0.4, 0.05), rel=1e-15)
    assert njit(lambda: model.bulk_factor(0.5e6, -0.08e6, 2e6, 0.01))() == \
        pytest.approx(bulk_factor(0.5e6, -0.08e6, 2e6, 0.01), rel=1e-15)
