"""Where the model correction stops: the model's own error on the record, beyond the load cells' noise.

Pure checks of :attr:`Calibration.excess_nrmse` and :func:`fallback_reason` on hand-made
calibrations (the numbers behind the limit are measured by benchmarks/model_correction.py; the
runs that produce a real fallback are tests/scenarios/records/test_model_correction.py's and tests/scenarios/records/test_correct_model.py's).
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace
import math

import pytest

from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.records.model.fallback import (DIFFERENTIAL_LIMIT, HYBRID_LIMIT, OUTLIER_RATIO, calibration_failed,
                                                     differential_holds, fallback_reason, model_error_limit,
                                                     outlier_reason, outlier_wheel, wheels_reason)
from rigsim.scenarios.records.model.result import Calibration, fitted_text


def _cal(fit, noise=(), converged=True, band=(), band_noise=()) -> Calibration:
    return Calibration(names=("payload_kg",), units=("kg",), initial=(1.0,), fitted=(1.0,), sigma=(0.0,),
                       sigma_robust=(0.0,), fixed={}, fit_nrmse=tuple(fit), initial_nrmse=(1.0,) * 4,
                       windows_s=((0.0, 1.0),), weighted=True, evaluations=3, converged=converged, message="stopped",
                       wall_time_s=1.0, noise_nrmse=tuple(noise), band_nrmse=tuple(band), band_noise_nrmse=tuple(band_noise))


def test_the_model_error_is_read_in_the_correction_band_where_measured():
    """A whole-band fit of 0.50 whose noise estimate failed (0.01, read behind an anti-alias filter) but
    whose band-limited residual is 0.05 (noise there 0.01): the model holds; the sentence says where."""
    cal = _cal((0.50,) * 4, (0.01,) * 4, band=(0.05, 0.05, 0.30, 0.05), band_noise=(0.01,) * 4)
    assert cal.excess_nrmse == pytest.approx((math.sqrt(0.05 ** 2 - 0.01 ** 2),) * 2 + (math.sqrt(0.3 ** 2 - 0.01 ** 2),)
                                             + (math.sqrt(0.05 ** 2 - 0.01 ** 2),))
    why = fallback_reason(cal)
    assert why.startswith("the calibrated truck model reproduces the measured wheel force of rl in the correction's "
                          "band only to NRMSE 0.300")
    assert fallback_reason(_cal((0.50,) * 4, (0.01,) * 4, band=(0.05,) * 4, band_noise=(0.01,) * 4)) == ""


def test_the_excess_is_the_fit_beyond_independent_noise():
    """Independent errors add in power: fit^2 = model^2 + noise^2 (3-4-5: 0.05 from 0.04 and 0.03)."""
    cal = _cal((0.05, 0.05, 0.02, 0.10), (0.03, 0.05, 0.03, 0.0))
    assert cal.excess_nrmse == pytest.approx((0.04, 0.0, 0.0, 0.10))
    assert _cal((0.05,) * 4).excess_nrmse == (0.05,) * 4  # no noise estimate: the fit itself


def test_a_noisy_record_is_not_taken_for_a_bad_model():
    """A fit NRMSE of 0.20 made mostly of noise (0.16) leaves a model error of 0.12: the model is used;
    the same fit with little noise is a model error of 0.199: the linear correction, one sentence why."""
    assert fallback_reason(_cal((0.05, 0.20, 0.05, 0.05), (0.03, 0.16, 0.03, 0.03)), DIFFERENTIAL_LIMIT) == ""
    why = fallback_reason(_cal((0.05, 0.20, 0.05, 0.05), (0.03, 0.02, 0.03, 0.03)), DIFFERENTIAL_LIMIT)
    assert why.startswith("the calibrated truck model reproduces the measured wheel force of fr only to NRMSE 0.200")
    assert (f"0.200: a model error of {math.sqrt(0.2 ** 2 - 0.02 ** 2):.3f} beyond the load cells' noise "
            f"(0.020; limit {DIFFERENTIAL_LIMIT:g})") in why
    assert why.endswith("so the linear correction is to be used.") and why.count(". ") == 0


def test_the_limit_and_convergence():
    """The hybrid's limit by default, the differential form's lower one when given (fallback.py says why)."""
    assert DIFFERENTIAL_LIMIT < HYBRID_LIMIT
    for just, kw in ((HYBRID_LIMIT, {}), (DIFFERENTIAL_LIMIT, {"excess_limit": DIFFERENTIAL_LIMIT})):
        assert fallback_reason(_cal((just,) * 4), **kw) == ""
        assert f"limit {just:g})" in fallback_reason(_cal((just * 1.01,) * 4), **kw)
    assert fallback_reason(_cal((0.05,) * 4, converged=False)) == (
        "the truck model's calibration did not converge within its evaluation limit (3 truck variants run; stopped), "
        "so the linear correction is to be used.")


def test_each_form_has_its_limit_and_the_failures_their_sentence():
    """The hybrid's limit with L, the differential's without; the differential holds wheel by wheel
    within it; a calibration that refuses the record or whose run fails says which."""
    assert model_error_limit(hybrid=True) == HYBRID_LIMIT and model_error_limit(hybrid=False) == DIFFERENTIAL_LIMIT
    assert differential_holds(_cal((0.05, DIFFERENTIAL_LIMIT, 0.15, 0.05))).tolist() == [True, True, False, True]
    assert calibration_failed(ScenarioError("too short.")) == (
        "the truck model could not be calibrated on this record (too short), so the linear correction is to be used.")
    assert calibration_failed(RuntimeError("MuJoCo warned at 3 s")) == (
        "a truck-model run failed during the calibration (MuJoCo warned at 3 s), so the linear correction is to be "
        "used.")
    assert outlier_reason(_cal((0.05, 0.06, 0.30, 0.76)), 3) == (
        "rr's model error (0.760) is far past every other wheel's, so the truck is calibrated again without it")


def test_one_wheel_far_past_every_other_is_the_outlier_left_out():
    """outlier_wheel: past the limit and OUTLIER_RATIO times the next wheel (rr 0.76 against rl 0.30, ratio 2);
    two wheels alike past the limit, or one past the ratio but inside the limit, name none."""
    assert outlier_wheel(_cal((0.05, 0.06, 0.30, 0.76))) == 3
    assert outlier_wheel(_cal((0.05, 0.06, 0.30, 0.30 * OUTLIER_RATIO * 0.99))) is None
    assert outlier_wheel(_cal((0.40, 0.41, 0.05, 0.05))) is None
    assert outlier_wheel(_cal((0.01, 0.01, 0.01, HYBRID_LIMIT))) is None


def test_a_wheel_left_out_of_the_calibration_is_named_as_such():
    """The sentence for a per-wheel fallback names the wheel the calibration left out (Calibration.wheels)."""
    cal = dataclasses.replace(_cal((0.03, 0.03, 0.04, 2.5)), wheels=("fl", "fr", "rl"))
    why = wheels_reason(cal, (True, True, True, False))
    assert why == ("the calibrated truck model reproduces the measured wheel force only to NRMSE rr 2.500 (model error "
                   f"2.500) (limit {HYBRID_LIMIT:g} beyond the load cells' noise); rr, alone far past it, was "
                   "left out of the calibration, so that wheel is corrected linearly.")
    assert "left out" not in wheels_reason(_cal((0.03, 0.03, 0.04, 0.5)), (True, True, True, False))


def test_the_fit_table_writes_each_value_to_the_digits_its_sigma_supports():
    """To the decimal of sigma's second significant digit, at most 5 significant digits; .5g where sigma
    or the value says nothing (zero, not finite)."""
    assert fitted_text(0.0039416, 0.063) == "0.004"  # sigma 0.063: to 0.001
    assert fitted_text(0.028863, 0.0099) == "0.0289"  # sigma 0.0099: to 0.0001
    assert fitted_text(3657.65, 0.44) == "3657.7"  # 0.01 would be 6 digits: 5
    assert fitted_text(8.9988e5, 47.0) == "8.9988e+05"
    assert fitted_text(0.0, 5e-12) == "0" and fitted_text(1.25, 0.0) == "1.25" and fitted_text(2.5, math.nan) == "2.5"
    cal = Calibration(names=("tire_progressive_ratio_rear",), units=("1",), initial=(0.2,), fitted=(0.0039416,),
                      sigma=(0.063,), sigma_robust=(0.068,), fixed={}, fit_nrmse=(0.05,) * 4, initial_nrmse=(0.1,) * 4,
                      windows_s=((0.0, 1.0),), weighted=True, evaluations=3, converged=True, message="ok",
                      wall_time_s=1.0)
    assert "| tire_progressive_ratio_rear | 1 | 0.2 | 0.004 +- 0.063 (0.068) |" in cal.table().splitlines()


@pytest.mark.parametrize("wheels", [(), ("fl", "fl"), ("fl", "xx")])
def test_the_wheels_to_fit_are_checked_before_any_run(wheels):
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.records.model.calibrate import calibrate

    with pytest.raises(ScenarioError, match="wheels must be distinct corners of fl, fr, rl, rr"):
        calibrate([0.0, 0.001], [[0.0] * 4] * 2, [[1e4] * 4] * 2, base_scenario=None, wheels=wheels)


def test_the_cab_is_chosen_on_the_calibration_without_the_outlier_wheel(monkeypatch):
    """correct_with_model's ``defer`` (cab_choice.calibrate_cab, calibrations faked): the first fit,
    rr far past every other wheel (the walk-through's broken channel: model errors 0.035-0.039
    against 9.4), defers the cab's choice with a sentence naming rr; the fit without rr, whose rr
    error is still 9.4 but no longer fitted, does not (it chooses the cab)."""
    import numpy as np

    from rigsim.mjcf.names import CORNERS
    from rigsim.scenarios.core.config import load_scenario, paper_scenarios
    import rigsim.scenarios.records.model.differential as differential

    said = []

    def fake_calibrate_cab(t, x_a, f, *, cab, defer, wheels=CORNERS, start=None, **kw):
        cal = dataclasses.replace(_cal((0.035, 0.039, 0.038, 9.4)), wheels=tuple(wheels))
        said.append(defer(cal))
        return cal

    monkeypatch.setattr(differential, "calibrate_truck", fake_calibrate_cab)
    monkeypatch.setattr(differential, "calibrate_again", lambda cal, again, limit: cal)
    monkeypatch.setattr(differential, "model_force_pair", lambda variant, t, x_ref, x_a, **kw: (np.zeros((n, 4)),) * 2)
    # the hybrid's own weighing (fallback.hybrid_outlook) keeps every calibrated wheel: not this test's subject
    monkeypatch.setattr(differential, "hybrid_outlook",
                        lambda *a, **k: SimpleNamespace(holds=np.ones(4, bool), reason=lambda *a: ""))
    monkeypatch.setattr(differential, "record_errors", lambda *a: (0.0,) * 4)  # nor the whole record's error
    n = 4000
    t = np.arange(n) / 1000.0
    x = np.zeros((n, 4))
    force = 20e3 + np.random.default_rng(0).normal(0.0, 100.0, (n, 4))
    sc = load_scenario(paper_scenarios()[0])
    mc = differential.correct_with_model(t, x, x, force, base_scenario=sc, workers=1, windows=1, window_s=1.0,
                                         lead_s=0.5, linear=lambda f: (np.asarray(f, float), np.ones(len(f), bool)))
    assert said == ["rr's model error (9.400) is far past every other wheel's, so the truck is calibrated again "
                    "without it", ""]
    assert mc.calibration.wheels == ("fl", "fr", "rl") and mc.wheels == ("fl", "fr", "rl")


def test_a_wheel_the_model_loses_over_the_whole_record_is_corrected_linearly(monkeypatch):
    """correct_with_model weighs the model on the run the correction uses, not on the calibration's
    windows alone (calibrations faked, their windows' errors 0.035): a model force equal to the
    measured one on fl and fr, and on rl and rr out of step from 2.5 s on (a 5 Hz force of the
    same size half a period late: a model error near sqrt(2) there) is kept on fl and fr; rl and rr
    are corrected linearly, the sentence naming both with both errors."""
    import numpy as np

    from rigsim.scenarios.core.config import load_scenario, paper_scenarios
    import rigsim.scenarios.records.model.differential as differential

    n = 6000
    t = np.arange(n) / 1000.0
    wave = 3e3 * np.sin(2 * np.pi * 5.0 * t)
    force = 20e3 + wave[:, None] + np.random.default_rng(0).normal(0.0, 100.0, (n, 4))
    model = 20e3 + np.repeat(wave[:, None], 4, axis=1)
    model[2500:, 2:] = 20e3 - wave[2500:, None]
    monkeypatch.setattr(differential, "calibrate_truck", lambda *a, **k: _cal((0.035,) * 4))
    monkeypatch.setattr(differential, "calibrate_again", lambda cal, again, limit: cal)
    monkeypatch.setattr(differential, "model_force_pair", lambda *a, **kw: (model.copy(), model.copy()))
    monkeypatch.setattr(differential, "hybrid_outlook",  # the hybrid's own weighing keeps every wheel
                        lambda *a, **k: SimpleNamespace(holds=np.ones(4, bool), reason=lambda *a: ""))
    sc = load_scenario(paper_scenarios()[0])
    x = np.zeros((n, 4))
    mc = differential.correct_with_model(t, x, x, force, base_scenario=sc, workers=1, windows=1, window_s=1.0,
                                         lead_s=0.5, linear=lambda f: (np.asarray(f, float), np.ones(len(f), bool)))
    assert mc.method == "model" and mc.wheels == ("fl", "fr")
    assert max(mc.record_error[:2]) < 0.05 and min(mc.record_error[2:]) > 1.0
    assert mc.reason.startswith("run over the whole record, the calibrated truck model reproduces the measured wheel "
                                "force of rl only to a model error of ")
    assert "(0.035 on the calibration's windows)" in mc.reason and "so those wheels are corrected linearly." in mc.reason
    np.testing.assert_array_equal(mc.corrected_N[:, 2:], force[:, 2:])  # L, here the identity, on the measured force
