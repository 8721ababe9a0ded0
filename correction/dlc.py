"""Dynamic Load Coefficient (DLC), per-wheel force statistics and the NRMSE against a reference force.

DLC = standard deviation / mean of a wheel force (Cebon 1999; the paper's quality figure).
NRMSE = rms(force - reference) / std(reference): how far a force's time history is from the
reference force's, relative to the reference's dynamic part (this project's error figure of a
corrected or rig force against the band-limited road force; see :func:`nrmse`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["dlc", "force_statistics", "nrmse"]


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
    f = np.asarray(force_N, dtype=float)
    if f.shape[axis] < 2:
        raise ValueError("a DLC needs at least two force samples")
    if not np.all(np.isfinite(f)):
        raise ValueError("the wheel forces contain NaN or infinite values")
    mean = f.mean(axis=axis)
    if np.any(mean <= 0):
        raise ValueError("the mean wheel force must be positive (compression) to form a DLC")
    return f.std(axis=axis) / mean


def force_statistics(force_N, axis: int = 0) -> dict[str, np.ndarray]:
    """Mean (N), standard deviation (N) and DLC of wheel forces along ``axis``."""
    f = np.asarray(force_N, dtype=float)
    return {"mean_force_N": f.mean(axis=axis), "std_force_N": f.std(axis=axis), "dlc": dlc(f, axis=axis)}


def nrmse(x, reference, axis: int = 0) -> np.ndarray:
    """Normalized root-mean-square error of ``x`` against ``reference``, per column.

    ``sqrt(mean((x - reference)^2)) / std(reference)`` along ``axis``: the RMS of the error over
    the population standard deviation (ddof = 0) of the reference, i.e. the error relative to the
    reference's dynamic part (its mean, the static load, does not count in the denominator; a
    constant offset of ``x`` does count in the error). 0 is a perfect match; 1 is an error as large
    as the reference's own fluctuation, which is what ``x`` = the reference's mean would score.
    In this project the reference is the road force passed through the same band limit as the
    correction (:func:`correction.apply.band_limit`), and ``x`` the corrected or the rig's force.

    Parameters
    ----------
    x : array_like, N
        Forces to score; time runs along ``axis``.
    reference : array_like, N
        The reference forces, same shape as ``x``.
    axis : int
        Time axis.

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
    return np.sqrt(np.mean((a - r) ** 2, axis=axis)) / s
