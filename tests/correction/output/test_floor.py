"""The least-squares FIR "linear floor" (correction/output/floor.py) against analytic cases.

References: a record passed through a known two-sided FIR (numpy.convolve, independent of
the fit's own filtering) plus white noise of known rms must be recovered with taps within
the noise's standard error and an NRMSE equal to the noise rms over the target's std; a
cross-coupled 4 x 4 mix is recovered exactly by the coupled fit and not by the per-channel one;
the block-wise QR reduction gives the same taps as numpy.linalg.lstsq on the whole design matrix.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from rigsim.correction.output.floor import fir_filter, fir_fit, linear_floor


def _through(x, taps, lead):
    """y[n] = sum_k taps[k + lead] x[n - k] for k = -lead .. (numpy.convolve's full product,
    advanced by ``lead``; zeros assumed outside the record)."""
    return np.convolve(x, taps, mode="full")[lead:lead + x.size]


def test_known_two_sided_fir_is_recovered_to_the_noise_level():
    rng = np.random.default_rng(3)
    n, lead, lag = 20_000, 3, 5
    x = signal.lfilter([1.0], [1.0, -0.9], rng.standard_normal(n))  # coloured input
    taps = rng.standard_normal(lead + lag + 1)
    clean = _through(x, taps, lead) + 7.0
    noise_rms = 0.01 * clean[lag:n - lead].std()
    y = clean + noise_rms * rng.standard_normal(n)
    fl = linear_floor(x[:, None], y[:, None], lead, lag)
    assert fl.rows.sum() == n - lead - lag
    expected = noise_rms / y[fl.rows].std()
    assert fl.nrmse[0] == pytest.approx(expected, rel=0.05)
    fit = fir_fit(x, y, lead, lag)
    np.testing.assert_allclose(fit.coefficients[:, 0, 0], taps, atol=5e-3 * np.abs(taps).max())
    assert fit.intercept[0] == pytest.approx(7.0, abs=0.05)
    np.testing.assert_array_equal(fit.lags, np.arange(-lead, lag + 1))


def test_coupled_fit_recovers_a_cross_coupled_mix_exactly_and_per_wheel_does_not():
    rng = np.random.default_rng(5)
    n, lead, lag = 6_000, 2, 4
    x = np.column_stack([signal.lfilter([1.0], [1.0, -a], rng.standard_normal(n)) for a in (0.5, 0.7, 0.8, 0.9)])
    mix = rng.standard_normal((lead + lag + 1, 4, 4))
    y = np.zeros((n, 4))
    for q in range(4):
        for j in range(4):
            y[:, q] += _through(x[:, j], mix[:, j, q], lead)
    coupled = linear_floor(x, y, lead, lag, coupled=True, block_rows=500)  # many QR updates
    assert np.all(coupled.nrmse < 1e-9)
    fit = fir_fit(x, y, lead, lag)
    np.testing.assert_allclose(fit.coefficients, mix, atol=1e-9)
    per_wheel = linear_floor(x, y, lead, lag, coupled=False)
    assert np.all(per_wheel.nrmse > 0.1)  # the other wheels' share is out of its reach


def test_blockwise_qr_equals_lstsq_on_the_whole_design_matrix():
    rng = np.random.default_rng(7)
    n, lead, lag = 3_000, 4, 6
    x = rng.standard_normal((n, 2))
    y = rng.standard_normal((n, 3))
    rows = rng.random(n) > 0.3
    fit = fir_fit(x, y, lead, lag, rows=rows, block_rows=97)
    k = np.flatnonzero(fit.rows)
    design = np.column_stack([x[k - lag_k, j] for j in range(2) for lag_k in range(-lead, lag + 1)] + [np.ones(k.size)])
    ref = np.linalg.lstsq(design, y[k], rcond=None)[0]
    np.testing.assert_allclose(fit.coefficients.transpose(1, 0, 2).reshape(-1, 3), ref[:-1], atol=1e-10)
    np.testing.assert_allclose(fit.intercept, ref[-1], atol=1e-10)
    assert not fit.rows[:lag].any() and not fit.rows[n - lead:].any()
    np.testing.assert_allclose(fit.fitted[k], design @ ref, atol=1e-9)


def test_fir_filter_matches_convolve_and_marks_the_edges():
    rng = np.random.default_rng(9)
    x = rng.standard_normal(200)
    taps = np.array([0.5, -1.0, 2.0, 0.25])
    out = fir_filter(x, taps[:, None, None], np.arange(-1, 3))
    ref = _through(x, taps, 1)
    np.testing.assert_allclose(out[2:199, 0], ref[2:199], atol=1e-12)
    assert np.isnan(out[:2, 0]).all() and np.isnan(out[199:, 0]).all()


def test_bad_input_is_refused():
    x = np.ones((10, 1))
    with pytest.raises(ValueError, match="lead and lag"):
        fir_fit(x, x, -1, 2)
    with pytest.raises(ValueError, match="unknowns"):
        fir_fit(x, x, 4, 4)
    with pytest.raises(ValueError, match="same number of samples"):
        fir_fit(x, np.ones(9), 0, 1)
    with pytest.raises(ValueError, match="NaN"):
        fir_fit(np.full(10, np.nan), x, 0, 1)


def test_cross_validation_sees_overfitting_that_the_in_sample_fit_hides():
    # y is pure noise, independent of x: the true floor is 1. The in-sample fit with P unknowns
    # on N samples removes a fraction ~P/N of the noise's variance (NRMSE ~ sqrt(1 - P/N)); the
    # out-of-fold predictions add variance instead (NRMSE ~ sqrt(1 + P/N') > 1).
    rng = np.random.default_rng(11)
    n, lead, lag = 4_000, 100, 99
    x = rng.standard_normal((n, 1))
    y = rng.standard_normal((n, 1))
    fl = linear_floor(x, y, lead, lag, folds=2)
    ratio = (lead + lag + 2) / fl.rows.sum()
    assert fl.nrmse[0] == pytest.approx(np.sqrt(1 - ratio), abs=0.02)
    assert fl.nrmse_cv[0] > 1.0 + 0.5 * ratio
    assert linear_floor(x, y, lead, lag).nrmse_cv is None
    with pytest.raises(ValueError, match="folds"):
        linear_floor(x, y, lead, lag, folds=1)


def test_out_of_fold_predictions_equal_fits_on_the_other_folds():
    rng = np.random.default_rng(13)
    n, lead, lag = 2_000, 3, 7
    x = rng.standard_normal((n, 2))
    y = _through(x[:, 0], rng.standard_normal(lead + lag + 1), lead)[:, None] + rng.standard_normal((n, 1))
    fit = fir_fit(x, y, lead, lag, folds=3, block_rows=211)
    idx = np.flatnonzero(fit.rows)
    for part in np.array_split(idx, 3):
        others = fit.rows.copy()
        others[part] = False
        direct = fir_fit(x, y, lead, lag, rows=others)
        np.testing.assert_allclose(fit.predicted_cv[part], direct.fitted[part], atol=1e-9)
    assert np.isnan(fit.predicted_cv[~fit.rows]).all()
