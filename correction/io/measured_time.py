"""The time axis of a measured record: uniform (each step within :data:`STEP_TOLERANCE` of the
record's step, no gap), at most :data:`MAX_RATE_HZ`, and its rate read within the axis's own
resolution (:func:`uniform_rate`, :func:`round_rate`).

Used by :mod:`rigsim.correction.io.measured_core` (a record is checked as it is built) and the readers
and writers; every refusal is one :class:`~rigsim.correction.io.measured_error.MeasuredDataError`
sentence naming the time column or argument, the place (file and line, or sample) and the fix.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from rigsim.correction.io.measured_error import MeasuredDataError

__all__ = ["MAX_RATE_HZ", "STEP_TOLERANCE", "RATE_ROUNDING", "uniform_rate", "checked_rate", "time_grid", "round_rate"]

#: Highest sampling rate of a measured record, float, Hz. A road simulator's controller plays and
#: records time histories at 102.4 to 2048 Hz on system rates up to 4096 Hz (MTS TestSuite
#: Multipurpose Elite User Manual, "Time History Controller Rates"); 1 MHz is far above any
#: rig's acquisition. A faster axis is a wrong time unit or a damaged file, and the correction
#: sizes its filters' impulse responses in samples of the step
#: (``rigsim.correction.output.correction_filter.transient_lengths``: GBs at 10 MHz).
MAX_RATE_HZ = 1e6
#: Largest difference of one step of a time axis from the record's step, as a fraction of it:
#: times rounded when written (a 1024 Hz axis in whole microseconds is off by 0.05 %) pass; a
#: jitter, or a step of two or more (a gap: samples missing), does not.
STEP_TOLERANCE = 0.01
#: Largest relative difference between the rate of a time axis and the rounder rate it is read
#: at (:func:`round_rate`), however coarsely its times are written.
RATE_ROUNDING = 1e-4
_BLOCK = 1 << 18  # samples of a time axis checked at once


def uniform_rate(t: np.ndarray, name: str, where: Callable[[int], str], what: str = "column") -> float:
    """Sampling rate (float, Hz) of a uniform time axis ``t`` (s), read within its own resolution.

    A step may differ from the median step by :data:`STEP_TOLERANCE` (rounding of the written
    times), not more: a jitter, or a gap (a step of about two or more: samples missing) is
    refused naming the first place, as is a rate above :data:`MAX_RATE_HZ`. The rate is
    ``(n - 1) / (t[-1] - t[0])``, rounded (:func:`round_rate`) within what the axis can tell
    apart: four times its largest deviation from that rate's line (or float64's spacing of its
    times, if larger) over its span, at most :data:`RATE_ROUNDING`. A 1 kHz axis at 86 400 s or
    1.7e9 s, or printed in whole microseconds, so reads at 1000 Hz exactly.

    Parameters
    ----------
    t : numpy.ndarray, shape (n,), s
    name : str
        The time column or argument, for messages.
    where : callable
        ``where(i)`` names sample ``i`` with its file (``"line 12 of 'rig.csv'"``, ``"time_s[12]"``).
    what : str
        What ``name`` is (``"column"``, ``"channel"``, ``"argument"``).

    Raises
    ------
    MeasuredDataError
        One sentence naming ``name``, the place and the fix.
    """
    return round_rate(*checked_rate(t, name, where, what))


def checked_rate(t: np.ndarray, name: str, where: Callable[[int], str], what: str) -> tuple[float, float]:
    """(rate of ``t``, Hz, unrounded; its relative tolerance) of a checked uniform axis
    (:func:`uniform_rate`), in blocks of :data:`_BLOCK` samples: memory beside ``t`` stays small."""
    n = t.size
    if n < 2:
        raise MeasuredDataError(f"{what} {name!r} has {n} samples; at least two are needed")
    for a in range(0, n, _BLOCK):
        bad = np.flatnonzero(~np.isfinite(t[a:a + _BLOCK]))
        if bad.size:
            raise MeasuredDataError(f"{what} {name!r} is {float(t[a + bad[0]])} at {where(a + int(bad[0]))}; fix: "
                                    "give a finite time (s) for every sample")
    dt = 0.0
    for typical in (False, True):  # first a step that is no step forward, then one off the typical step
        if typical:  # the median step of at most about two blocks of steps
            every = np.arange(0, n - 1, max(1, (n - 1) // _BLOCK))
            dt = float(np.median(t[every + 1] - t[every]))
        for a in range(0, n - 1, _BLOCK):
            steps = np.diff(t[a:a + _BLOCK + 1])
            off = np.flatnonzero(np.abs(steps - dt) > STEP_TOLERANCE * dt if typical else steps <= 0)
            if off.size:
                _refuse_step(t, a + int(off[0]) + 1, dt, name, where, what)
    span = float(t[-1] - t[0])
    rate = (n - 1) / span
    if rate > MAX_RATE_HZ:
        raise MeasuredDataError(f"{what} {name!r} steps {1 / rate:.3g} s at {where(1)}, a rate of {rate:.4g} Hz, above "
                                f"the {MAX_RATE_HZ:g} Hz of any rig's acquisition; fix: check the time's unit (ms or "
                                "us written as s) or decimate the record")
    step = span / (n - 1)
    deviation = max(float(np.max(np.abs((t[a:a + _BLOCK] - t[0]) - np.arange(a, min(a + _BLOCK, n)) * step)))
                    for a in range(0, n, _BLOCK))
    resolution = max(deviation, math.ulp(max(abs(float(t[0])), abs(float(t[-1])))))
    return rate, min(4.0 * resolution / span, RATE_ROUNDING)


def _refuse_step(t: np.ndarray, i: int, dt: float, name: str, where: Callable[[int], str], what: str):
    """The sentence refusing the step into sample ``i`` of ``t`` (s), the record's step being ``dt`` (s)."""
    if t[i] <= t[i - 1]:
        raise MeasuredDataError(f"{what} {name!r} does not increase at {where(i)} (t = {t[i]:.9g} s after "
                                f"{t[i - 1]:.9g} s); fix: sort the rows and remove duplicates")
    ratio = (t[i] - t[i - 1]) / dt
    step = (f"the step from t = {t[i - 1]:.9g} s is {t[i] - t[i - 1]:.6g} s, {ratio:.3g} times the record's step of "
            f"{dt:.6g} s")
    missing = round(ratio) - 1
    if missing >= 1:
        raise MeasuredDataError(f"{what} {name!r} is not uniform at {where(i)} (a gap, about {missing} "
                                f"sample{'s' if missing > 1 else ''} missing: {step}); fix: fill the gap (interpolate) "
                                "or cut the record there")
    raise MeasuredDataError(f"{what} {name!r} is not uniform at {where(i)} ({step}); fix: resample the record to a "
                            "uniform grid")


def time_grid(n: int, fs_hz: float, like: np.ndarray | None = None) -> np.ndarray:
    """``np.arange(n) / fs_hz`` (s, shape (n,)) for a rate ``fs_hz`` (Hz): ``like`` itself when it
    holds exactly that (compared in blocks), else one new array."""
    if like is not None and like.shape == (n,) and all(
            np.array_equal(like[a:a + _BLOCK], np.arange(a, min(a + _BLOCK, n), dtype=float) / fs_hz)
            for a in range(0, n, _BLOCK)):
        return like
    grid = np.arange(n, dtype=float)
    grid /= fs_hz
    return grid


def round_rate(fs_hz: float, tolerance: float) -> float:
    """The rate (float, Hz) with the fewest significant digits, written in Hz (``1024``,
    ``409.6``) or as a step in s (``0.0003``: 3333.33 Hz), within ``tolerance`` (relative) of
    ``fs_hz``; ``fs_hz`` when none is."""
    for digits in range(1, 17):
        for rate in (float(f"{fs_hz:.{digits}g}"), 1.0 / float(f"{1.0 / fs_hz:.{digits}g}")):
            if abs(rate - fs_hz) <= tolerance * fs_hz:
                return rate
    return fs_hz
