"""A channel skew read as tire damping (rigsim.scenarios.records.model.skew)."""

from types import SimpleNamespace

import numpy as np
import pytest

from rigsim.scenarios.records.model.skew import TIRE_TIME_CONSTANT_S, skew_note, tire_time_constants


def test_a_force_late_by_tau_fits_as_tire_damping_smaller_by_kt_tau():
    # The relation the note rests on, checked on the tire law itself: F = k x + c dx/dt over a pan
    # motion of 0.5-30 Hz (a rig record's band), the force read 0.5 ms late; the least-squares (k, c)
    # of the late force find c - k tau to within 3 % of k tau (first order in omega tau; 0.09 rad at 30 Hz).
    fs, tau, k, c = 10_000.0, 5e-4, 1.0e6, 1725.0
    t = np.arange(int(20 * fs)) / fs
    rng = np.random.default_rng(0)
    freqs = rng.uniform(0.5, 30.0, 40)
    phases = rng.uniform(0, 2 * np.pi, 40)

    def x(time):
        return sum(1e-3 * np.sin(2 * np.pi * f * time + p) for f, p in zip(freqs, phases))

    def v(time):
        return sum(1e-3 * 2 * np.pi * f * np.cos(2 * np.pi * f * time + p) for f, p in zip(freqs, phases))

    late = k * x(t - tau) + c * v(t - tau)
    (k_fit, c_fit), *_ = np.linalg.lstsq(np.column_stack([x(t), v(t)]), late, rcond=None)
    assert k_fit == pytest.approx(k, rel=0.02)  # second order in omega tau
    assert c_fit == pytest.approx(c - k * tau, abs=0.03 * k * tau)


def _cal(c_front, k_front=1.0e6, c_rear=3000.0, k_rear=1.8e6):
    return SimpleNamespace(names=("tire_damping_front_Ns_per_m", "tire_stiffness_front_N_per_m"),
                           fitted=(c_front, k_front),
                           fixed={"tire_damping_rear_Ns_per_m": c_rear, "tire_stiffness_rear_N_per_m": k_rear})


def test_a_tire_time_constant_inside_the_band_says_nothing():
    assert tire_time_constants(_cal(1700.0)) == pytest.approx({"front": 1.7e-3, "rear": 3000.0 / 1.8e6})
    assert skew_note(_cal(1700.0)) == ""
    assert skew_note(None) == ""


def test_a_tire_damped_below_any_tire_names_the_force_late_and_by_how_much():
    lo, hi = TIRE_TIME_CONSTANT_S
    note = skew_note(_cal(0.1e-3 * 1.0e6))  # 0.1 ms: 0.2 ms below the band's floor
    assert "front" in note and "force channel late on the LVDT by 0.20 ms" in note and "--force-filter" in note
    note = skew_note(_cal(1700.0, c_rear=(hi + 1e-3) * 1.8e6))  # 1 ms above the ceiling: the LVDT late
    assert "rear" in note and "LVDT channel late on the force by 1.00 ms" in note
    assert note.count(".") <= 6 and "\n" not in note  # one sentence
