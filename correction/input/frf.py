"""Measured frequency-response matrices for drive iteration: identification, resampling, inverse.

The first step of input correction (:mod:`rigsim.correction.input.iterate`): from a broadband drive of the
rig and its measured responses, the H1 estimate ``H(f)`` (p x m) with the multiple coherence of
each response (:func:`identify_frf`, on :func:`rigsim.correction.identification.identify.h1_estimate`); its values on
another frequency grid (:func:`frf_on_grid`); and its regularized per-frequency inverse
(:func:`inverse_frf`), which the drive update multiplies the error by. The four wheels couple
through the truck, so ``H`` is the full matrix (MIMO H1 from four independent drives).

numpy and scipy only (no simulator): works on data of a real rig. Units SI (m, N, s, Hz).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigsim.correction.identification.identify import h1_estimate

__all__ = ["FRF", "identify_frf", "frf_on_grid", "inverse_frf"]


@dataclass(frozen=True)
class FRF:
    """A measured frequency-response matrix.

    Attributes
    ----------
    f_hz : numpy.ndarray, Hz, (nf,)
    h : numpy.ndarray of complex, (nf, p, m)
        ``h[:, i, j]``: response ``i`` per unit of drive ``j`` (e.g. m/m or N/m).
    coherence : numpy.ndarray, (nf, p)
        Multiple coherence of each response with all drives (1: linear and noise-free).
    averages : int
        Number of independent Welch averages (about ``2 N / nperseg - 1`` with half overlap).
    """

    f_hz: np.ndarray
    h: np.ndarray
    coherence: np.ndarray
    averages: int


def as_columns(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise ValueError(f"{name} must be 1-D or 2-D (N, channels), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def identify_frf(drive, response, fs: float, nperseg: int) -> FRF:
    """H1 estimate of the rig's FRF matrix from a broadband drive (independent channels).

    Parameters
    ----------
    drive : array_like, (N, m)
        Simultaneous, mutually uncorrelated broadband drives (e.g. independent random noise).
    response : array_like, (N, p)
        The measured responses.
    fs : float, Hz
    nperseg : int
        Welch segment length (resolution ``fs / nperseg``).
    """
    u = as_columns(drive, "drive")
    y = as_columns(response, "response")
    f, h, coh = h1_estimate(u, y, fs, nperseg)
    if h.ndim == 1:  # SISO
        h = h[:, None, None]
        coh = coh[:, None]
    n_avg = max(1, int(2 * u.shape[0] // int(nperseg)) - 1)
    return FRF(f_hz=f, h=h, coherence=coh, averages=n_avg)


def frf_on_grid(frf: FRF, f_hz) -> tuple[np.ndarray, np.ndarray]:
    """Interpolate ``frf`` (real and imaginary parts, linearly) onto ``f_hz``.

    Returns ``(h, coherence)`` of shapes (nf, p, m) and (nf, p); NaN outside the measured range
    or where the estimate is undefined.
    """
    f = np.asarray(f_hz, dtype=float)
    nf, p, m = frf.h.shape
    h = np.empty((f.size, p, m), dtype=complex)
    for i in range(p):
        for j in range(m):
            hij = frf.h[:, i, j]
            ok = np.isfinite(hij)
            re = np.interp(f, frf.f_hz[ok], hij[ok].real, left=np.nan, right=np.nan)
            im = np.interp(f, frf.f_hz[ok], hij[ok].imag, left=np.nan, right=np.nan)
            h[:, i, j] = re + 1j * im
    coh = np.empty((f.size, p))
    for i in range(p):
        c = np.nan_to_num(frf.coherence[:, i], nan=0.0)
        coh[:, i] = np.interp(f, frf.f_hz, c, left=0.0, right=0.0)
    return h, coh


def inverse_frf(h: np.ndarray, *, regularization: float = 1e-3) -> np.ndarray:
    """Per-frequency (pseudo-)inverse ``(H^H H + lambda I)^-1 H^H`` of ``h`` (nf, p, m) -> (nf, m, p).

    ``lambda = regularization * sigma_max^2`` at each frequency (Tikhonov): directions the rig
    barely responds to get a bounded drive instead of an infinite one. Non-finite ``h`` gives 0.
    """
    h = np.asarray(h, dtype=complex)
    nf, p, m = h.shape
    out = np.zeros((nf, m, p), dtype=complex)
    ok = np.all(np.isfinite(h.reshape(nf, -1)), axis=1)
    hh = h[ok]
    hH = np.conj(np.swapaxes(hh, 1, 2))
    a = hH @ hh
    smax2 = np.linalg.norm(hh, ord=2, axis=(1, 2)) ** 2
    lam = float(regularization) * smax2
    a = a + lam[:, None, None] * np.eye(m)[None]
    good = smax2 > 0
    out_ok = np.zeros((hh.shape[0], m, p), dtype=complex)
    if np.any(good):
        out_ok[good] = np.linalg.solve(a[good], hH[good])
    out[ok] = out_ok
    return out
