"""The load cells' uncompensated mass (scenarios/records/model/cell_mass.py): the closed-form
least squares and its uncertainty on synthetic data, then the calibration recovering a lab's
mass-compensation error from a record."""

from __future__ import annotations

import numpy as np
import pytest

from rigsim.scenarios.core.lab import pan_acceleration
from rigsim.scenarios.records.model.calibrate import calibrate
from rigsim.scenarios.records.model.cell_mass import mass_of, mass_sigma

from tests.scenarios.records.test_model_correction import _road_record


def test_the_shared_mass_is_the_weighted_least_squares_one():
    """error = -m a + noise (the model's force less the measured F + m a) on four columns: the estimate is (sum_k w_k a_k.(-e_k)) / (sum_k w_k a_k.a_k)
    (the normal equation of one parameter), a column of weight 0 does not count, and a nil
    acceleration gives 0."""
    rng = np.random.default_rng(1)
    a = rng.normal(size=(5000, 4)) * [1.0, 2.0, 3.0, 4.0]
    e = 7.5 * a + rng.normal(size=a.shape)  # the model reads 7.5 kg too much: m = -7.5
    e[:, 3] += 50.0 * a[:, 3]  # a column far off: left out by its weight
    w = np.array([1.0, 0.5, 2.0, 0.0])
    m = mass_of(e, a, w)
    expected = -sum(w[k] * a[:, k] @ e[:, k] for k in range(4)) / sum(w[k] * a[:, k] @ a[:, k] for k in range(4))
    assert m == pytest.approx(expected, rel=1e-12) and m == pytest.approx(-7.5, abs=0.01)
    assert mass_of(e, np.zeros_like(a), w) == 0.0


def test_the_mass_sigma_matches_the_spread_of_the_estimate():
    """White residual, blocks of 1: the sandwich is the ordinary least squares standard error,
    s sqrt(sum w^2 a^2) / sum w a^2; over 400 draws the estimates' std matches the mean sigma within 10 %."""
    rng = np.random.default_rng(2)
    a = rng.normal(size=(2000, 4))
    w = np.array([1.0, 1.0, 0.5, 0.5])
    est, sig = [], []
    for _ in range(400):
        e = 3.0 * a + 2.0 * rng.normal(size=a.shape)
        m = mass_of(e, a, w)
        est.append(m)
        sig.append(mass_sigma(e + m * a, a, w, block=1))
    assert np.std(est) == pytest.approx(np.mean(sig), rel=0.1)
    assert np.mean(est) == pytest.approx(-3.0, abs=3 * np.std(est) / np.sqrt(400))


def test_the_calibration_recovers_a_labs_mass_compensation_error():
    """The road test of the medium case's plant (pans following the road exactly), its load cells
    reading 7.5 kg of pan mass too little (3 % of a 250 kg pan plate over-compensated,
    rigsim.scenarios.core.lab.TYPICAL_LAB) plus 100 N of noise; the payload fitted on one 3 s window, the
    rest held at the plant's: the cells' mass is recovered within 5 % and its sigma covers the error;
    without the pan's term the fitted mass is within 3 sigma of 0."""
    sc, road, force = _road_record()
    pan = road.signals["pan_m"]
    fs = float(road.rate_hz)
    held = {k: getattr(sc.vehicle, k) for k in ("tire_stiffness_front_N_per_m", "tire_stiffness_rear_N_per_m",
                                                "tire_damping_front_Ns_per_m", "tire_damping_rear_Ns_per_m",
                                                "spring_friction_front_N", "spring_friction_rear_N",
                                                "axle_mass_front_kg", "axle_mass_rear_kg")}

    def fit(f):
        return calibrate(road.t_s, pan, f, base_scenario=sc, names=("payload_kg",), fitted_guess=held, windows=1,
                         window_s=3.0, lead_s=2.0, max_nfev=6, workers=2)

    cal = fit(force - 7.5 * pan_acceleration(pan, fs))
    assert cal.cell_mass_kg == pytest.approx(-7.5, rel=0.05)
    assert abs(cal.cell_mass_kg + 7.5) < 3 * cal.cell_mass_sigma_kg + 0.05 * 7.5
    clean = fit(force)
    assert abs(clean.cell_mass_kg) < 3 * clean.cell_mass_sigma_kg, (clean.cell_mass_kg, clean.cell_mass_sigma_kg)


def test_without_cell_mass_takes_the_mass_times_the_band_limited_acceleration_out():
    """The correction's and the suite's one way to take the fitted mass out of the force."""
    from rigsim.scenarios.records.model.cell_mass import band_acceleration, without_cell_mass

    fs = 1000.0
    t = np.arange(4000) / fs
    x = np.column_stack([0.01 * np.sin(2 * np.pi * 5.0 * t), 0.005 * np.sin(2 * np.pi * 12.0 * t)])
    force = np.full((4000, 2), 30e3)
    np.testing.assert_array_equal(without_cell_mass(force, x, fs, 0.0), force)
    got = without_cell_mass(force, x, fs, -7.5)
    np.testing.assert_allclose(got, force + 7.5 * band_acceleration(x, fs))
    # in the band the acceleration is the analytic -(2 pi f)^2 x: 7.5 kg x 9.87 m/s^2 = 74 N at 5 Hz
    mid = slice(1000, 3000)
    np.testing.assert_allclose((got - force)[mid, 0], -7.5 * (2 * np.pi * 5.0) ** 2 * x[mid, 0], atol=0.5)
