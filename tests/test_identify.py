"""correction.identify: H1 estimation and rational fitting on known linear systems.

The systems are simulated with scipy (exact ZOH discretization, lfilter) and the estimates are
compared with their exact discrete-time frequency responses (scipy.signal.freqz); the fit is
checked against the poles the data were made from.
"""

import math

import control
import numpy as np
import pytest
from scipy import signal

from correction.identify import fit_rational, h1_estimate
from correction.transfer import frequency_response_hz

FS = 1000.0


def _discrete(sys_c):
    num, den = np.ravel(sys_c.num[0][0]), np.ravel(sys_c.den[0][0])
    bd, ad, _ = signal.cont2discrete((num, den), 1.0 / FS, method="zoh")
    return np.ravel(bd), ad


def _exact(bd, ad, f):
    _, h = signal.freqz(bd, ad, worN=f, fs=FS)
    return h


def test_h1_recovers_a_known_system_within_0p2_db_where_coherence_is_high():
    # A 15 Hz resonance (zeta 0.3) with a real pole at 40 Hz, white input, output noise 5 % RMS.
    wn = 2 * math.pi * 15.0
    sys = control.tf([wn ** 2], [1, 2 * 0.3 * wn, wn ** 2]) * control.tf([2 * math.pi * 40], [1, 2 * math.pi * 40])
    bd, ad = _discrete(sys)
    rng = np.random.default_rng(11)
    u = rng.normal(size=200_000)
    y = signal.lfilter(bd, ad, u)
    y = y + 0.05 * np.std(y) * rng.normal(size=y.size)
    f, h, coh = h1_estimate(u, y, FS, 2000)
    band = (f > 0.5) & (f < 40.0)
    good = band & (coh > 0.95)
    assert np.sum(good) > 0.9 * np.sum(band)  # the coherence is high where the system passes
    err_db = 20 * np.log10(np.abs(h[good] / _exact(bd, ad, f[good])))
    err_deg = np.degrees(np.angle(h[good] / _exact(bd, ad, f[good])))
    assert np.max(np.abs(err_db)) < 0.2
    assert np.max(np.abs(err_deg)) < 2.0
    # The coherence really drops where the noise dominates (far above the poles).
    assert np.median(coh[(f > 300) & (f < 490)]) < 0.9


def test_mimo_h1_separates_two_simultaneous_inputs():
    # y1 = G11 u1 + G12 u2, y2 = G22 u2 with independent inputs: each path comes back, and the
    # coupled path is not counted as noise (multiple coherence ~ 1 without noise).
    g = {(0, 0): control.tf([100.0], [1, 100.0]), (0, 1): control.tf([0.3 * 400.0], [1, 20.0, 400.0]),
         (1, 1): control.tf([2.0 * 60.0], [1, 60.0])}
    rng = np.random.default_rng(5)
    u = rng.normal(size=(200_000, 2))
    y = np.zeros((u.shape[0], 2))
    disc = {k: _discrete(v) for k, v in g.items()}
    for (i, j), (bd, ad) in disc.items():
        y[:, i] += signal.lfilter(bd, ad, u[:, j])
    # Segments (4 s) much longer than the slowest impulse response (~0.3 s) keep the leakage small.
    f, h, coh = h1_estimate(u, y, FS, 4000)
    assert h.shape == (f.size, 2, 2) and coh.shape == (f.size, 2)
    band = (f > 0.5) & (f < 200.0)
    for (i, j), (bd, ad) in disc.items():
        exact = _exact(bd, ad, f[band])
        # Within 2 % (0.17 dB) of the path's peak gain: what remains is the leakage of the windowed
        # segments. A single-input H1 of u2 -> y1 counts G11 u1 as noise (~3x the level of G12 u2):
        # with these data its error reaches ~60 % of the path's peak.
        err = np.abs(h[band, i, j] - exact) / np.max(np.abs(exact))
        assert np.max(err) < 0.02, (i, j)
    assert np.max(np.abs(h[band, 1, 0])) < 0.02  # no path from u1 to y2
    assert np.min(coh[band]) > 0.995


def test_h1_checks_its_inputs():
    with pytest.raises(ValueError, match="same number of samples"):
        h1_estimate(np.zeros(100), np.zeros(99), FS, 50)
    with pytest.raises(ValueError, match="nperseg"):
        h1_estimate(np.zeros(100), np.zeros(100), FS, 200)
    with pytest.raises(ValueError, match="finite"):
        h1_estimate(np.full(100, np.nan), np.zeros(100), FS, 50)


def test_fit_rational_recovers_known_poles_and_zeros():
    sys = control.tf([100.0, 500.0], [1.0, 12.0, 900.0]) * control.tf([50.0], [1.0, 50.0])
    f = np.geomspace(0.1, 100.0, 300)
    fit = fit_rational(f, frequency_response_hz(sys, f), 1, 3)
    assert np.allclose(np.sort_complex(fit.poles()), np.sort_complex(sys.poles()), rtol=1e-7)
    assert np.allclose(fit.zeros(), sys.zeros(), rtol=1e-7)
    assert float(np.real(fit.dcgain())) == pytest.approx(float(np.real(sys.dcgain())), rel=1e-7)


def test_fit_rational_from_an_h1_estimate():
    # End to end: simulate, estimate, fit; the fitted poles land near the true ones.
    wn = 2 * math.pi * 12.0
    sys = control.tf([wn ** 2], [1, 2 * 0.25 * wn, wn ** 2])
    bd, ad = _discrete(sys)
    rng = np.random.default_rng(3)
    u = rng.normal(size=100_000)
    f, h, coh = h1_estimate(u, signal.lfilter(bd, ad, u), FS, 2000)
    fit = fit_rational(f, h, 0, 2, weight=coh, f_min=0.5, f_max=60.0)
    p_fit = fit.poles()[np.argmax(fit.poles().imag)]
    p_true = sys.poles()[np.argmax(sys.poles().imag)]
    assert abs(p_fit - p_true) < 0.01 * abs(p_true)


def test_fit_rational_returns_a_stable_system():
    # The magnitude of 1/((s - 2)(s + 10)) fitted as a real, stable system: the unstable pole
    # is reflected to -2 (same magnitude response, all poles in the left half-plane).
    f = np.geomspace(0.01, 20.0, 200)
    s = 2j * np.pi * f
    h = 1.0 / ((s - 2.0) * (s + 10.0))
    fit = fit_rational(f, h, 0, 2)
    assert np.all(fit.poles().real < 0)
    assert np.allclose(np.sort(fit.poles().real), [-10.0, -2.0], rtol=1e-6)
    assert np.allclose(np.abs(frequency_response_hz(fit, f)), np.abs(h), rtol=1e-6)


def test_fit_rational_checks_orders_and_data():
    f = np.geomspace(1, 10, 3)
    with pytest.raises(ValueError, match="den_order"):
        fit_rational(f, np.ones(3), 3, 2)
    with pytest.raises(ValueError, match="cannot determine"):
        fit_rational(f, np.ones(3), 2, 6)
