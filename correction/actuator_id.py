"""``T_a`` identified from a rig run's drive and pan displacement, shaped for the correction.

A lab that does not know its hydraulic parameters can still correct: the H1 estimate of the
drive-to-pan frequency response (:func:`correction.identify.h1_estimate`) is fitted with eq. 4's
shape, one zero and four poles (:func:`correction.identify.fit_rational`), weighted by the
coherence (``sqrt(coh / (1 - coh))``, the inverse standard deviation of the H1 estimate).

The static gain is anchored: an actuator with integral action follows its drive at steady state,
``T_a(0) = 1``, but eq. 4's slow pole-zero pair (near 1 rad/s, 0.16 Hz) lies below the H1
estimate's first bins, and a free fit puts it anywhere (static gains 0.98-1.09 on 30-120 s
records, which then scale every corrected force). Three points ``H = 1`` at 1, 2 and 5 % of the
frequency resolution, with the largest weight, pin it; the remaining error is below 1 % from
0.05 to 20 Hz on simulated eq.-4 rigs, and the correction then scales ``T_a(0)`` to exactly 1.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["identify_actuator"]

#: numerator / denominator orders of the identified T_a: eq. 4's shape
EQ4_ORDERS = (1, 4)


def identify_actuator(drive_m, displacement_m, fs: float, *, f_max_hz: float | None = None,
                      nperseg: int | None = None, orders: tuple[int, int] = EQ4_ORDERS):
    """Identify ``T_a = X_a / X_p`` from a drive record and the measured pan displacement.

    Parameters
    ----------
    drive_m : array_like, m
        The rig's drive ``x_p`` (the profile sent to the actuator), shape (n,).
    displacement_m : array_like, m
        Measured pan displacement ``x_a``, sampled with ``drive_m``.
    fs : float, Hz
        Sampling rate.
    f_max_hz : float, Hz, optional
        Highest frequency fitted (default ``min(0.4 fs, 80 Hz)``, which covers eq. 4's oil-column
        mode of DYNTRAC-sized actuators).
    nperseg : int, optional
        Welch segment length (default: about 8 s, at least 8 segments in the record).
    orders : (int, int)
        Numerator and denominator orders of the fit (default: eq. 4's shape, 1 and 4).

    Returns
    -------
    control.TransferFunction
        Continuous, stable, one zero and four poles (s in rad/s), ``T_a(0)`` close to 1.

    Raises
    ------
    ValueError
        From the estimate or the fit (record too short, too few usable frequencies).
    """
    from . import identify  # the H1 estimator and the rational fit

    u = np.asarray(drive_m, dtype=float)
    y = np.asarray(displacement_m, dtype=float)
    n = u.shape[0]
    if nperseg is None:
        nperseg = int(min(2 ** round(math.log2(fs * 8.0)), max(8, n // 8)))
    f, h, coh = identify.h1_estimate(u, y, fs, nperseg)
    c = np.clip(np.nan_to_num(coh), 0.0, 0.999)
    weight = np.sqrt(c / (1.0 - c))
    resolution = fs / nperseg
    anchor_f = resolution * np.array([0.01, 0.02, 0.05])
    top = float(np.max(weight)) if np.any(weight > 0) else 1.0
    f = np.concatenate([anchor_f, f])
    h = np.concatenate([np.ones(anchor_f.size, dtype=complex), h])
    weight = np.concatenate([np.full(anchor_f.size, top), weight])
    f_max = min(0.4 * fs, 80.0) if f_max_hz is None else float(f_max_hz)
    return identify.fit_rational(f, h, orders[0], orders[1], weight=weight, f_max=f_max)
