"""Frequency-response identification from measured input and output records.

* :func:`h1_estimate`: the H1 estimator ``H = S_yu / S_uu`` (Welch-averaged cross and auto
  spectra, ``scipy.signal.csd``) with its (multiple) coherence, for one input or several
  simultaneous, uncorrelated inputs (MIMO: ``H = S_yu S_uu^-1``, which removes the
  cross-coupling of the other inputs from each path instead of counting it as noise).
* :func:`fit_rational`: a stable rational transfer function of chosen order fitted to a
  frequency response by weighted least squares in the frequency domain (Sanathanan-Koerner
  iterations, unstable poles reflected into the left half-plane).

Works on data of a real rig as on simulated data: numpy, scipy and python-control only.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # python-control and scipy.signal are imported where they are used
    import control

__all__ = ["h1_estimate", "fit_rational", "fit_rational_coefficients"]


def _as_columns(x, name: str) -> tuple[np.ndarray, bool]:
    a = np.asarray(x, dtype=float)
    if a.ndim == 1:
        return a[:, None], True
    if a.ndim == 2:
        return a, False
    raise ValueError(f"{name} must be 1-D (N,) or 2-D (N, channels), got shape {a.shape}")


def h1_estimate(u, y, fs: float, nperseg: int, *, noverlap: int | None = None,
                window: str = "hann") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """H1 estimate of the frequency response from ``u`` to ``y``, and its coherence.

    Parameters
    ----------
    u : array_like, shape (N,) or (N, m)
        Input record(s), any unit; several inputs must be simultaneously sampled and should be
        mutually uncorrelated (independent random drives).
    y : array_like, shape (N,) or (N, p)
        Output record(s), sampled with ``u``.
    fs : float, Hz
        Sampling rate.
    nperseg : int
        Samples per Welch segment (frequency resolution ``fs / nperseg``).
    noverlap : int, optional
        Overlap of the segments (default half a segment).
    window : str
        Window of each segment (``scipy.signal.get_window`` name), default Hann.

    Returns
    -------
    f : numpy.ndarray, Hz, shape (nf,)
        Frequencies, 0 to fs/2.
    H : numpy.ndarray of complex
        ``(nf,)`` for 1-D ``u`` and ``y``; otherwise ``(nf, p, m)``, ``H[:, i, j]`` the
        response of output ``i`` to input ``j`` (unit of ``y`` per unit of ``u``).
    coherence : numpy.ndarray, 1
        Ordinary coherence ``|S_uy|^2 / (S_uu S_yy)`` ``(nf,)`` for one input and output;
        otherwise the multiple coherence of each output with all inputs, ``(nf, p)``. 1 means
        the output is a linear function of the inputs at that frequency; nonlinearity,
        noise and unmeasured inputs lower it.

    Notes
    -----
    With ``G_uu[j, k] = csd(u_j, u_k)`` and ``G_uy[j, i] = csd(u_j, y_i)`` (scipy's convention
    ``csd(x, y) = E[conj(X) Y]``), ``y = H u`` gives ``G_uy = G_uu H^T``, so
    ``H^T = G_uu^-1 G_uy``. The multiple coherence is ``Re(g^H G_uu^-1 g) / G_yy`` with
    ``g = G_uy[:, i]``. H1 is unbiased by output noise and biased low by input noise.
    """

    uc, u1 = _as_columns(u, "u")
    yc, y1 = _as_columns(y, "y")
    if uc.shape[0] != yc.shape[0]:
        raise ValueError(f"u and y must have the same number of samples, got {uc.shape[0]} and {yc.shape[0]}")
    if not (isinstance(fs, (int, float, np.floating)) and fs > 0):
        raise ValueError(f"fs must be > 0, got {fs!r}")
    nperseg = int(nperseg)
    if not 8 <= nperseg <= uc.shape[0]:
        raise ValueError(f"nperseg must lie in [8, {uc.shape[0]}] (the record length), got {nperseg}")
    if not (np.all(np.isfinite(uc)) and np.all(np.isfinite(yc))):
        raise ValueError("u and y must be finite")
    m, p = uc.shape[1], yc.shape[1]
    f, spectra = _welch_spectra(np.column_stack([uc, yc]), fs, nperseg, noverlap, window)
    su, sy, even = spectra[:m], spectra[m:], nperseg % 2 == 0
    g_uu = np.empty((f.size, m, m), dtype=complex)
    for j in range(m):
        for k in range(j, m):
            g = _cross_density(su[j], su[k], even)
            g_uu[:, j, k] = g
            g_uu[:, k, j] = np.conj(g)
    g_uy = np.empty((f.size, m, p), dtype=complex)
    for j in range(m):
        for i in range(p):
            g_uy[:, j, i] = _cross_density(su[j], sy[i], even)
    g_yy = np.empty((f.size, p))
    for i in range(p):
        g_yy[:, i] = _cross_density(sy[i], sy[i], even, auto=True)
    h = np.full((f.size, p, m), np.nan + 0j)
    coh = np.full((f.size, p), np.nan)
    for n in range(f.size):
        guu = g_uu[n]
        if not np.all(np.isfinite(guu)) or np.linalg.cond(guu) > 1e12:
            continue  # no input power here (e.g. above the drive's band or at DC)
        x = np.linalg.solve(guu, g_uy[n])  # (m, p) = H^T
        h[n] = x.T
        with np.errstate(divide="ignore", invalid="ignore"):
            coh[n] = np.real(np.einsum("ji,ji->i", np.conj(g_uy[n]), x)) / g_yy[n]
    if u1 and y1:
        return f, h[:, 0, 0], coh[:, 0]
    return f, h, coh


def _welch_spectra(x: np.ndarray, fs: float, nperseg: int, noverlap: int | None, window: str):
    """Each column's short-time spectra as ``scipy.signal.csd`` computes them (Welch segments,
    constant detrend, one-sided, density scaling), once per column: ``(f, [S_0, S_1, ...])``.

    :func:`_cross_density` combines two of them into the cross density ``csd`` returns, to the
    bit, so that each record is transformed once instead of once per pair it belongs to."""
    from scipy.signal import ShortTimeFFT, get_window

    n = x.shape[0]
    noverlap = nperseg // 2 if noverlap is None else int(noverlap)
    sft = ShortTimeFFT(get_window(window, nperseg), nperseg - noverlap, fs, fft_mode="onesided", mfft=nperseg,
                       scale_to="psd", phase_shift=None)
    p1 = (n - noverlap) // sft.hop
    return sft.f, [sft.stft_detrend(x[:, c], "constant", p0=0, p1=p1, k_offset=nperseg // 2) for c in range(x.shape[1])]


def _cross_density(sa: np.ndarray, sb: np.ndarray, even: bool, auto: bool = False) -> np.ndarray:
    """``scipy.signal.csd(a, b)`` (``E[conj(A) B]``) from the spectra of :func:`_welch_spectra`
    (``even``: an even segment length, whose last bin, Nyquist, is not doubled); ``auto``:
    ``scipy.signal.welch(a)``, real. The same operations in the same order as scipy's."""
    pxy = sa.real**2 + sa.imag**2 if auto else sb * sa.conj()
    pxy = np.moveaxis(pxy, 0, -1)
    pxy[..., 1:-1 if even else None] *= 2
    pxy = np.moveaxis(pxy, -1, 0)
    pxy = pxy.mean(axis=-1) if pxy.shape[-1] > 1 else np.reshape(pxy, pxy.shape[:-1])
    pxy = pxy.astype(complex)
    return pxy.real if auto else pxy


