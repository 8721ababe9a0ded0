"""The hybrid model correction F_model(x_ref) + L(W(F_rig - F_model(x_a))) takes the load cells' white
noise out of the model's residual (rigsim.scenarios.records.model.differential.hybrid_correction)."""

import numpy as np
from scipy import signal

from rigsim.scenarios.records.model.differential import HYBRID_FORMULA, hybrid_correction

FS = 1000.0
N = 30_000


def _identity(forces):
    return np.asarray(forces, dtype=float), np.ones(len(forces), dtype=bool)


def _truck_force(seed=0):
    sos = signal.butter(4, 12.0, fs=FS, output="sos")
    return 4e4 + 3e3 * signal.sosfilt(sos, np.random.default_rng(seed).standard_normal((N, 4)), axis=0)


def test_an_exact_model_leaves_little_of_the_noise():
    # The model explains the rig force exactly: the residual is the 100 N white noise, and the hybrid
    # with L = 1 returns the model's road force with a few percent of the noise's power left.
    f_a = _truck_force(1)
    f_ref = _truck_force(2)
    noise = 100.0 * np.random.default_rng(3).standard_normal((N, 4))
    corrected, settled, gain = hybrid_correction(f_a + noise, f_ref, f_a, _identity, FS)
    left = corrected - f_ref - noise.mean(axis=0)
    assert settled.all()
    assert gain.measured.all() and np.allclose(gain.noise_rms, 100.0, rtol=0.05)
    assert np.all(left.std(axis=0) < 0.3 * noise.std(axis=0))
    assert "W(" in HYBRID_FORMULA


def test_a_model_error_is_kept():
    # The model misses a 4 Hz force of 500 N (what the residual carries beside the noise): the
    # hybrid with L = 1 keeps it, to within the noise's share at 4 Hz.
    t = np.arange(N) / FS
    f_a = _truck_force(1)
    miss = 500.0 * np.sin(2 * np.pi * 4.0 * t)[:, None] * np.ones(4)
    noise = 100.0 * np.random.default_rng(4).standard_normal((N, 4))
    corrected, _, _ = hybrid_correction(f_a + miss + noise, f_a, f_a, _identity, FS)
    kept = corrected - f_a
    inner = slice(5000, -5000)
    err = kept[inner] - miss[inner] - (kept[inner] - miss[inner]).mean(axis=0)
    assert np.all(np.sqrt(np.mean(err ** 2, axis=0)) < 0.1 * 500.0)


def test_the_noise_taken_out_is_said_per_model_wheel():
    from rigsim.scenarios.records.model_record import residual_noise_text

    text = residual_noise_text({"fl": 99.27, "fr": None})
    assert "fl 99.27 N" in text and "fr none" in text and "rl" not in text


def test_the_model_start_up_does_not_shift_the_settled_record():
    # An exact model whose runs start at rest: the residual starts with a start-up transient of
    # 20 kN decaying in 0.1 s, then it is the 100 N white noise. Designed and applied on the settled
    # samples (past 3 s), W leaves the corrected force there at the model's road force plus the
    # settled residual's mean (a few newtons). Designed on the whole record (the contrast below), W
    # keeps the whole record's mean, the transient's share included, while its zero gain at the
    # lowest frequencies takes out the step between start-up and the rest: the settled samples
    # shift by tens of newtons (a truck model measured here: -24 ... -90 N, +0.4 % of the DLC).
    from rigsim.scenarios.records.model.differential import settled_mask

    t = np.arange(N) / FS
    f_a = _truck_force(1)
    f_ref = _truck_force(2)
    noise = 100.0 * np.random.default_rng(5).standard_normal((N, 4))
    start_up = np.where(t < 3.0, -20000.0 * np.exp(-t / 0.1), 0.0)[:, None] * np.ones(4)
    force = f_a + start_up + noise
    settled = settled_mask(t)
    corrected, _, gain = hybrid_correction(force, f_ref, f_a, _identity, FS, settled)
    expected = noise[settled].mean(axis=0)
    shift = (corrected - f_ref)[settled].mean(axis=0)
    assert np.all(np.abs(shift - expected) < 5.0)
    assert gain.measured.all() and np.allclose(gain.noise_rms, 100.0, rtol=0.05)
    unmasked, _, _ = hybrid_correction(force, f_ref, f_a, _identity, FS)
    assert np.all(np.abs((unmasked - f_ref)[settled].mean(axis=0) - expected) > 30.0)


def test_the_load_cells_drift_is_taken_out():
    # An exact model; the load cells add 100 N of white noise and 50 N of drift (white noise through a
    # first-order low-pass at 0.1 Hz, a lab's slow zero drift). W's drift cut at DRIFT_HZ takes most of
    # the drift out of the residual (7-15 N of its 50 N left below 2 Hz): the model's road force
    # carries the slow force alone. Judged below 2 Hz (the white noise's few percent left are spread
    # over the whole band). The contrast: the white-noise gain alone leaves 42-55 N of it.
    from rigsim.correction.output.denoise import design_noise_gain

    f_a, f_ref = _truck_force(1), _truck_force(2)
    sos = signal.butter(1, 0.1, fs=FS, output="sos")
    drift = signal.sosfilt(sos, np.random.default_rng(6).standard_normal((N + 20_000, 4)), axis=0)[20_000:]
    drift = 50.0 * (drift - drift.mean(axis=0)) / drift.std(axis=0)
    noise = 100.0 * np.random.default_rng(7).standard_normal((N, 4))
    residual = drift + noise
    corrected, _, _ = hybrid_correction(f_a + residual, f_ref, f_a, _identity, FS)
    inner = slice(5000, -5000)
    slow = signal.butter(4, 2.0, fs=FS, output="sos")
    left = signal.sosfiltfilt(slow, corrected - f_ref, axis=0)[inner]
    assert np.all((left - left.mean(axis=0)).std(axis=0) < 0.4 * 50.0)
    white_only = design_noise_gain(residual, FS).apply(residual)
    kept = signal.sosfiltfilt(slow, white_only, axis=0)[inner]
    assert np.all((kept - kept.mean(axis=0)).std(axis=0) > 0.8 * 50.0)
    # drift_hz=None (a lab whose cells do not drift): W is the white-noise gain alone
    uncut, _, _ = hybrid_correction(f_a + residual, f_ref, f_a, _identity, FS, drift_hz=None)
    np.testing.assert_allclose(uncut - f_ref, white_only, atol=1e-6)
