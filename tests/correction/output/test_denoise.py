"""Spectral subtraction of a record's white noise (rigsim.correction.output.denoise) and the padded spectral
application it shares with the channels' timing (rigsim.correction.output.spectral)."""

import numpy as np
import pytest
from scipy import signal

from rigsim.correction.output.denoise import FLAT_RATIO, design_noise_gain
from rigsim.correction.output.spectral import through_gain

FS = 1000.0
N = 30_000  # 30 s, the mismatch suite's records


def _signal(amp_N=3000.0, corner_hz=8.0, k=2, seed=1):
    """Band-limited force (4th-order Butterworth of white noise), its one-sided PSD (N^2/Hz) at ``f``."""
    sos = signal.butter(4, corner_hz, fs=FS, output="sos")
    x = amp_N * signal.sosfilt(sos, np.random.default_rng(seed).standard_normal((N + 2000, k)), axis=0)[2000:]

    def psd(f):
        return amp_N ** 2 * 2.0 / FS * np.abs(signal.sosfreqz(sos, worN=f, fs=FS)[1]) ** 2

    return x, psd


def _white(sigma_N=100.0, k=2, seed=2):
    return sigma_N * np.random.default_rng(seed).standard_normal((N, k))


def test_white_noise_alone_is_read_and_taken_out():
    noise = _white()
    g = design_noise_gain(noise, FS)
    # The level read is the noise's own (Welch estimates over 90 Hz of bandwidth, 30 s: ~2 % scatter).
    assert g.noise_rms == pytest.approx([100.0, 100.0], rel=0.05)
    assert g.measured.all()
    out = g.apply(noise)
    # Where S_x is N0 up to its estimate's scatter, max(0, 1 - N0 / S_x) keeps a few percent of the power.
    assert np.all(out.std(axis=0) < 0.3 * noise.std(axis=0))


def test_signal_in_noise_comes_close_to_the_wiener_bound():
    # Wiener (1949): the least mean-square error of any linear estimate of s from s + n is
    # the integral of S_s N0 / (S_s + N0) over frequency; spectral subtraction estimates that filter
    # from the record itself, so its error lies above the bound but near it: 1.76-1.81 times it on
    # this record (a 380 N rms force below 8 Hz in 100 N of white noise), where passing the record
    # unchanged leaves 26 times the bound and a gain of 0, 370 times.
    s, psd = _signal()
    n = _white()
    g = design_noise_gain(s + n, FS)
    err = g.apply(s + n) - s
    f = np.linspace(0.0, FS / 2, 200_001)
    n0 = 2.0 * 100.0 ** 2 / FS
    bound = np.trapezoid(psd(f) * n0 / (psd(f) + n0), f)
    mse = np.mean((err - err.mean(axis=0)) ** 2, axis=0)
    assert np.all(mse >= 0.95 * bound)
    assert np.all(mse <= 2.0 * bound)
    assert np.all(mse < 0.1 * 100.0 ** 2)  # against the noise's own power: most of it is gone
    # and the signal is kept: its power within a few percent
    assert g.apply(s + n).std(axis=0) == pytest.approx(s.std(axis=0), rel=0.03)


def test_the_mean_passes_untouched():
    x = 4.2e4 + _white()
    out = design_noise_gain(x, FS).apply(x)
    assert out.mean(axis=0) == pytest.approx(x.mean(axis=0), abs=1e-8)


def test_a_band_that_is_not_white_passes_the_record_unchanged():
    # A force that reaches through the noise band (a 1st-order roll-off at 20 Hz: its level falls
    # about 2.5 times from 60 to 150 Hz) over a 10 N noise: the band's parts differ by more than
    # FLAT_RATIO and the noise is not read from it.
    sos = signal.butter(2, 20.0, fs=FS, output="sos")
    x = 3e3 * signal.sosfilt(sos, np.random.default_rng(3).standard_normal((N, 2)), axis=0) + _white(10.0)
    g = design_noise_gain(x, FS)
    assert not g.measured.any()
    np.testing.assert_array_equal(g.gain, 1.0)
    np.testing.assert_allclose(g.apply(x), x, atol=1e-6)


def test_each_column_has_its_own_gain():
    s, _ = _signal(k=1)
    x = np.hstack([s + _white(100.0, k=1), s + _white(400.0, k=1, seed=5)])
    g = design_noise_gain(x, FS)
    assert g.noise_rms == pytest.approx([100.0, 400.0], rel=0.05)
    assert FLAT_RATIO > 1
    assert g.share_kept()[0] > g.share_kept()[1]


@pytest.mark.parametrize("x, fs, match", [
    (np.zeros(1000), FS, "must be \\(n, k\\)"),
    (np.zeros((100, 2)), FS, "at least"),
    (np.full((5000, 2), np.nan), FS, "NaN"),
    (np.zeros((5000, 2)), -1.0, "positive rate"),
])
def test_bad_records_are_refused(x, fs, match):
    with pytest.raises(ValueError, match=match):
        design_noise_gain(x, fs)


def test_apply_refuses_other_columns():
    g = design_noise_gain(_white(), FS)
    with pytest.raises(ValueError, match="must be \\(n, 2\\)"):
        g.apply(np.zeros((N, 3)))


def test_through_gain_delays_a_sine_exactly_inside_the_record():
    # A pure delay d is the gain exp(-2 pi i f d): a 3 Hz sine comes out as sin(2 pi 3 (t - d)); the
    # reflected ends are not the sine's continuation, so only samples 0.5 s inside are compared.
    t = np.arange(10_000) / FS
    x = np.sin(2 * np.pi * 3.0 * t)
    y = through_gain(x, FS, lambda f: np.exp(-2j * np.pi * f * 0.01), pad_s=0.5)
    inner = slice(500, -500)
    np.testing.assert_allclose(y[inner], np.sin(2 * np.pi * 3.0 * (t[inner] - 0.01)), atol=2e-3)
    np.testing.assert_allclose(through_gain(x, FS, lambda f: np.ones_like(f), pad_s=0.5), x, atol=1e-12)


