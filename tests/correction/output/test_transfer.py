"""rigsim.correction.output.transfer: the paper's eq. 4 and the frequency-response helpers.

Expected values come from eq. 4 as printed (b0 = b1 = a0: static gain 1, zero at -1 rad/s),
from rigsim.correction.output.eq4.eq4_coefficients_from (which eq4_transfer_function wraps), from
closed-form first/second-order systems, or from python-control's own evaluation and ZOH
discretization -- never from a previous run of this module.
"""

import math

import control
import numpy as np
import pytest

from rigsim.correction.output.transfer import (apply_transfer_function, bandwidth_hz, describe_roots,
                                 eq4_transfer_function, frequency_response_hz,
                                 state_space_frequency_response, transfer_bandwidth_hz)
from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.hydraulics import ActuatorParams, eq4_parameters

DEFAULT = ActuatorParams()


def _eq4_args(params=DEFAULT, kt=1.0e6, load=0.0):
    args = eq4_parameters(params, kt, load)
    del args["ti_s"]  # the printed Ti = 1 s by default; tests pass their own
    return args


def _random_args(rng):
    """Valid parameters spread over decades around a servo-hydraulic actuator's."""
    lu = lambda lo, hi: float(10 ** rng.uniform(math.log10(lo), math.log10(hi)))  # noqa: E731
    return dict(ksv=lu(0.1, 10), kq_m3_s=lu(1e-4, 1e-1), kc_m3_s_Pa=lu(1e-14, 1e-9), kp_per_m=lu(1, 1e3),
                kdp_per_Pa=lu(1e-10, 1e-6), piston_area_m2=lu(1e-4, 1e-1), fluid_volume_m3=lu(1e-5, 1e-1),
                bulk_modulus_Pa=lu(1e8, 2e9), mass_kg=lu(1, 5e3), damping_N_s_m=lu(1e-1, 1e5),
                tire_N_per_m=lu(1e4, 1e8))


def test_eq4_static_gain_one_and_zero_at_minus_one_for_any_valid_parameters():
    # Eq. 4 as printed: b0 = b1 = a0, so T_a(0) = b0/a0 = 1 and the zero is -b0/b1 = -1 rad/s.
    rng = np.random.default_rng(4)
    for _ in range(300):
        args = _random_args(rng)
        tf = eq4_transfer_function(**args)
        assert float(np.real(tf.dcgain())) == pytest.approx(1.0, rel=1e-12), args
        zeros = tf.zeros()
        assert zeros.shape == (1,) and zeros[0] == pytest.approx(-1.0, rel=1e-12), args
        assert len(tf.poles()) == 4


@pytest.mark.parametrize("ti_s", [0.25, 0.3, 2.0])  # 0.3 s: 1/Ti not a whole number (a 1 // Ti survived 0.25)
def test_eq4_zero_follows_the_integral_time(ti_s):
    # The general PI loop Kp (1 + 1/(Ti s)) puts the zero at -1/Ti and keeps the static gain 1.
    tf = eq4_transfer_function(**_eq4_args(), ti_s=ti_s)
    assert tf.zeros()[0] == pytest.approx(-1.0 / ti_s, rel=1e-12)
    assert float(np.real(tf.dcgain())) == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("kt, load", [(0.9e6, 0.0), (1.8e6, 34.5e3)])
def test_eq4_transfer_function_wraps_the_one_formula(kt, load):
    # eq4_transfer_function is control.tf of eq4_coefficients_from (no second copy), with unit
    # static gain for the hydraulics package's parameters at any linearization point.
    args = eq4_parameters(DEFAULT, kt, load)
    num, den = eq4_coefficients_from(**args)
    tf = eq4_transfer_function(**args)
    assert np.array_equal(np.ravel(tf.num[0][0]), num)
    assert np.array_equal(np.ravel(tf.den[0][0]), den)
    assert float(np.real(tf.dcgain())) == pytest.approx(1.0, rel=1e-12)


def test_eq4_p_only_cancels_the_root_at_zero():
    # ti_s = inf: b0 = a0 = 0; the transfer function drops the common root at s = 0 and keeps
    # the P loop's static error against the tire spring: T_a(0) = b1 / a1 = K / (K + Kc' kt / Ap^2).
    args = _eq4_args()
    tf = eq4_transfer_function(**args, ti_s=math.inf)
    assert len(tf.poles()) == 3 and tf.zeros().size == 0
    k = args["ksv"] * args["kq_m3_s"] * args["kp_per_m"] / args["piston_area_m2"]
    kc = args["kc_m3_s_Pa"] + args["kdp_per_Pa"] * args["ksv"] * args["kq_m3_s"]
    expected = k / (k + kc * args["tire_N_per_m"] / args["piston_area_m2"] ** 2)
    assert float(np.real(tf.dcgain())) == pytest.approx(expected, rel=1e-12)


def test_eq4_accepts_a_zero_tire_stiffness():
    # One rule for kt (eq4_coefficients_from): >= 0; a pan without a tire is still eq. 4.
    tf = eq4_transfer_function(**{**_eq4_args(), "tire_N_per_m": 0.0})
    assert float(np.real(tf.dcgain())) == pytest.approx(1.0, rel=1e-12)


