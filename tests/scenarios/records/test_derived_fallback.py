"""The derived fallback (scenarios.records.model.fallback): the hybrid weighed against the linear
correction on the model's own runs, checked on signals whose figures are known in closed form.

L is a pure gain g here (a linear correction of the actuators' amplitude loss alone) and every signal
lies far below the band limit B (30 Hz), where B passes it whole: then E[M] = g F_model(x_a) -
F_model(x_ref) and (L - B) r = (g - 1) r exactly."""

import numpy as np
import pytest

from scenarios.records.model.fallback import DLC_GOAL, hybrid_outlook

FS = 1000.0
T = np.arange(20_000) / FS
ROWS = T >= 2.0  # past the band limit's transients
ROAD = 40e3 + 10e3 * np.sin(2 * np.pi * 2.0 * T)[:, None] * np.ones(4)  # F_model(x_ref): 7.07 kN rms, DLC 0.177


def _gain(g):
    """L: a gain g on the signal's dynamic part, its mean kept (T_a(0) = 1)."""
    def linear(f):
        f = np.asarray(f, dtype=float)
        return f.mean(axis=0) + g * (f - f.mean(axis=0)), np.ones(len(f), bool)
    return linear


def _outlook(lag, g, residual_amp):
    f_a = 40e3 + lag * (ROAD - 40e3)  # the pans' amplitude loss seen by the model
    r = residual_amp * np.sin(2 * np.pi * 5.0 * T)[:, None] * np.ones(4)
    hybrid = ROAD + _gain(g)(r)[0]
    return hybrid_outlook(ROAD, f_a, r, hybrid, _gain(g), FS, ROWS)


def test_a_linear_correction_exact_on_the_model_leaves_the_model_nothing_to_add():
    # lag 0.8, L = 1 / 0.8: E[M] = 0, so no residual can make the hybrid the better one
    out = _outlook(0.8, 1.25, 500.0)
    assert out.linear_error == pytest.approx(np.zeros(4), abs=2e-3)
    assert not out.holds.any()
    assert "corrected linearly" in out.reason() and out.reason().count("fl (") == 1


def test_a_residual_that_l_does_not_move_keeps_the_hybrid():
    # L = 1 (no correction): E[M] = -0.2 F_dyn, linear error 0.2; (L - B) r = 0
    out = _outlook(0.8, 1.0, 5000.0)
    assert out.linear_error == pytest.approx(np.full(4, 0.2), rel=0.01)
    assert out.hybrid_bound == pytest.approx(np.zeros(4), abs=1e-3)
    assert out.holds.all() and out.reason() == ""


@pytest.mark.parametrize("amp, kept", [(500.0, True), (5000.0, False)])
def test_the_hybrid_is_kept_while_twice_its_bound_is_below_the_linear_error(amp, kept):
    # lag 0.9, L = 1.25: E[M] = 0.125 F_dyn (linear error 0.125); (L - B) r = 0.25 r: a 500 N sine
    # (354 N rms) bounds the hybrid at 0.0125, a 5 kN one at 0.125 = the linear error (not kept)
    out = _outlook(0.9, 1.25, amp)
    assert out.linear_error == pytest.approx(np.full(4, 0.125), rel=0.01)
    assert out.hybrid_bound == pytest.approx(np.full(4, 0.25 * amp / np.sqrt(2) / (10e3 / np.sqrt(2))), rel=0.01)
    assert out.holds.all() == kept
    # the DLC guard: the residual's 5 Hz part moved by L changes the hybrid's DLC by at most the bound's share
    assert np.all(out.hybrid_dlc_bound <= out.hybrid_bound * 10e3 / np.sqrt(2) / 40e3 + 1e-9)
    assert out.to_dict()["rr"]["model"] == kept


def test_the_dlc_guard_refuses_a_wheel_whose_dlc_the_residual_moves_past_the_goal():
    # lag 0.5 (linear error 0.375) and a 6 kN residual: NRMSE bound 0.15, 2 x 0.15 < 0.375 passes; the
    # residual moved by L (1.5 kN at 5 Hz) moves the hybrid's DLC past the 1 % goal, and the wheel is
    # kept only where that is within the linear correction's own DLC error on the model truck
    out = _outlook(0.5, 1.25, 6000.0)
    assert (2 * out.hybrid_bound < out.linear_error).all()
    assert out.hybrid_dlc_bound[0] > DLC_GOAL
    assert out.holds.all() == bool(out.hybrid_dlc_bound[0] <= abs(out.linear_dlc_error[0]))


def test_a_residual_linear_in_the_pans_motion_commutes_with_l_and_costs_nothing():
    # The 5 kN residual that refuses the hybrid above (lag 0.9, L = 1.25) is here a filter of the pans'
    # motion (a 5 Hz motion, the residual its delayed copy): L moves the force and the motion alike, so
    # the part linear in the motion is taken out before weighing and the hybrid is kept.
    pans = 2e-3 * np.sin(2 * np.pi * 5.0 * T - 0.4)[:, None] * np.ones(4)
    f_a = 40e3 + 0.9 * (ROAD - 40e3)
    r = 5000.0 * np.sin(2 * np.pi * 5.0 * T)[:, None] * np.ones(4)
    hybrid = ROAD + _gain(1.25)(r)[0]
    worst = hybrid_outlook(ROAD, f_a, r, hybrid, _gain(1.25), FS, ROWS)
    out = hybrid_outlook(ROAD, f_a, r, hybrid, _gain(1.25), FS, ROWS, pans_m=pans)
    assert not worst.holds.any() and out.holds.all()
    assert np.all(out.hybrid_bound < 0.02 * worst.hybrid_bound)


def test_the_linear_part_of_a_filtered_pan_motion_is_found_to_the_noise():
    # A residual that is a first-order filter of one pan plus a gain on another, over 50 N of white noise:
    # in the 30 Hz band what is left is the noise's band-limited share (11 N) within 30 %.
    from scipy import signal

    from scenarios.records.model.fallback import linear_part

    rng = np.random.default_rng(0)
    x = signal.sosfilt(signal.butter(2, 20.0, fs=FS, output="sos"), rng.normal(size=(30_000, 4)), axis=0)
    y = 1e3 * signal.lfilter([0.5, 0.3], [1.0, -0.9], x[:, 0])[:, None] + 200.0 * x[:, [1]]
    noise = rng.normal(scale=50.0, size=(30_000, 1))
    left = y + noise - linear_part(y + noise, x, FS)
    band = signal.butter(4, 30.0, fs=FS, output="sos")
    inner = slice(2000, -2000)
    got = signal.sosfiltfilt(band, left[:, 0])[inner].std()
    expect = signal.sosfiltfilt(band, noise[:, 0])[inner].std()
    assert got == pytest.approx(expect, rel=0.3)
