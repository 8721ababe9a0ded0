"""The "linear floor" of an output correction: the best FIR filter fitted on the answer itself.

A diagnostic, never a correction: it needs the road force, which a rig test does not have.
For a measured rig force ``x`` and the band-limited road force ``y`` it fits, by least squares,
the FIR filter ``h`` (lags ``-lead .. lag`` samples, so it may be two-sided) that minimizes
``||y - h * x||^2``, and scores the fit with :func:`rigsim.correction.metrics.dlc.nrmse`. No linear correction
of the same length, per wheel or 4 x 4, can do better on the samples it was fitted on, so the
NRMSE of the fit is the floor that only a nonlinear correction (or a better plant) can go below.

Two forms (:func:`linear_floor`):

* per wheel: wheel ``i``'s road force from wheel ``i``'s rig force alone (what any per-wheel
  ``T_a^-1 T_F`` can reach);
* coupled (4 x 4): each wheel's road force from all the rig forces (what a MIMO correction
  with the wheel-to-wheel coupling can reach).

Each filter is affine: a constant term absorbs any static offset between the two forces, so
the floor measures the dynamic mismatch only. The fit is in-sample: a lower bound, which a long
filter pushes down by fitting part of the residual itself (much more than the white-noise
estimate ``P / N`` of ``P`` unknowns on ``N`` samples suggests when the residual is narrow-band).
With ``folds`` it is also cross-validated (each fold predicted by the filter fitted on the
others): what a filter of that length does on data it has not seen, an upper bound of the floor
as the folds are shorter than the record.

The least squares (:func:`fir_fit`) is ``numpy.linalg.lstsq`` of the Toeplitz design matrix
(rows: the input's lagged windows, a ``numpy.lib.stride_tricks.sliding_window_view``, never
copied whole), reduced block by block: the QR factor ``R`` of ``[X Y]`` is updated with each
block of rows (``numpy.linalg.qr(..., mode="r")`` of the previous ``R`` stacked on the block),
and ``lstsq`` is solved on the final ``R``. Since ``[X Y] = Q R`` with orthonormal ``Q``,
``||X h - Y|| = ||R [h; -I]||`` exactly: the same minimizer (minimum norm if rank deficient)
as ``lstsq(X, Y)`` in the memory of one block and one factor (60 s at 1 kHz, 4 inputs x 451
taps: 32 MB and 26 MB, against 870 MB for the whole matrix). Cross-validation keeps one factor
per fold; the factor of a union of folds is the QR of their stacked factors.

Time runs along axis 0; forces in N (any unit: the fit is linear); lags in samples.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from rigsim.correction.metrics.dlc import nrmse

__all__ = ["FirFit", "fir_fit", "fir_filter", "LinearFloor", "linear_floor"]

#: Elements of one block of the design matrix (float64: 8 bytes each), 1.
BLOCK_ELEMENTS = 4_000_000


@dataclass(frozen=True)
class FirFit:
    """An affine FIR filter fitted by least squares, and its fit.

    ``y[n, q] ~ intercept[q] + sum_k sum_j coefficients[k, j, q] x[n - lags[k], j]``.

    Attributes
    ----------
    lags : numpy.ndarray of int, (n_lags,)
        Lag of each tap in samples, from ``-lead`` (the input ``lead`` samples ahead) to ``lag``.
    coefficients : numpy.ndarray, (n_lags, m, p)
        Taps from each of the ``m`` inputs to each of the ``p`` outputs (output unit per input unit).
    intercept : numpy.ndarray, (p,)
        Constant term (output unit).
    fitted : numpy.ndarray, (n, p)
        The filter's output; NaN where its window leaves the record.
    rows : numpy.ndarray of bool, (n,)
        Samples the fit used: the requested ones whose window lies inside the record.
    predicted_cv : numpy.ndarray or None, (n, p)
        With ``folds``: on ``rows``, each fold's samples predicted by the filter fitted on the
        other folds (NaN elsewhere).
    """

    lags: np.ndarray
    coefficients: np.ndarray
    intercept: np.ndarray
    fitted: np.ndarray
    rows: np.ndarray
    predicted_cv: np.ndarray | None = None


def _as_2d(a, name: str) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] < 2:
        raise ValueError(f"{name} must be a record of shape (n,) or (n, channels) with n >= 2, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values; fix: remove or interpolate them")
    return a


def _windows(x: np.ndarray, lead: int, lag: int):
    """The lagged windows of ``x`` (n, m): row ``r`` holds ``x[r + t]``, t = 0 .. lead + lag,
    i.e. the taps of output ``r + lag`` from lag ``lag`` down to ``-lead``."""
    return sliding_window_view(x, lead + lag + 1, axis=0)  # (n - L + 1, m, L): a view


def _factor(win, y: np.ndarray, idx: np.ndarray, lag: int, step: int) -> np.ndarray:
    """Triangular factor R of ``[X 1 Y]`` over the output samples ``idx``, block by block."""
    n_rows, m, taps = idx.size, win.shape[1], win.shape[2]
    width = m * taps + 1 + y.shape[1]
    r_aug = np.zeros((0, width))
    for start in range(0, n_rows, step):
        k = idx[start:start + step]
        block = np.empty((k.size, width))
        block[:, :m * taps] = win[k - lag].reshape(k.size, m * taps)
        block[:, m * taps] = 1.0
        block[:, m * taps + 1:] = y[k]
        r_aug = np.linalg.qr(np.vstack([r_aug, block]), mode="r")
    return r_aug


def _solve(factors: list, m: int, taps: int) -> tuple[np.ndarray, np.ndarray]:
    """Taps (n_lags, m, p), lags ascending, and intercept (p,) from the factors of some row sets."""
    r_aug = factors[0] if len(factors) == 1 else np.linalg.qr(np.vstack(factors), mode="r")
    n_par = m * taps + 1
    sol = np.linalg.lstsq(r_aug[:, :n_par], r_aug[:, n_par:], rcond=None)[0]  # (n_par, p)
    # column (j, t) of a window row is x[n - lag + t, j]: the tap of lag (lag - t)
    coef = sol[:m * taps].reshape(m, taps, -1).transpose(1, 0, 2)[::-1]  # lags -lead .. lag
    return np.ascontiguousarray(coef), sol[m * taps].copy()


def fir_fit(x, y, lead: int, lag: int, *, rows=None, folds: int = 0, block_rows: int | None = None) -> FirFit:
    """Fit the affine FIR filter from ``x`` to ``y`` with lags ``-lead`` to ``lag`` by least squares.

    Parameters
    ----------
    x : array_like, (n,) or (n, m)
        Input record(s), e.g. the measured rig forces (N).
    y : array_like, (n,) or (n, p)
        Target record(s) on the same samples, e.g. the band-limited road forces (N).
    lead, lag : int
        Taps ahead of (non-causal) and behind (causal) the output sample, >= 0; the filter has
        ``lead + lag + 1`` taps per input.
    rows : array_like of bool, (n,), optional
        Samples to fit on (default all); those whose window leaves the record are dropped.
    folds : int
        0: no cross-validation; >= 2: also :attr:`FirFit.predicted_cv`, each of that many
        contiguous folds of the rows predicted by the filter fitted on the other folds. Costs
        next to nothing: the factor of each fold is computed once, and the factor of a union
        of folds is the QR of their stacked factors.
    block_rows : int, optional
        Rows of the design matrix per QR update (default: about :data:`BLOCK_ELEMENTS` elements).

    Returns
    -------
    FirFit

    Raises
    ------
    ValueError
        Bad shapes, non-finite values, negative lags, a bad number of folds, or fewer usable
        rows (per fold complement) than unknowns.
    """
    x, y = _as_2d(x, "x"), _as_2d(y, "y")
    n, m = x.shape
    if y.shape[0] != n:
        raise ValueError(f"x and y must have the same number of samples, got {n} and {y.shape[0]}")
    lead, lag, folds = int(lead), int(lag), int(folds)
    if lead < 0 or lag < 0:
        raise ValueError(f"lead and lag must be >= 0 samples, got {lead} and {lag}")
    if folds == 1 or folds < 0:
        raise ValueError(f"folds must be 0 (no cross-validation) or >= 2, got {folds}")
    taps = lead + lag + 1
    use = np.ones(n, dtype=bool) if rows is None else np.asarray(rows, dtype=bool).copy()
    if use.shape != (n,):
        raise ValueError(f"rows must be a boolean mask of shape ({n},), got {use.shape}")
    use[:lag] = False
    use[n - lead:] = False
    idx = np.flatnonzero(use)
    n_par = m * taps + 1
    parts = np.array_split(idx, folds) if folds else [idx]
    if idx.size - max(p.size for p in parts) * (folds > 0) < n_par:
        raise ValueError(f"{idx.size} usable samples for {n_par} unknowns"
                         f"{f' in {folds} folds' if folds else ''}; fix: fewer taps or a longer record")
    win = _windows(x, lead, lag)
    width = n_par + y.shape[1]
    step = int(block_rows) if block_rows else max(width, BLOCK_ELEMENTS // width)
    factors = [_factor(win, y, part, lag, step) for part in parts]
    coef, intercept = _solve(factors, m, taps)
    lags = np.arange(-lead, lag + 1)
    predicted = None
    if folds:
        predicted = np.full((n, y.shape[1]), np.nan)
        for k, part in enumerate(parts):
            c_k, i_k = _solve([f for j, f in enumerate(factors) if j != k], m, taps)
            predicted[part] = fir_filter(x, c_k, lags, i_k)[part]
    return FirFit(lags=lags, coefficients=coef, intercept=intercept, fitted=fir_filter(x, coef, lags, intercept),
                  rows=use, predicted_cv=predicted)


def fir_filter(x, coefficients, lags, intercept=None) -> np.ndarray:
    """Apply an affine FIR filter: ``intercept[q] + sum_k sum_j c[k, j, q] x[n - lags[k], j]``.

    Parameters
    ----------
    x : array_like, (n,) or (n, m)
    coefficients : array_like, (n_lags, m, p)
    lags : array_like of int, (n_lags,)
        Consecutive lags in samples (``-lead .. lag``).
    intercept : array_like, (p,), optional

    Returns
    -------
    numpy.ndarray, (n, p)
        NaN where the filter's window leaves the record.
    """
    x = _as_2d(x, "x")
    c = np.asarray(coefficients, dtype=float)
    lags = np.asarray(lags, dtype=int)
    if c.ndim != 3 or c.shape[:2] != (lags.size, x.shape[1]) or np.any(np.diff(lags) != 1):
        raise ValueError("coefficients must have shape (n_lags, m, p) for consecutive lags and m inputs")
    lead, lag = -int(lags[0]), int(lags[-1])
    n = x.shape[0]
    out = np.full((n, c.shape[2]), np.nan)
    win = _windows(x, lead, lag)  # row r: x[r + t] is the tap of lag (lag - t), output r + lag
    # coefficient of window column t is c[lag - t]; one output block at a time keeps memory low
    c_win = c[::-1].transpose(1, 0, 2).reshape(-1, c.shape[2])  # (m * taps, p), (j, t) order
    step = max(1, BLOCK_ELEMENTS // max(1, c_win.shape[0]))
    for start in range(0, win.shape[0], step):
        w = win[start:start + step]
        out[start + lag:start + lag + w.shape[0]] = w.reshape(w.shape[0], -1) @ c_win
    if intercept is not None:
        out += np.asarray(intercept, dtype=float)
    return out


@dataclass(frozen=True)
class LinearFloor:
    """The best linear (affine FIR) estimate of a reference force from measured forces.

    Attributes
    ----------
    coupled : bool
        False: per channel (channel i from channel i); True: each channel from all.
    lead, lag : int
        Non-causal and causal taps per input, samples.
    fitted : numpy.ndarray, (n, channels)
        The fitted estimate (NaN where the window leaves the record), same unit as the reference.
    rows : numpy.ndarray of bool, (n,)
        Samples fitted and scored.
    nrmse : numpy.ndarray, (channels,), 1
        :func:`rigsim.correction.metrics.dlc.nrmse` of ``fitted`` against the reference on ``rows`` (in-sample:
        the fit has seen these samples, so it also fits part of their noise).
    nrmse_cv : numpy.ndarray or None, (channels,), 1
        With ``folds``: the NRMSE of out-of-fold predictions (each contiguous fold of ``rows``
        predicted by the filter fitted on the others): what the filter does on data it has not
        seen. Close to ``nrmse`` when the filter has few taps for the record; above it when it
        starts to fit noise.
    """

    coupled: bool
    lead: int
    lag: int
    fitted: np.ndarray
    rows: np.ndarray
    nrmse: np.ndarray
    nrmse_cv: np.ndarray | None = None


def linear_floor(measured, reference, lead: int, lag: int, *, coupled: bool = False, rows=None,
                 folds: int = 0, block_rows: int | None = None) -> LinearFloor:
    """Fit and score the best linear estimate of ``reference`` from ``measured`` (see the module notes).

    Parameters
    ----------
    measured : array_like, (n, channels)
        The measured forces (e.g. the rig's, with the load cells' noise), N.
    reference : array_like, (n, channels)
        The forces to reach (e.g. the road's through the correction's band limit), N.
    lead, lag : int
        Non-causal and causal taps per input, samples.
    coupled : bool
        Fit each channel from all measured channels (True) or from its own (False).
    rows : array_like of bool, (n,), optional
        Samples to fit and score on (e.g. the correction's settled samples); the filter's
        window must also lie inside the record.
    folds : int
        0: in-sample only; >= 2: also the out-of-fold NRMSE over that many contiguous folds.
    block_rows : int, optional
        See :func:`fir_fit`.

    Returns
    -------
    LinearFloor
    """
    x, y = _as_2d(measured, "measured"), _as_2d(reference, "reference")
    if x.shape != y.shape:
        raise ValueError(f"measured and reference must have the same shape, got {x.shape} and {y.shape}")
    if coupled:
        fits = [fir_fit(x, y, lead, lag, rows=rows, folds=folds, block_rows=block_rows)]
    else:
        fits = [fir_fit(x[:, i], y[:, i], lead, lag, rows=rows, folds=folds, block_rows=block_rows)
                for i in range(x.shape[1])]
    fitted = np.hstack([f.fitted for f in fits])
    used = fits[0].rows  # the same for every channel: same mask, same window
    cv = None
    if folds:
        cv = nrmse(np.hstack([f.predicted_cv for f in fits])[used], y[used])
    return LinearFloor(coupled=bool(coupled), lead=int(lead), lag=int(lag), fitted=fitted, rows=used,
                       nrmse=nrmse(fitted[used], y[used]), nrmse_cv=cv)
