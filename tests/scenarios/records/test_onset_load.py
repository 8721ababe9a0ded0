"""The progressive tire's onset searched as a wheel load (rigsim.scenarios.records.model.onset_load).

Pinned by hand: loads built so that their smallest, largest and median values are known, and the
field mapping's derivatives against central differences of the fields themselves."""

from __future__ import annotations

import numpy as np
import pytest

from rigsim.scenarios.core.config import load_scenario, paper_scenarios
from rigsim.scenarios.records.model.problem import FitProblem
from rigsim.scenarios.records.model.onset_load import ONSET_STIFFNESS, load_guess, load_range
from rigsim.scenarios.records.model.uncertainty import uncertainties

FRONT, REAR = "tire_progressive_onset_m", "tire_progressive_onset_rear_m"


@pytest.fixture
def record():
    """Four wheels' loads, N: the scored samples of two windows hold front 20-30 kN and rear 30-40 kN;
    the lead-ins and the unscored tail hold loads far outside both, which the range must not see."""
    force = np.zeros((100, 4))
    force[:, :2], force[:, 2:] = 1e3, 9e4  # lead-ins and tail: outside every scored load
    force[10:30, 0], force[10:30, 1] = np.linspace(20e3, 24e3, 20), 22e3
    force[50:70, 0], force[50:70, 1] = np.linspace(26e3, 30e3, 20), 25e3
    force[10:30, 2:], force[50:70, 2:] = 30e3, 40e3
    force[69, 3] = 41e3
    return force, [(0, 10, 30), (40, 50, 70)]


def test_the_range_is_the_axles_scored_loads(record):
    force, windows = record
    assert load_range(force, windows, FRONT) == (20e3, 30e3)
    assert load_range(force, windows, REAR) == (30e3, 41e3)


def test_the_first_guess_is_the_median_load_or_a_given_onset_inside_the_range(record):
    force, windows = record
    # 80 scored loads per axle: the front's median lies between its 40th and 41st, both 24e3 / 25e3 ...
    assert load_guess(force, windows, FRONT, None, 1e6) == np.median(np.r_[force[10:30, :2].ravel(), force[50:70, :2].ravel()])
    assert load_guess(force, windows, REAR, None, 1e6) == 35e3  # half at 30 kN, half at 40-41 kN
    assert load_guess(force, windows, REAR, 0.02, 1.6e6) == pytest.approx(32e3)  # inside: the given onset's load
    for onset_m in (0.02, 0.05, 0.0):  # 40 kN = kt x 2 cm ... 0: at or outside the range -> the median
        assert load_guess(force, windows, REAR, onset_m, 2.05e6 if onset_m == 0.02 else 1e6) == 35e3


def problem(names, guess, loads, fixed=None):
    sc = load_scenario(paper_scenarios()[0])
    return FitProblem(names, None, None, np.ones((10, 4)), [(0, 0, 10)], sc, guess, fixed or {}, None, None, loads)


def test_an_onset_is_its_load_over_its_axles_stiffness():
    names = ("tire_stiffness_rear_N_per_m", "tire_progressive_ratio_rear", REAR)
    guess = {"tire_stiffness_rear_N_per_m": 2.0e6, "tire_progressive_ratio_rear": 0.2, REAR: 0.016}
    prob = problem(names, guess, {REAR: (32e3, 10e3)})
    np.testing.assert_allclose(prob.fields(np.ones(3)), (2.0e6, 0.2, 32e3 / 2.0e6))
    theta = np.array([0.8, 1.5, 0.6])  # kt 1.6 MN/m; load 32 kN + 10 kN x (0.6 - 1) = 28 kN
    np.testing.assert_allclose(prob.fields(theta), (1.6e6, 0.2 + 0.5 * 0.5, 28e3 / 1.6e6))
    held = problem(names[1:], guess, {REAR: (32e3, 10e3)}, {"tire_stiffness_rear_N_per_m": 1.6e6})
    np.testing.assert_allclose(held.fields(np.array([1.0, 0.6])), (0.2, 28e3 / 1.6e6))


def test_the_mapping_is_the_fields_derivative():
    """Against central differences of fields(): the onset's row carries -onset / kt x d kt / d theta."""
    names = ("payload_kg", "tire_stiffness_front_N_per_m", "tire_progressive_ratio", FRONT, "cab_mount_hz")
    guess = {"payload_kg": 4e3, "tire_stiffness_front_N_per_m": 9e5, "tire_progressive_ratio": 0.2, FRONT: 0.027,
             "cab_mount_hz": 2.5}
    prob = problem(names, guess, {FRONT: (24e3, 6e3)})
    theta, h = np.array([1.1, 0.9, 0.7, 1.2, 1.3]), 1e-6
    numeric = np.column_stack([(prob.fields(theta + h * e) - prob.fields(theta - h * e)) / (2 * h) for e in np.eye(5)])
    analytic = prob.mapping(theta)
    np.testing.assert_allclose(analytic, numeric, rtol=1e-6, atol=1e-12)
    assert analytic[3, 1] != 0.0 and ONSET_STIFFNESS[FRONT] == names[1]


def test_the_sigmas_go_through_the_mapping():
    """A value that is the difference of two fitted parameters has the variance of both less twice their
    covariance: sigma^2 = s^2 (J^T J)^-1 contracted with (1, -1)."""
    rng = np.random.default_rng(7)
    jac, res = rng.standard_normal((400, 2)), rng.standard_normal(400)
    mapping = np.array([[1.0, 0.0], [1.0, -1.0]])
    formal, _ = uncertainties(jac, res, block=25, mapping=mapping)
    cov = np.linalg.inv(jac.T @ jac) * (res @ res) / (400 - 2)
    assert formal[0] == pytest.approx(np.sqrt(cov[0, 0]))
    assert formal[1] == pytest.approx(np.sqrt(cov[0, 0] + cov[1, 1] - 2 * cov[0, 1]))


def test_an_onset_stays_within_its_bounds_at_a_soft_kt():
    """A large load over a kt at the bottom of its search range would put the onset past
    rigsim.mjcf.variant.BOUNDS (0.1 m), which TruckVariant refuses: the fields stop it there."""
    from rigsim.mjcf.variant import BOUNDS

    names = ("tire_stiffness_front_N_per_m", FRONT)
    prob = problem(names, {"tire_stiffness_front_N_per_m": 7.65e5, FRONT: 0.03}, {FRONT: (40e3, 10e3)})
    assert prob.fields(np.array([0.3, 1.0]))[1] == BOUNDS[FRONT][1] == 0.1  # 40 kN / 230 kN/m = 0.17 m
    assert prob.fields(np.array([1.0, 1.0]))[1] == pytest.approx(40e3 / 7.65e5)


def test_a_wheel_off_the_ground_bounds_the_onset_at_zero_load(record):
    """A lifted wheel reads the load cells' noise about 0 N: no tire pulls, so the range starts at 0,
    and an onset at 0 N is the XML's lower bound, 0 m."""
    force, windows = record
    force[12, 0] = -260.0
    assert load_range(force, windows, FRONT) == (0.0, 30e3)
    force[10:30, :2], force[50:70, :2] = -50.0, -40.0  # every front sample below 0
    assert load_range(force, windows, FRONT) == (0.0, 0.0) and load_guess(force, windows, FRONT, None, 1e6) == 0.0
