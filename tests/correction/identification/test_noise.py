"""rigsim.correction.identification.noise.noise_rms: the white noise of a record from the band above its signal.

Reference: white Gaussian noise of known rms sigma has the one-sided PSD sigma^2 / (fs / 2) at
every frequency (Parseval), so the estimate must return sigma whatever band it reads, within the
Welch estimate's statistical scatter (60 s at 1 kHz, ~100 segments averaged over ~200 Hz:
well under 1 %); a signal confined below the band does not move it.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import butter, sosfiltfilt

from rigsim.correction.identification.noise import noise_rms

FS = 1000.0


def _signal(n: int, rng) -> np.ndarray:
    """A wheel-force-like record: 25 kN static, 5 kN rms below 30 Hz (zero-phase Butterworth)."""
    sos = butter(4, 30.0, fs=FS, output="sos")
    s = sosfiltfilt(sos, rng.normal(size=(n, 2)), axis=0)
    return 25e3 + 5e3 * s / s.std(axis=0)


@pytest.mark.parametrize("sigma", [10.0, 100.0, 1000.0])
def test_white_noise_under_a_band_limited_force_is_recovered(sigma):
    rng = np.random.default_rng(4)
    n = int(60 * FS)
    x = _signal(n, rng) + rng.normal(0.0, sigma, (n, 2))
    est = noise_rms(x, FS)
    assert est.shape == (2,)
    np.testing.assert_allclose(est, sigma, rtol=0.02)
    assert float(noise_rms(x[:, 0], FS)) == pytest.approx(est[0])  # one channel: the same number


def test_content_inside_the_band_counts_as_noise():
    """A 300 Hz tone in the band is read as noise: the estimate is an upper bound of the white part."""
    rng = np.random.default_rng(5)
    t = np.arange(int(30 * FS)) / FS
    x = rng.normal(0.0, 100.0, t.size) + 200.0 * np.sin(2 * np.pi * 300.0 * t)
    assert float(noise_rms(x, FS)) > 120.0
    assert float(noise_rms(x, FS, band_hz=(350.0, 450.0))) == pytest.approx(100.0, rel=0.03)


@pytest.mark.parametrize("kw, match", [({"band_hz": (300.0, 600.0)}, "Nyquist"), ({"band_hz": (0.0, 100.0)}, "band_hz"),
                                       ({"fs": -1.0}, "fs")])
def test_bad_arguments_are_refused(kw, match):
    x = np.random.default_rng(0).normal(size=1000)
    with pytest.raises(ValueError, match=match):
        noise_rms(x, **({"fs": FS} | kw))
    with pytest.raises(ValueError, match="64"):
        noise_rms(x[:10], FS)
    with pytest.raises(ValueError, match="NaN"):
        noise_rms(np.r_[x, np.nan], FS)
