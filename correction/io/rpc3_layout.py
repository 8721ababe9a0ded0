"""The numbers of an MTS RPC III header held to the file before they size anything, and its
samples held to the header's own limits.

Used by :mod:`rigsim.correction.io.rpc3` (the reader and writer); imports nothing of it.

* Counts (CHANNELS, PTS_PER_FRAME, PTS_PER_GROUP, FRAMES, SAMPLES) are whole numbers, exact for
  any number of digits; the values they lay out must be in the file (FRAMES), and SAMPLES may not
  exceed the frames present: more would read the last group's padding as data.
* DELTA_T is the step of a measured record (:data:`MIN_DELTA_T_S` to :data:`MAX_DELTA_T_S`),
  START_TIME a finite number (the time of the first sample, kept as metadata: the record's time
  axis starts at 0).
* The byte order: FORMAT names it, and LOWER_LIMIT.CHAN_n / UPPER_LIMIT.CHAN_n (the range of
  channel n in its units, which RPC and this module's writer record) say whether the data agree.
  When some channel's samples read in the declared order lie far outside its limits (by more than
  :data:`LIMIT_MARGIN` of their span) and every limited channel's samples read in the other order
  lie within them, FORMAT contradicts the data and the file is refused naming the key and the fix.
"""

from __future__ import annotations

import math
import re

import numpy as np

from rigsim.correction.io.measured_core import MeasuredDataError
from rigsim.correction.io.measured_time import MAX_RATE_HZ

__all__ = ["MIN_DELTA_T_S", "MAX_DELTA_T_S", "STEP_ROUNDING", "LIMIT_MARGIN", "REPAIR", "WHOLE", "fail", "count",
           "number", "layout", "times", "samples"]

#: Shortest and longest sampling step (DELTA_T, s) of a measured record: the rate cap of every
#: format (:data:`rigsim.correction.io.measured_core.MAX_RATE_HZ`, 1 MHz) and 0.1 Hz (slow channels
#: such as temperatures).
MIN_DELTA_T_S = 1.0 / MAX_RATE_HZ
MAX_DELTA_T_S = 10.0
#: A step printed with 7 significant digits from a float32 (9.999999e-07) is taken at its rate,
#: relative tolerance.
STEP_ROUNDING = 1e-6
#: How far (fraction of the larger of the limits' span and magnitudes) a sample may lie outside
#: LOWER_LIMIT/UPPER_LIMIT before the byte order is questioned: the limits of a file are its
#: samples' range or the channel's configured range, so a real sample lies within them.
LIMIT_MARGIN = 0.1
REPAIR = "fix: copy the file again from the rig's computer or repair its header in RPC"
WHOLE = re.compile(r"\+?[0-9]+")
#: What each number of the header gives, for the errors.
_MEANS = {"CHANNELS": "channels", "FRAMES": "frames", "PTS_PER_FRAME": "points in a frame",
          "PTS_PER_GROUP": "points in a group", "SAMPLES": "samples", "PARTITIONS": "partitions",
          "HALF_FRAMES": "half frames", "DELTA_T": "sampling step in s (1 / the sampling rate in Hz)",
          "START_TIME": "time of the first sample in s"}
_ORDERS = {"<": "BINARY_IEEE_LITTLE_END", ">": "BINARY_IEEE_BIG_END"}


def fail(path, text: str) -> MeasuredDataError:
    """The refusal of RPC III file ``path``: ``text`` completes the sentence."""
    return MeasuredDataError(f"RPC III file {str(path)!r} {text}")


def count(head, key, path, default=None) -> int:
    """Count ``key`` (``"12"``, ``"12.0"``, ``"1.2e1"``), exact for any number of digits."""
    text = head.get(key)
    if text is None:
        if default is None:
            raise fail(path, f"has no {key} key, so its data cannot be laid out; fix: add {key} = the number of "
                             f"{_MEANS[key]} it was recorded with")
        return default
    if WHOLE.fullmatch(text):
        return int(text)
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0 and value == int(value)):
        raise fail(path, f"has {key} = {text!r}, not a whole number of {_MEANS[key]}; fix: set {key} to the "
                         f"number of {_MEANS[key]} it was recorded with")
    return int(value)


def number(head, key, path) -> float:
    """The finite number ``key``."""
    text = head.get(key)
    if text is None:
        raise fail(path, f"has no {key} key; fix: add {key} = the {_MEANS[key]}")
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise fail(path, f"has {key} = {text!r}, not a finite number; fix: write the {_MEANS[key]} as {key}")
    return value


