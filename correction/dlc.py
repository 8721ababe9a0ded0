"""Dynamic Load Coefficient (DLC) and per-wheel force statistics.

DLC = standard deviation / mean of a wheel force (Cebon 1999; the paper's quality figure).
"""

from __future__ import annotations

import numpy as np

__all__ = ["dlc", "force_statistics"]


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
