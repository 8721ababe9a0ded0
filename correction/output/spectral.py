"""A record through a gain given on its spectrum, offline.

The record is padded at each end by odd reflection (level and slope continuous at the ends, so
the padded record's period has no jump), transformed, multiplied by the gain at each frequency,
transformed back and cut to its own samples. Non-causal: for records already taken.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["through_gain"]


def through_gain(x, fs_hz: float, gain, pad_s: float) -> np.ndarray:
    """``x`` through ``gain`` applied to its spectrum.

    Parameters
    ----------
    x : array_like, (n,) or (n, k)
        The record, time along axis 0, any unit.
    fs_hz : float, Hz
        Its rate.
    gain : callable
        ``gain(f_hz)`` for the frequencies ``f_hz`` (Hz, (m,), 0 to ``fs_hz / 2``): the complex or
        real gain at each, (m,) for every column alike or (m, k) per column.
    pad_s : float, s
        Odd reflection padded to each end (at most the record's length): longer than the
        gain's impulse response, so that neither end leaks into the other.

    Returns
    -------
    numpy.ndarray
        Same shape and unit as ``x``.
    """
    x = np.asarray(x, dtype=float)
    n = x.shape[0]
    pad = min(n - 1, int(math.ceil(pad_s * fs_hz)))
    if pad > 0:
        head = 2.0 * x[:1] - x[pad:0:-1]
        tail = 2.0 * x[-1:] - x[-2:-pad - 2:-1]
        padded = np.concatenate([head, x, tail], axis=0)
    else:
        padded = x
    m = padded.shape[0]
    f = np.fft.rfftfreq(m, 1.0 / fs_hz)
    g = np.asarray(gain(f))
    if g.ndim == 1:
        g = g.reshape(-1, *([1] * (x.ndim - 1)))
    y = np.fft.irfft(np.fft.rfft(padded, axis=0) * g, n=m, axis=0)
    return y[pad:pad + n]