def layout(head, path, n_params: int, size: int, itemsize: int) -> tuple[int, int, int, int]:
    """(channels, points per group, groups, samples), each checked against what the file holds
    (``n_params`` header records, ``size`` bytes of data) before anything is allocated for it."""
    n_ch, ppf, ppg, frames = (count(head, k, path) for k in ("CHANNELS", "PTS_PER_FRAME", "PTS_PER_GROUP", "FRAMES"))
    if n_ch < 1:
        raise fail(path, "has CHANNELS = 0; fix: set CHANNELS to the number of channels recorded")
    if n_ch > n_params:  # each channel has records of its own: DESC.CHAN_n, SCALE.CHAN_n...
        raise fail(path, f"has CHANNELS = {head['CHANNELS']!r}, not a whole number of channels the file can hold "
                         f"(its header has {n_params} records, a channel needs its own DESC.CHAN_n, SCALE.CHAN_n); "
                         "fix: set CHANNELS to the number of channels recorded")
    if ppf < 1 or ppg < ppf or ppg % ppf:
        raise fail(path, f"has PTS_PER_FRAME {ppf} and PTS_PER_GROUP {ppg}, which do not describe a record (a "
                         "group is a whole number of frames of at least one point); fix: set them as recorded")
    groups = -(-frames // (ppg // ppf))
    need = groups * ppg * n_ch * itemsize  # Python ints: no overflow
    if need > size:
        raise fail(path, f"is truncated: its header asks for {groups * ppg * n_ch} values (CHANNELS {n_ch} x "
                         f"PTS_PER_GROUP {ppg} x {groups} groups of FRAMES {frames}), {need} bytes, but the file "
                         f"holds {size} bytes of data; fix: check FRAMES and CHANNELS or copy the whole file again")
    n = frames * ppf
    if "SAMPLES" in head:
        recorded = count(head, "SAMPLES", path)
        if recorded > n:
            raise fail(path, f"has SAMPLES = {head['SAMPLES']!r} but its FRAMES {frames} x PTS_PER_FRAME {ppf} hold "
                             f"{n} samples (the rest of the last group is padding, not data); fix: set SAMPLES to "
                             f"the samples recorded (at most {n}) or copy the whole file again")
        n = recorded
    return n_ch, ppg, groups, n


def times(head, path) -> tuple[float, float]:
    """(DELTA_T, START_TIME), s: the step of a measured record and the time of the first sample."""
    dt = number(head, "DELTA_T", path)
    if not (MIN_DELTA_T_S <= dt * (1 + STEP_ROUNDING) and dt <= MAX_DELTA_T_S):
        raise fail(path, f"has DELTA_T = {head['DELTA_T']!r} s, not the sampling step of a measured record "
                         f"({MIN_DELTA_T_S:g} to {MAX_DELTA_T_S:g} s, 1 MHz to 0.1 Hz); fix: write the step in s "
                         "(1 / the sampling rate in Hz) as DELTA_T")
    return dt, (number(head, "START_TIME", path) if "START_TIME" in head else 0.0)


def samples(raw: bytes, head, path, dtype: np.dtype, offset: int, shape: tuple[int, int, int], n: int,
            scales, names) -> np.ndarray:
    """The data (channels, ``n`` samples), scaled by ``scales`` (int16) or None (float32), of
    ``shape`` (channels, points per group, groups) at ``offset`` of ``raw``, read in ``dtype``;
    refused when FORMAT's byte order contradicts the limits, or a sample is not finite."""
    n_ch, ppg, groups = shape

    def channels(order: np.dtype) -> np.ndarray:
        block = np.frombuffer(raw, dtype=order, count=groups * ppg * n_ch, offset=offset)
        return block.reshape(groups, n_ch, ppg).transpose(1, 0, 2).reshape(n_ch, groups * ppg)[:, :n]

    data = channels(dtype).astype(float)
    if scales is not None:
        with np.errstate(over="ignore"):  # an overflow is reported below, naming the channel
            data *= scales[:, None]
    _check_order(raw, head, path, dtype, data, scales, names, channels)
    if data.size and not (math.isfinite(data.max()) and math.isfinite(data.min())):  # NaN propagates: no mask
        c, i = divmod(int(np.argmax(~np.isfinite(data))), n)
        why = f"its counts times SCALE.CHAN_{c + 1} = {head[f'SCALE.CHAN_{c + 1}']!r} exceed float64" if (
            scales is not None) else "a float32 sample that is not finite"
        dt, start = times(head, path)
        raise fail(path, f"has the value {data[c, i]} in channel {names[c]!r} (DESC.CHAN_{c + 1}) at sample {i} "
                         f"(t = {start + i * dt:.9g} s), {why}; fix: remove or interpolate it in RPC")
    return data


def _limits(head, c: int) -> tuple[float, float, float] | None:
    """(LOWER_LIMIT, UPPER_LIMIT, margin) of channel ``c`` (from 1), None when not both given."""
    try:
        lo, hi = float(head[f"LOWER_LIMIT.CHAN_{c}"]), float(head[f"UPPER_LIMIT.CHAN_{c}"])
    except (KeyError, ValueError):
        return None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
        return None
    return lo, hi, LIMIT_MARGIN * max(hi - lo, abs(lo), abs(hi))


def _within(lo: float, hi: float, margin: float, low: float, high: float) -> bool:
    return lo - margin <= low and high <= hi + margin  # False for NaN


def _check_order(raw, head, path, dtype, data, scales, names, channels) -> None:
    """Refuse the file when its samples lie far outside the limits read in ``dtype``'s byte order
    and within them read in the other (:data:`LIMIT_MARGIN`); one channel at a time."""
    limited = {c: lim for c in range(data.shape[0]) if (lim := _limits(head, c + 1)) is not None}
    if not limited or not data.shape[1]:
        return
    lows, highs = data.min(axis=1), data.max(axis=1)
    outside = [c for c, (lo, hi, m) in limited.items() if not _within(lo, hi, m, lows[c], highs[c])]
    if not outside:
        return
    other = dtype.newbyteorder()
    swapped = channels(other)
    for c, (lo, hi, m) in limited.items():
        low, high = float(swapped[c].min()), float(swapped[c].max())
        if scales is not None:
            low, high = sorted((low * scales[c], high * scales[c]))
        if not _within(lo, hi, m, low, high):
            return
    c = outside[0]
    lo, hi, _ = limited[c]
    declared, fix = head["FORMAT"], _ORDERS[other.str[0]]
    raise fail(path, f"has FORMAT = {declared!r}, but its samples read so lie far outside the file's own limits "
                     f"(channel {names[c]!r}: {lows[c]:.6g} to {highs[c]:.6g} for LOWER_LIMIT.CHAN_{c + 1} = {lo:g} "
                     f"and UPPER_LIMIT.CHAN_{c + 1} = {hi:g}) and within them in the other byte order; fix: set "
                     f"FORMAT to {fix!r} in RPC's header editor")
