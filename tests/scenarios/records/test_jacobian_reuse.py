"""The calibration's Jacobian reuse (problem.REUSE_MAX): Broyden's rank-one update where the last
Jacobian predicted the step, finite differences otherwise. Pure checks on a hand-made problem (no
model runs: a run asked for raises); the calibrations that use it are test_model_correction.py's."""

from __future__ import annotations

import numpy as np
import pytest

from rigsim.scenarios.records.model.problem import REUSE_MAX, REUSE_RATIO, FitProblem


class _Ran(Exception):
    """A model run was asked for: the Jacobian was recomputed by finite differences."""


def _problem(last, f0) -> FitProblem:
    prob = object.__new__(FitProblem)
    prob.last, prob.fun = last, lambda theta: f0

    def model(thetas):
        raise _Ran

    prob.model = model
    return prob


def _step_problem(scale_reduction: float):
    """A residual whose last Jacobian predicts a step's reduction, and the residual after the step
    reducing the sum of squares by ``scale_reduction`` of the predicted reduction."""
    rng = np.random.default_rng(0)
    j1, f1 = rng.normal(size=(40, 3)), rng.normal(size=40)
    th1 = np.ones(3)
    step = -0.1 * np.linalg.lstsq(j1, f1, rcond=None)[0]  # a tenth of the Gauss-Newton step: downhill
    pred = f1 + j1 @ step
    predicted = f1 @ f1 - pred @ pred
    assert predicted > 0.0
    # f0 along pred's direction from f1 so that |f1|^2 - |f0|^2 = scale_reduction * predicted
    target = f1 @ f1 - scale_reduction * predicted
    f0 = pred * np.sqrt(target / (pred @ pred))
    return th1, step, j1, f1, f0


def test_a_well_predicted_step_updates_the_jacobian_by_the_secant_condition():
    """Broyden's update satisfies the secant condition J_new s = f(theta) - f(theta_last) and
    changes J only along the step (J_new v = J v for v orthogonal to s): Dennis & Schnabel 1996,
    Numerical Methods for Unconstrained Optimization, eq. 8.1.5."""
    th1, step, j1, f1, f0 = _step_problem(0.9)
    prob = _problem((th1, f1, j1, 0), f0)
    jac = prob.jac(th1 + step, th1 + 1.0)
    np.testing.assert_allclose(jac @ step, f0 - f1, atol=1e-12)
    ortho = np.cross(step, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(jac @ ortho, j1 @ ortho, atol=1e-12)
    assert prob.last[3] == 1


def test_a_poorly_predicted_step_or_too_many_updates_recomputes_it():
    th1, step, j1, f1, f0 = _step_problem(0.5 * REUSE_RATIO)
    with pytest.raises(_Ran):  # the step reduced the sum of squares by less than REUSE_RATIO of the prediction
        _problem((th1, f1, j1, 0), f0).jac(th1 + step, th1 + 1.0)
    th1, step, j1, f1, f0 = _step_problem(0.9)
    with pytest.raises(_Ran):  # REUSE_MAX updates in a row already
        _problem((th1, f1, j1, REUSE_MAX), f0).jac(th1 + step, th1 + 1.0)
    with pytest.raises(_Ran):  # no reuse asked for
        _problem((th1, f1, j1, 0), f0).jac(th1 + step, th1 + 1.0, reuse=0)
    with pytest.raises(_Ran):  # the uncertainties' Jacobian is never an update
        _problem((th1 + step, f0, j1, 1), f0).final_jac(th1 + step, th1 + 1.0)
    assert _problem((th1 + step, f0, j1, 0), f0).final_jac(th1 + step, th1 + 1.0) is j1
