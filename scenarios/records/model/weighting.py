"""The calibration's frequency weighting: fit the model where the differential correction uses it.

The correction's error is the model's error in the force *change* the actuators' error
x_ref - x_a causes. If the model's force error per unit pan motion at frequency f is D(f), the
calibration residual (pans following x_a) has the spectrum |D| |X_a|, the correction's error
|D| |X_ref - X_a| |T_F| (T_F the 30 Hz band limit it is judged through). Weighting the
calibration residual by

    W(f) = |T_F(f)| sqrt(S_dx(f) / S_xa(f))

(S the power spectra of x_ref - x_a and of x_a, pooled over the four corners, measured on the
record) makes the least squares minimize the correction's error itself; the model's errors at
frequencies the actuators follow well (low: W ~ 0.1 at 1 Hz) weigh little, those where the pans
miss the drive (W ~ 1 from ~10 Hz) fully. Only rig signals enter (the drive and the LVDTs).

:func:`differential_kernel` gives W as a zero-phase FIR kernel (half-length :data:`KERNEL_S`,
Hann-windowed, unit energy so that a white residual keeps its variance).
"""

from __future__ import annotations

import numpy as np

from rigsim.correction.output.lowpass import BAND_LOWPASS, as_lowpass

__all__ = ["KERNEL_S", "differential_weight", "differential_kernel"]

#: Half-length of the weighting kernel, s (W is smooth, so its kernel is short).
KERNEL_S = 0.1


def differential_weight(x_ref_m, x_a_m, fs: float, nperseg: int = 2048) -> tuple[np.ndarray, np.ndarray]:
    """(f in Hz, W(f) in 1): the weighting of the module notes, from the record's x_ref and x_a (m, (n, 4))."""
    from scipy.signal import welch

    x_ref, x_a = np.asarray(x_ref_m, float), np.asarray(x_a_m, float)
    nper = int(min(nperseg, x_a.shape[0]))
    f, s_dx = welch(x_ref - x_a, fs=fs, nperseg=nper, axis=0)
    _, s_a = welch(x_a, fs=fs, nperseg=nper, axis=0)
    ratio = np.sqrt(s_dx.sum(axis=1) / np.maximum(s_a.sum(axis=1), 1e-300))
    ratio[0] = ratio[1]  # the mean is no frequency the correction has to follow
    band = np.abs(as_lowpass(BAND_LOWPASS).response(f))  # the band limit the correction is judged through
    return f, ratio * band


def differential_kernel(x_ref_m, x_a_m, fs: float, kernel_s: float = KERNEL_S) -> np.ndarray:
    """The weighting W(f) as a zero-phase FIR kernel, odd length 2 round(kernel_s fs) + 1, unit energy."""
    f, w = differential_weight(x_ref_m, x_a_m, fs)
    half = int(round(kernel_s * fs))
    m = 8 * (2 * half + 1)
    grid = np.fft.rfftfreq(m, 1.0 / fs)
    h = np.fft.irfft(np.interp(grid, f, w), m)
    h = np.concatenate([h[-half:], h[:half + 1]]) * np.hanning(2 * half + 3)[1:-1]
    return h / np.sqrt(np.sum(h ** 2))