def test_eq4_coefficients_by_hand():
    # One parameter set, the printed formulas written out.
    a = dict(ksv=2.0, kq_m3_s=0.01, kc_m3_s_Pa=1e-11, kp_per_m=50.0, kdp_per_Pa=2e-8,
             piston_area_m2=0.005, fluid_volume_m3=0.002, bulk_modulus_Pa=1e9, mass_kg=400.0,
             damping_N_s_m=3000.0, tire_N_per_m=1.2e6)
    k = 2.0 * 0.01 * 50.0 / 0.005  # Ksv Kq Ke = 200 1/s
    kc = 1e-11 + 2e-8 * 2.0 * 0.01
    c = 0.002 / (4 * 1e9 * 0.005 ** 2)
    den = [c * 400, kc * 400 / 0.005 ** 2 + c * 3000, kc * 3000 / 0.005 ** 2 + c * 1.2e6 + 1,
           k + kc * 1.2e6 / 0.005 ** 2, k]
    tf = eq4_transfer_function(**a)
    assert np.allclose(np.ravel(tf.num[0][0]), [k, k], rtol=1e-14)
    assert np.allclose(np.ravel(tf.den[0][0]), den, rtol=1e-14)


@pytest.mark.parametrize("name, value", [("mass_kg", -1.0), ("tire_N_per_m", -1.0), ("kc_m3_s_Pa", -1e-12),
                                         ("bulk_modulus_Pa", math.nan), ("kq_m3_s", math.inf),
                                         ("tire_N_per_m", math.inf),  # only ti_s may be infinite (P only)
                                         ("ksv", True)])
def test_eq4_refuses_invalid_parameters(name, value):
    args = _eq4_args()
    args[name] = value
    with pytest.raises(ValueError, match=name):
        eq4_transfer_function(**args)


def test_state_space_response_matches_python_control_continuous_and_discrete():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(5, 5)) - 4 * np.eye(5)
    b = rng.normal(size=(5, 2))
    c = rng.normal(size=(3, 5))
    f = np.array([0.01, 0.3, 2.0, 40.0])
    h = state_space_frequency_response(a, b, c, f)
    ref = frequency_response_hz(control.ss(a, b, c, 0), f)
    assert h.shape == (4, 3, 2) and np.allclose(h, ref, rtol=1e-12)
    dt = 1e-3
    ad = np.eye(5) + dt * a
    hd = state_space_frequency_response(ad, b, c, f, dt_s=dt)
    refd = frequency_response_hz(control.ss(ad, b, c, 0, dt), f)
    assert np.allclose(hd, refd, rtol=1e-12)
    # definition: C (z I - A)^-1 B at z = exp(j 2 pi f dt)
    z = np.exp(2j * np.pi * f[1] * dt)
    assert np.allclose(hd[1], c @ np.linalg.solve(z * np.eye(5) - ad, b), rtol=1e-12)


def test_bandwidth_of_a_first_order_lag():
    # |1 / (1 + j f/fc)| = 10^(-3/20) at f = fc sqrt(10^0.3 - 1) (-3 dB; -3.01 dB is fc).
    fc = 12.0
    expected = fc * math.sqrt(10 ** 0.3 - 1)
    sys = control.tf([1], [1 / (2 * math.pi * fc), 1])
    assert transfer_bandwidth_hz(sys) == pytest.approx(expected, rel=1e-8)
    f = np.geomspace(0.1, 100, 2000)
    assert bandwidth_hz(f, frequency_response_hz(sys, f)) == pytest.approx(expected, rel=1e-4)
    assert math.isnan(bandwidth_hz(f, np.ones_like(f)))


def test_describe_roots_of_a_known_pair():
    wn, zeta = 2 * math.pi * 10.0, 0.2
    sys = control.tf([wn ** 2], [1, 2 * zeta * wn, wn ** 2])
    (r,) = describe_roots(sys.poles())
    assert r["frequency_hz"] == pytest.approx(10.0, rel=1e-12)
    assert r["damping_ratio"] == pytest.approx(0.2, rel=1e-12)
    dt = 1e-3
    (rd,) = describe_roots(np.exp(sys.poles() * dt), dt_s=dt)
    assert rd["frequency_hz"] == pytest.approx(10.0, rel=1e-9)


def test_apply_transfer_function_is_the_exact_zoh_discretization():
    # Reference: python-control's ZOH discretization of the same system, stepped by forced_response.
    sys = control.tf([50.0, 200.0], [1.0, 30.0, 4000.0]) * control.tf([80.0], [1.0, 80.0])
    dt = 1e-3
    rng = np.random.default_rng(2)
    u = rng.normal(size=3000)
    y = apply_transfer_function(sys, u, dt)
    sysd = control.sample_system(control.ss(sys), dt, "zoh")
    yd = control.forced_response(sysd, U=u).outputs
    assert np.max(np.abs(y - yd)) <= 1e-9 * np.max(np.abs(yd))
    # derivative: s T(s) through the same discretization
    dsys = control.tf([1.0, 0.0], [1.0]) * sys
    dd = control.forced_response(control.sample_system(control.ss(dsys), dt, "zoh"), U=u).outputs
    yv = apply_transfer_function(sys, u, dt, derivative=True)
    assert np.max(np.abs(yv - dd)) <= 1e-9 * np.max(np.abs(dd))
    # columns are filtered independently
    y2 = apply_transfer_function(sys, np.column_stack([u, 2 * u]), dt)
    assert np.allclose(y2[:, 1], 2 * y, rtol=1e-12, atol=0)


def test_apply_transfer_function_refuses_what_it_cannot_filter():
    with pytest.raises(ValueError, match="continuous"):
        apply_transfer_function(control.tf([1], [1, 0.5], 0.1), np.zeros(5), 0.1)
    with pytest.raises(ValueError, match="improper"):
        apply_transfer_function(control.tf([1, 0], [1]), np.zeros(5), 0.1)
    with pytest.raises(ValueError, match="distinct"):
        apply_transfer_function(control.tf([1], [1, 2, 1]), np.zeros(5), 0.1)