def test_the_drift_cut_is_a_forward_backward_butterworth_high_pass():
    # Reference: scipy's second-order Butterworth high-pass at the corner, its magnitude squared
    # (run forward and backward, a zero-phase filter has |H|^2); scipy's is the digital design, whose
    # bilinear transform bends the analog response by ~1e-5 at 1 kHz.
    from rigsim.correction.output.denoise import DRIFT_HZ, drift_cut

    f = np.linspace(0.0, 20.0, 401)
    sos = signal.butter(2, DRIFT_HZ, btype="highpass", fs=FS, output="sos")
    h = np.abs(signal.sosfreqz(sos, worN=f, fs=FS)[1]) ** 2
    np.testing.assert_allclose(drift_cut(f, DRIFT_HZ), h, rtol=1e-4, atol=1e-9)
    s, _ = _signal()
    x = s + _white()
    plain, cut = design_noise_gain(x, FS), design_noise_gain(x, FS, drift_hz=DRIFT_HZ)
    np.testing.assert_allclose(cut.gain, plain.gain * drift_cut(plain.freq_hz, DRIFT_HZ)[:, None])


def test_the_drift_cut_takes_the_slow_part_out_and_keeps_the_rest():
    # 500 N at 0.2 Hz (drift) and 500 N at 5 Hz over 10 N of white noise and a 40 kN mean: the cut at
    # 1 Hz passes (5 / 1)^4 / (1 + (5 / 1)^4) = 0.998 of the 5 Hz sine and ~0.3 % of the 0.2 Hz one
    # (its gain interpolated between the spectrum's bins at 0 and 0.24 Hz), the mean untouched.
    t = np.arange(N) / FS
    slow, fast = (500.0 * np.sin(2 * np.pi * f * t)[:, None] * np.ones(2) for f in (0.2, 5.0))
    x = 4e4 + slow + fast + _white(10.0)
    out = design_noise_gain(x, FS, drift_hz=1.0).apply(x)
    inner = slice(5000, -5000)
    assert out.mean(axis=0) == pytest.approx(x.mean(axis=0), abs=1e-6)
    err = out[inner] - 4e4 - fast[inner]
    assert np.all(np.sqrt(np.mean(err ** 2, axis=0)) < 0.03 * 500.0)


@pytest.mark.parametrize("drift_hz", [0.0, -1.0, float("nan"), FS / 2])
def test_a_drift_corner_outside_the_band_is_refused(drift_hz):
    with pytest.raises(ValueError, match="drift_hz"):
        design_noise_gain(_white(), FS, drift_hz=drift_hz)


def test_a_slow_part_far_above_the_drift_level_is_kept_and_one_at_it_cut():
    # Spectral subtraction of the drift's power from the slow part's (Boll 1979, applied to the band
    # the cut takes out): a 0.37 Hz sine of 300 N amplitude (212 N rms, far above a 50 N drift) keeps
    # 1 - 50^2 / 212^2 = 0.944 of its power; one of 60 N (42 N rms, under the drift's level) is cut
    # whole; the 9 Hz part passes either way. The analytic share is that of the sine alone: the white
    # noise below 0.7 Hz adds (100 N)^2 x 0.7 / 500 = 14 N^2 to the 45 000 N^2, nothing at 1e-3.
    from rigsim.correction.output.denoise import drift_keep

    t = np.arange(N) / FS
    slow = np.column_stack([300.0 * np.sin(2 * np.pi * 0.37 * t), 60.0 * np.sin(2 * np.pi * 0.37 * t)])
    fast = 1000.0 * np.sin(2 * np.pi * 9.0 * t)[:, None] * np.ones(2)
    x = slow + fast + _white(100.0)
    g = design_noise_gain(x, FS, drift_hz=0.7, drift_rms=50.0)
    assert g.drift_kept[0] == pytest.approx(1 - 50.0 ** 2 / (300.0 ** 2 / 2), abs=0.01)
    assert g.drift_kept[1] == 0.0
    out = g.apply(x)
    inner = slice(5000, -5000)
    basis = np.column_stack([np.sin(2 * np.pi * 0.37 * t), np.cos(2 * np.pi * 0.37 * t)])[inner]
    amp = np.hypot(*np.linalg.lstsq(basis, out[inner] - out[inner].mean(axis=0), rcond=None)[0])
    # the gain on the slow sine, h + (1 - h) k with h(0.37 Hz) < 0.2 (the spectrum's bins interpolated)
    assert 0.9 * 300.0 < amp[0] < 300.0
    assert amp[1] < 0.2 * 60.0  # the 60 N sine cut as drift
    # without a level every slow part is cut, as the drift cut alone (the previous test's gain)
    np.testing.assert_array_equal(design_noise_gain(x, FS, drift_hz=0.7).drift_kept, [0.0, 0.0])
    np.testing.assert_array_equal(drift_keep([1e4, 1e2], None), [0.0, 0.0])
    assert design_noise_gain(x, FS).drift_kept is None


@pytest.mark.parametrize("drift_rms", [-1.0, float("nan"), float("inf")])
def test_a_drift_level_that_is_not_a_level_is_refused(drift_rms):
    with pytest.raises(ValueError, match="drift_rms"):
        design_noise_gain(_white(), FS, drift_hz=0.7, drift_rms=drift_rms)
