"""A calibration started from given values (``calibrate(start=...)``, what the cab's choice uses to
start the cab-fitted search where the cab-held one ended). Pure checks of the mapping between the
fitted values and the scaled parameters theta (no model runs)."""

from __future__ import annotations

import numpy as np

from rigsim.scenarios.records.model.problem import FitProblem


def _problem() -> FitProblem:
    """Four fields as the calibration maps them: a plain one, an additive one, a compliance (the
    cab's mount) and a tire onset searched as a load over its fitted kt."""
    prob = object.__new__(FitProblem)
    prob.names = ("payload_kg", "tire_stiffness_front_N_per_m", "cab_mount_hz", "tire_progressive_onset_m")
    prob.offset = np.array([0.0, 0.0, 0.0, 20e3])  # the onset's load range starts at 20 kN
    prob.scale = np.array([3000.0, 9e5, 2.5, 10e3])  # theta 1: 3 t, 900 kN/m, 2.5 Hz, 30 kN
    prob.compliance = np.array([False, False, True, False])
    prob.onsets = [(3, 1, None)]  # onset = load / kt, kt the second field
    return prob


def test_the_values_of_a_theta_map_back_to_it():
    """theta_of inverts fields (the round trip is the identity inside the bounds)."""
    prob = _problem()
    theta = np.array([1.3, 0.8, 0.5, 0.4])
    values = dict(zip(prob.names, prob.fields(theta)))
    np.testing.assert_allclose(prob.theta_of(values, np.zeros(4), np.full(4, 5.0)), theta, rtol=1e-12)


def test_fields_not_given_start_at_their_first_guess_and_outside_values_at_the_edge():
    prob = _problem()
    theta = prob.theta_of({"payload_kg": 9000.0, "cab_mount_hz": None}, np.full(4, 0.5), np.full(4, 2.0))
    # 9 t is 3 x the guess, past the upper bound 2; the rest (none given, or None) at 1
    np.testing.assert_array_equal(theta, [2.0, 1.0, 1.0, 1.0])
