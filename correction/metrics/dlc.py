"""Dynamic Load Coefficient (DLC), per-wheel force statistics and the NRMSE against a reference force.

DLC = standard deviation / mean of a wheel force (Cebon 1999; the paper's quality figure).
NRMSE = rms(force - reference) / std(reference): how far a force's time history is from the
reference force's, relative to the reference's dynamic part (this project's error figure of a
corrected or rig force against the band-limited road force; see :func:`nrmse`).

Along the time axis of an (n, k) record the statistics need no temporary as large as the record
(19 MB for 600 s of four wheel forces at 1 kHz): :func:`column_sum` maps and sums it block by
block, with exactly numpy's result.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BLOCK_ROWS", "column_sum", "dlc", "force_statistics", "nrmse"]

#: Rows of a record that :func:`column_sum` maps at a time (1 MB of four float64 columns).
BLOCK_ROWS = 2 ** 15


def column_sum(f: np.ndarray, fn=None, block_rows: int = BLOCK_ROWS) -> np.ndarray:
    """``numpy.sum(fn(f), axis=0)`` bit for bit, with ``fn`` applied to ``block_rows`` rows at a time.

    NumPy sums a C-contiguous (n, k) array with k >= 2 along axis 0 row after row, one running
    sum per column (no pairwise summation across rows). So the blocks are mapped into one buffer
    whose first row carries the running sum of the rows before: the same numbers are added in
    the same order. Any other input (1-D, one column, not C-contiguous: numpy orders those
    sums differently) is mapped and summed whole.

    Parameters
    ----------
    f : numpy.ndarray
        The record, (n, k), time along axis 0.
    fn : callable, optional
        Elementwise map: ``fn(b)`` has the shape of the block ``b`` of rows of ``f``, each value
        depending only on the value of ``b`` at the same place. Default: the identity.
    block_rows : int
        Rows mapped at a time (>= 1).

    Returns
    -------
    numpy.ndarray
        Shape (k,), in the units of ``fn(f)``.
    """
    fn = (lambda b: b) if fn is None else fn
    if f.ndim != 2 or f.shape[1] < 2 or not f.flags.c_contiguous or f.shape[0] <= block_rows:
        return np.sum(fn(f), axis=0)
    first = fn(f[:block_rows])
    buf = np.empty((block_rows + 1, f.shape[1]), dtype=first.dtype)
    buf[:block_rows] = first
    del first
    total = np.sum(buf[:block_rows], axis=0)
    for i in range(block_rows, f.shape[0], block_rows):
        m = min(block_rows, f.shape[0] - i)
        buf[0] = total
        buf[1:m + 1] = fn(f[i:i + m])
        total = np.sum(buf[:m + 1], axis=0)
    return total


def _mean_std(f: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """``f.mean(axis=axis)`` and ``f.std(axis=axis)`` (ddof = 0), bit for bit; along axis 0 of
    an (n, k) record without numpy's temporary ``f - mean`` as large as ``f``."""
    mean = f.mean(axis=axis)
    if f.ndim != 2 or axis not in (0, -2):
        return mean, f.std(axis=axis)
    # numpy's _var: square(f - mean) summed along the axis, over n; the std its square root
    return mean, np.sqrt(column_sum(f, lambda b: np.square(b - mean)) / f.shape[0])


def dlc(force_N, axis: int = 0) -> np.ndarray:
    """Dynamic Load Coefficient of wheel-force time series.

    Parameters
    ----------
    force_N : array_like, N
        Wheel forces; time runs along ``axis``.
    axis : int
        Time axis.

    Returns
    -------
    numpy.ndarray
        std / mean along ``axis`` (population standard deviation, ddof = 0), dimensionless.

    Raises
    ------
    ValueError
        If the forces contain NaN or infinity, or a mean force is not positive (a DLC of a
        signal that is not a compressive wheel load has no meaning).
    """
    mean, std = _checked_mean_std(force_N, axis)
    return std / mean


def _checked_mean_std(force_N, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Mean and std (N) of wheel forces along ``axis``, refused as :func:`dlc` documents."""
    f = np.asarray(force_N, dtype=float)
    if f.shape[axis] < 2:
        raise ValueError("a DLC needs at least two force samples")
    if not np.all(np.isfinite(f)):
        raise ValueError("the wheel forces contain NaN or infinite values")
    mean, std = _mean_std(f, axis)
    if np.any(mean <= 0):
        raise ValueError("the mean wheel force must be positive (compression) to form a DLC")
    return mean, std


def force_statistics(force_N, axis: int = 0) -> dict[str, np.ndarray]:
    """Mean (N), standard deviation (N, ddof = 0) and DLC of wheel forces along ``axis`` (refused
    as :func:`dlc` documents)."""
    mean, std = _checked_mean_std(force_N, axis)
    return {"mean_force_N": mean, "std_force_N": std, "dlc": std / mean}


def nrmse(x, reference, axis: int = 0, *, mean_free: bool = False) -> np.ndarray:
    """Normalized root-mean-square error of ``x`` against ``reference``, per column.

    ``sqrt(mean((x - reference)^2)) / std(reference)`` along ``axis``: the RMS of the error over
    the population standard deviation (ddof = 0) of the reference, i.e. the error relative to the
    reference's dynamic part (its mean, the static load, does not count in the denominator; a
    constant offset of ``x`` does count in the error). 0 is a perfect match; 1 is an error as large
    as the reference's own fluctuation, which is what ``x`` = the reference's mean would score.
    In this project the reference is the road force passed through the same band limit as the
    correction (:func:`rigsim.correction.output.apply.band_limit`), and ``x`` the corrected or the rig's force.

    Parameters
    ----------
    x : array_like, N
        Forces to score; time runs along ``axis``.
    reference : array_like, N
        The reference forces, same shape as ``x``.
    axis : int
        Time axis.
    mean_free : bool
        Leave the error's mean out: ``rms(e - mean(e)) / std(reference)``, ``e = x - reference``
        (the static level, which a drive iteration does not control, does not count; the drive
        iteration's :func:`rigsim.correction.input.convergence.dynamic_error`).

    Returns
    -------
    numpy.ndarray
        NRMSE along ``axis``, dimensionless (a 0-d array for 1-D input).

    Raises
    ------
    ValueError
        If the shapes differ, there are fewer than two samples, a value is NaN or infinite, or
        a reference column is constant (std 0: the NRMSE is undefined).
    """
    a = np.asarray(x, dtype=float)
    r = np.asarray(reference, dtype=float)
    if a.shape != r.shape:
        raise ValueError(f"x and reference must have the same shape, got {a.shape} and {r.shape}")
    if a.ndim == 0 or a.shape[axis] < 2:
        raise ValueError("an NRMSE needs at least two samples")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(r))):
        raise ValueError("the forces contain NaN or infinite values")
    s = r.std(axis=axis)
    if np.any(s == 0):
        raise ValueError("the reference force is constant (std 0) in a column, so its NRMSE is undefined")
    e = a - r
    if mean_free:
        e = e - e.mean(axis=axis, keepdims=True)
    return np.sqrt(np.mean(e ** 2, axis=axis)) / s
