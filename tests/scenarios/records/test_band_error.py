"""The calibrated model's error in the correction's band (rigsim.scenarios.records.model.band_error), against
analytic references: white noise through the band limit keeps the share of its power the low-pass's
noise bandwidth gives; a model off by a gain is off by that gain in every band; a static bias (which the
model correction cancels) is no error; noise above the band is none either."""

from __future__ import annotations

import numpy as np
import pytest

from rigsim.correction.output.lowpass import BAND_HZ, BAND_ORDER
from rigsim.scenarios.records.model.band_error import band_errors, noise_bandwidth_hz

FS = 1000.0
RNG = np.random.default_rng(11)


def _record(n=30_000):
    """A smooth four-wheel force: sinusoids at 1.5, 3 and 10 Hz around 30 kN, N."""
    t = np.arange(n) / FS
    f = 3e4 + sum(a * np.sin(2 * np.pi * fr * t + ph)[:, None] * np.ones((1, 4))
                  for a, fr, ph in ((2e3, 1.5, 0.1), (1e3, 3.0, 0.7), (5e2, 10.0, 1.3)))
    return f


def test_the_noise_bandwidth_of_a_butterworth():
    """|H|^2 of an order-n Butterworth integrates to f_c (pi / 2n) / sin(pi / 2n) (analytic)."""
    n = BAND_ORDER
    assert noise_bandwidth_hz(FS) == pytest.approx(BAND_HZ * (np.pi / (2 * n)) / np.sin(np.pi / (2 * n)), rel=1e-4)


def test_a_gain_error_a_bias_and_noise():
    force = _record()
    windows = [(0, 2000, 14_000), (14_000, 16_000, 30_000)]
    gain = [force[a:e] * 1.1 + np.array([500.0, 0, 0, 0]) - np.array([3e3, 3e3, 3e3, 3e3]) * 0.1 for a, _, e in windows]
    fit, noise = band_errors(gain, force, windows, FS, np.zeros(4))
    # 10 % gain on the dynamic part: the residual is 0.1 x the force's dynamic part, bias and mean aside
    assert fit == pytest.approx((0.1,) * 4, rel=2e-3) and noise == (0.0,) * 4
    noisy = force + 100.0 * RNG.standard_normal(force.shape)  # the measured force with white noise
    model = [force[a:e] for a, _, e in windows]  # the exact model
    fit, noise = band_errors(model, noisy, windows, FS, np.full(4, 100.0))
    std = np.concatenate([force[s:e] for _, s, e in windows]).std(axis=0)
    expect = 100.0 * np.sqrt(noise_bandwidth_hz(FS) / (FS / 2)) / std
    assert noise == pytest.approx(tuple(expect), rel=1e-3)
    assert fit == pytest.approx(tuple(expect), rel=0.05)  # the residual in band is that noise
    high = [force[a:e] + 300.0 * np.sin(2 * np.pi * 150.0 * np.arange(e - a) / FS)[:, None] for a, _, e in windows]
    fit, _ = band_errors(high, force, windows, FS, np.zeros(4))
    whole = 300.0 / np.sqrt(2) / std  # that error over the whole band: ~0.13
    assert max(fit / whole) < 0.02  # at five times the band limit: gone from the band (the filter's edges aside)


def test_the_whole_record_error_is_the_windows_figure_on_one_window_beyond_the_noise():
    """record_errors: a model off by 10 % of the dynamic part on rl and rr from the record's middle on
    (a model out of step where no window looked), exact before; the measured force with 100 N of
    white noise. Reference: the error's rms over the settled samples, sqrt(1/2) x 0.1 of the second
    half's dynamic part, over the band-limited force's std (the noise's share taken out as
    band_errors' white-noise figure, which the estimate from the record reproduces)."""
    from rigsim.scenarios.records.model.band_error import record_errors

    force = _record()
    n, first = force.shape[0], 3000
    model = force.copy()
    half = n // 2
    dyn = force - 3e4
    model[half:, 2:] += 0.1 * dyn[half:, 2:]
    noisy = force + 100.0 * RNG.standard_normal(force.shape)
    err = np.asarray(record_errors(model, noisy, first, FS))
    std = force[first:].std(axis=0)
    off = 0.1 * dyn[half:, 2:]
    expect = np.sqrt((off ** 2).sum(axis=0) / (n - first)) / std[2:]
    assert err[2:] == pytest.approx(expect, rel=0.03)
    assert max(err[:2]) < 0.2 * min(expect)  # the exact wheels: the noise taken out, a little left to chance