def _poly_eval(c_asc: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.polyval(c_asc[::-1], x)


def fit_rational(f_hz, h, num_order: int, den_order: int, weight=None, f_max: float | None = None, *,
                 f_min: float | None = None, iterations: int = 30, tol: float = 1e-10
                 ) -> control.TransferFunction:
    """Fit a stable continuous-time ``N(s) / D(s)`` to a frequency response.

    :func:`fit_rational_coefficients`, returned as a ``control.TransferFunction``; the
    parameters are the same.

    Returns
    -------
    control.TransferFunction
        Stable (all poles with negative real part), s in rad/s.
    """
    import control

    return control.tf(*fit_rational_coefficients(f_hz, h, num_order, den_order, weight, f_max, f_min=f_min,
                                                 iterations=iterations, tol=tol))


def fit_rational_coefficients(f_hz, h, num_order: int, den_order: int, weight=None, f_max: float | None = None, *,
                              f_min: float | None = None, iterations: int = 30, tol: float = 1e-10
                              ) -> tuple[np.ndarray, np.ndarray]:
    """Fit a stable continuous-time ``N(s) / D(s)`` to a frequency response: its coefficients.

    Minimises ``sum_k w_k^2 |N(s_k) / D(s_k) - H_k|^2`` over ``s_k = j 2 pi f_k`` by
    Sanathanan-Koerner iterations (each a linear least-squares problem in the coefficients,
    weighted by the previous ``1 / |D|``, with ``D`` monic and frequencies scaled by their
    largest value for conditioning). Poles that end in the right half-plane are reflected into
    the left one (``p -> -conj(p)``), which keeps the magnitude response exactly and changes
    only the phase: the result is always stable.

    Parameters
    ----------
    f_hz : array_like, Hz
        Frequencies of ``h`` (positive; zero and negative ones are ignored).
    h : array_like of complex
        Frequency response at ``f_hz`` (SISO), e.g. an :func:`h1_estimate`.
    num_order, den_order : int
        Orders of numerator and denominator (``0 <= num_order <= den_order``, ``den_order >= 1``).
    weight : array_like, optional
        Non-negative weight per frequency (e.g. a function of the coherence); default 1.
        Points with zero weight or a non-finite ``h`` are left out.
    f_max : float, Hz, optional
        Highest frequency used.
    f_min : float, Hz, optional
        Lowest frequency used.
    iterations : int
        Most Sanathanan-Koerner iterations.
    tol : float
        Stop when the relative change of the denominator coefficients falls below this.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        ``(num, den)`` in descending powers of s (rad/s), leading zero coefficients dropped;
        stable (all poles with negative real part).

    Raises
    ------
    ValueError
        For bad orders or too few usable frequency points.
    """
    num_order, den_order = int(num_order), int(den_order)
    if not (den_order >= 1 and 0 <= num_order <= den_order):
        raise ValueError(f"need den_order >= 1 and 0 <= num_order <= den_order, got {num_order}, {den_order}")
    f = np.asarray(f_hz, dtype=float).ravel()
    hv = np.asarray(h, dtype=complex).ravel()
    w = np.ones_like(f) if weight is None else np.asarray(weight, dtype=float).ravel()
    if not (f.shape == hv.shape == w.shape):
        raise ValueError("f_hz, h and weight must have the same length")
    keep = (f > 0) & np.isfinite(hv) & np.isfinite(w) & (w > 0)
    if f_max is not None:
        keep &= f <= f_max
    if f_min is not None:
        keep &= f >= f_min
    f, hv, w = f[keep], hv[keep], w[keep]
    n_unknown = num_order + 1 + den_order
    if 2 * f.size < n_unknown:
        raise ValueError(f"{f.size} usable frequency points cannot determine {n_unknown} coefficients")
    w0 = 2.0 * math.pi * float(np.max(f))
    x = 1j * 2.0 * math.pi * f / w0  # scaled Laplace variable
    vn = np.vander(x, num_order + 1, increasing=True)  # x^0..x^nb
    vd = np.vander(x, den_order, increasing=True)  # x^0..x^(na-1); D monic
    xna = x ** den_order

    def solve(rows, rhs):
        a = np.vstack([rows.real, rows.imag])
        b = np.concatenate([rhs.real, rhs.imag])
        scale = np.linalg.norm(a, axis=0)
        scale[scale == 0] = 1.0
        sol, *_ = np.linalg.lstsq(a / scale, b, rcond=None)
        return sol / scale

    d = np.zeros(den_order + 1)
    d[-1] = 1.0
    d_prev_val = np.ones_like(x)
    for _ in range(max(1, int(iterations))):
        wk = w / np.abs(d_prev_val)
        rows = np.hstack([vn, -hv[:, None] * vd]) * wk[:, None]
        sol = solve(rows, hv * xna * wk)
        d_new = np.append(sol[num_order + 1:], 1.0)
        change = np.linalg.norm(d_new - d) / np.linalg.norm(d_new)
        d = d_new
        d_prev_val = _poly_eval(d, x)
        if change < tol:
            break
    n_asc = sol[:num_order + 1]
    poles = np.roots(d[::-1])
    if np.any(poles.real > 0):
        # Reflect into the left half-plane: |j w - p| = |j w + conj(p)|, so with the numerator
        # kept the magnitude response is unchanged; only the phase changes.
        poles = np.where(poles.real > 0, -np.conj(poles), poles)
        d = np.real(np.poly(poles))[::-1]  # ascending, monic
    # Back to s: x = s / w0. Multiply through by w0^na so that D stays monic in s.
    num = np.array([n_asc[i] * w0 ** (den_order - i) for i in range(num_order + 1)])[::-1]
    den = np.array([d[i] * w0 ** (den_order - i) for i in range(den_order + 1)])[::-1]
    return _leading_zeros_dropped(num), _leading_zeros_dropped(den)


def _leading_zeros_dropped(c: np.ndarray) -> np.ndarray:
    """``c`` without its leading exact zeros (one zero if all are), as python-control keeps them."""
    nz = np.flatnonzero(c != 0)
    return c[nz[0]:].astype(float) if nz.size else np.zeros(1)
