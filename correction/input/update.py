"""The drive update of input correction: ``g IFFT(W H^-1 FFT(e))`` over the whole record.

One step of :func:`rigsim.correction.input.iterate.iterate_drive`::

    d_{k+1} = d_k + g  W(f) H^-1(f) (target - y_k)

with the relaxation gain ``g``, the weighted inverse ``W H^-1`` (:func:`rigsim.correction.input.frf.inverse_frf`
times the update weight) and a cosine taper at both ends of the record. The weight ``W`` is 1
inside the frequency band with cosine edges outside it (:func:`band_weight`); the iteration sets
it to 0 where the identification's coherence is below a threshold.

numpy only (no simulator): works on data of a real rig. Units SI (m, N, s, Hz).
"""

from __future__ import annotations

import numpy as np

from rigsim.correction.input.frf import as_columns

__all__ = ["drive_update"]


def band_weight(f: np.ndarray, band_hz: tuple[float, float], edge: float = 0.15) -> np.ndarray:
    """1 inside ``band_hz``, cosine roll-off to 0 over ``edge`` of each edge frequency outside."""
    lo, hi = float(band_hz[0]), float(band_hz[1])
    if not (0 <= lo < hi):
        raise ValueError(f"band_hz must be (low, high) with 0 <= low < high, got {band_hz!r}")
    w = np.ones_like(f)
    if lo > 0:
        lo0 = lo * (1 - edge)
        w = np.where(f < lo0, 0.0, w)
        r = (f >= lo0) & (f < lo)
        w = np.where(r, 0.5 - 0.5 * np.cos(np.pi * (f - lo0) / (lo - lo0)), w)
    hi1 = hi * (1 + edge)
    w = np.where(f > hi1, 0.0, w)
    r = (f > hi) & (f <= hi1)
    w = np.where(r, 0.5 + 0.5 * np.cos(np.pi * (f - hi) / (hi1 - hi)), w)
    return w


def end_taper(n: int, fs: float, taper_s: float) -> np.ndarray:
    k = int(round(taper_s * fs))
    w = np.ones(n)
    if k > 0 and 2 * k < n:
        ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(k) / k)
        w[:k] = ramp
        w[-k:] = ramp[::-1]
    return w


def drive_update(error, inv_w: np.ndarray, gain: float, fs: float, *, taper_s: float = 0.5) -> np.ndarray:
    """``g IFFT(W H^-1 FFT(e))`` of the whole record, tapered at both ends.

    ``inv_w`` (nf, m, p) is the weighted inverse on ``numpy.fft.rfftfreq(N, 1/fs)``. The error is
    tapered (cosine, ``taper_s``) before the FFT and the update after it, so the update starts
    and ends at zero (the drive's fade-in and the rig's rest state stay untouched) and the FFT's
    circular wrap-around cannot leak the end of the record into its start.
    """
    e = as_columns(error, "error")
    n = e.shape[0]
    w = end_taper(n, fs, taper_s)
    ef = np.fft.rfft((e - e.mean(axis=0)) * w[:, None], axis=0)  # (nf, p)
    df = np.einsum("fmp,fp->fm", inv_w, ef)
    d = np.fft.irfft(df, n=n, axis=0)
    return float(gain) * d * w[:, None]
