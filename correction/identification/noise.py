"""The white measurement noise of a record, read from the band above the signal.

A wheel-force record is the truck's force, band-limited by the tires and the actuators (the
simulated rig's forces fall below 1e-4 of a 100 N noise's spectral level above 200 Hz at 1 kHz),
plus the load cells' and the DAQ's noise, white up to Nyquist. The noise's rms is then the mean
one-sided power spectral density over a band where only the noise lives, times half the sampling
rate: :func:`noise_rms`, a Welch estimate (Hann windows of :data:`SEGMENT` samples, 50 % overlap)
over :data:`NOISE_BAND` of the sampling rate by default. Whatever else lives in that band (a rig's
structural modes, mains hum) counts as noise: the estimate is an upper bound of the white part.
"""

from __future__ import annotations

import numpy as np

__all__ = ["NOISE_BAND", "SEGMENT", "noise_rms"]

#: Default band of :func:`noise_rms`, as fractions of the sampling rate (250-450 Hz at 1 kHz).
NOISE_BAND = (0.25, 0.45)
#: Welch segment, samples (fewer if the record is shorter): 0.5 Hz resolution at 1 kHz.
SEGMENT = 2048


def noise_rms(x, fs: float, band_hz: tuple[float, float] | None = None) -> np.ndarray:
    """rms of the white noise of each channel of ``x``, in the unit of ``x``.

    Parameters
    ----------
    x : array_like, (n,) or (n, channels)
        The record (time along axis 0), any unit (N for wheel forces).
    fs : float, Hz
        Sampling rate.
    band_hz : (float, float), Hz, optional
        The band read, above the signal and below Nyquist (default :data:`NOISE_BAND` times ``fs``).

    Returns
    -------
    numpy.ndarray
        One rms per channel (a 0-d array for a 1-D ``x``).

    Raises
    ------
    ValueError
        A band outside (0, fs / 2), a record shorter than 64 samples, or non-finite values.
    """
    from scipy.signal import welch

    a = np.asarray(x, dtype=float)
    if a.shape[0] < 64:
        raise ValueError(f"the record has {a.shape[0]} samples; the noise estimate needs at least 64")
    if not np.all(np.isfinite(a)):
        raise ValueError("the record has NaN or infinite values; clean or cut it first")
    if not (np.isfinite(fs) and fs > 0):
        raise ValueError(f"fs must be a positive rate in Hz, got {fs!r}")
    lo, hi = (NOISE_BAND[0] * fs, NOISE_BAND[1] * fs) if band_hz is None else (float(band_hz[0]), float(band_hz[1]))
    if not (0 < lo < hi <= fs / 2):
        raise ValueError(f"band_hz must lie in (0, {fs / 2:g}] Hz (Nyquist) with low < high, got ({lo:g}, {hi:g})")
    f, p = welch(a - a.mean(axis=0), fs=fs, nperseg=min(SEGMENT, a.shape[0]), axis=0)
    rows = (f >= lo) & (f <= hi)
    if not rows.any():
        raise ValueError(f"band_hz ({lo:g}, {hi:g}) Hz holds no frequency of a {min(SEGMENT, a.shape[0])}-sample "
                         "segment; widen it")
    return np.sqrt(p[rows].mean(axis=0) * fs / 2.0)
