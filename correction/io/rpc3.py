"""MTS RPC III time-history files (.rsp responses, .drv drives, .tim, .rpc): read and write.

Own code, not a package: of the two on PyPI, ``rpc-reader`` 0.9 only reads, prints to stdout,
calls ``sys.exit`` on a bad file, starts its time at DELTA_T, scales by an extra
INT_FULL_SCALE/32768 (0.05 % off rpc3-file and FEDEM's FiRPC3File, 16 steps at full scale) and
reads a partly filled last group as if it were not padded; ``rpc3-file`` 1.0.0rc6 (a
pre-release) reads and writes correctly but draws tqdm progress bars unless a module global is
changed, returns float32 (a read-back then exceeds half a step by the float32 rounding), turns a
unit "1" into the integer 1, fails with a KeyError on a file without LOWER_LIMIT/UPPER_LIMIT
keys and with a TypeError on ``DELTA_T = 1e-05``, and without SAMPLES trims the record by a guess
on repeated end values. The layout is small; the tests cross-check this module against
rpc3-file both ways and against rpc-reader (its scale factor taken out).

Layout (as both packages and FEDEM read it): a header of 128-byte records, each a 32-byte key and a
96-byte value (latin-1, NUL-padded), in 512-byte blocks; the first three records are FORMAT,
NUM_HEADER_BLOCKS and NUM_PARAMS. Then the data in groups: each group holds, channel after
channel, PTS_PER_GROUP points (FRAMES of PTS_PER_FRAME points, the last group padded), as int16
(DATA_TYPE SHORT_INTEGER, value = integer * SCALE.CHAN_n) or float32 (FLOATING_POINT). Channel n
is named by DESC.CHAN_n, its unit is UNITS.CHAN_n; DELTA_T is the sampling step in s. SAMPLES,
when present, is the record length (else FRAMES * PTS_PER_FRAME). Files of one partition only;
HALF_FRAMES files and ASCII files are refused.

The reader takes no count of the header on trust, so that a damaged or hostile file costs no more
time and memory than its own bytes: CHANNELS is at most the number of header records (a channel
has records of its own, DESC.CHAN_n, SCALE.CHAN_n), and the data the counts lay out must be in
the file, before anything is sized by them, and SAMPLES may not exceed the frames present.
DELTA_T must be the step of a measured record (:data:`MIN_DELTA_T_S` to :data:`MAX_DELTA_T_S`),
START_TIME a finite number, SCALE.CHAN_n finite and not 0, every sample finite, and the byte
order of FORMAT not contradicted by the channels' LOWER_LIMIT/UPPER_LIMIT
(:mod:`rigsim.correction.io.rpc3_layout`). A key given twice with two values is refused (either could
be meant); the same value given twice is read once, as it reads the same whichever record is
taken.

The writer quantizes each channel to int16 with SCALE = max|x| / 32752 (the INT_FULL_SCALE of
MTS and rpc3-file), written exactly, so a read-back is within half a step (SCALE / 2) of the data.
It writes whole groups only (FRAMES a multiple of the frames per group, padded with the last
value; SAMPLES gives the length), so that readers that differ on a partly filled last group agree.
"""

from __future__ import annotations

import datetime
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rigsim.correction.io.measured_core import MeasuredDataError, read_bytes
from rigsim.correction.io.rpc3_layout import (MAX_DELTA_T_S, MIN_DELTA_T_S, REPAIR, STEP_ROUNDING, WHOLE, count, fail, layout,
                                              samples, times)

__all__ = ["INT_FULL_SCALE", "MIN_DELTA_T_S", "MAX_DELTA_T_S", "STEP_ROUNDING", "TIME_RESOLUTION", "Rpc3Data",
           "read_rpc3", "write_rpc3", "STRUCTURAL_KEYS", "BYTE_ORDERS"]

INT_FULL_SCALE = 32752
#: Largest float64 spacing of the times START_TIME + i DELTA_T the writer's files give, as a
#: fraction of DELTA_T: coarser, a reader that takes the times as written sees steps that are not
#: uniform (this module's reader keeps START_TIME as metadata and starts the times at 0).
TIME_RESOLUTION = 1e-3
_RECORD, _KEY, _BLOCK = 128, 32, 512
_CHAN_KEY = re.compile(r"^(SCALE|MAP|LOWER_LIMIT|UPPER_LIMIT|DESC|UNITS)\.CHAN_\d+$|^PART\.N?CHAN_\d+$")
#: Keys the writer derives from the data (given metadata with these names is not written).
STRUCTURAL_KEYS = frozenset({"FORMAT", "NUM_HEADER_BLOCKS", "NUM_PARAMS", "FILE_TYPE", "CHANNELS", "DELTA_T",
                             "PTS_PER_FRAME", "PTS_PER_GROUP", "FRAMES", "SAMPLES", "DATA_TYPE", "INT_FULL_SCALE",
                             "PARTITIONS", "HALF_FRAMES", "START_TIME", "BYPASS_FILTER", "REPEATS"})


#: FORMAT -> the byte order of the samples: ``"<"`` little-endian, ``">"`` big-endian (only binary files are read).
BYTE_ORDERS = {"BINARY": "<", "BINARY_IEEE_LITTLE_END": "<", "BINARY_IEEE_BIG_END": ">"}


def is_structural(key: str) -> bool:
    return key in STRUCTURAL_KEYS or bool(_CHAN_KEY.match(key))


@dataclass(frozen=True)
class Rpc3Data:
    """One RPC III file: channels ``data[k]`` named ``names[k]`` in ``units[k]`` (as written).

    Attributes
    ----------
    names, units : tuple of str
    data : numpy.ndarray, shape (channels, samples), in the file's units (scaled), finite
    dt_s : float, s
        DELTA_T, within [:data:`MIN_DELTA_T_S`, :data:`MAX_DELTA_T_S`].
    start_s : float, s
        START_TIME of this module's writer, else 0.
    header : Mapping[str, str]
        Every header key and value, as written.
    """

    names: tuple
    units: tuple
    data: np.ndarray
    dt_s: float
    start_s: float
    header: Mapping


def _header(raw: bytes, path) -> dict[str, str]:
    """Every header key -> value; a key given twice with two values is refused, a repeat of the
    same value is kept once (the file reads the same whichever record is taken)."""
    def record(i: int) -> tuple[str, str]:
        rec = raw[i * _RECORD:(i + 1) * _RECORD]
        if len(rec) < _RECORD:
            raise fail(path, f"ends inside its header, at record {i + 1}; the file is truncated; {REPAIR}")
        key, value = rec[:_KEY], rec[_KEY:]
        return (key.split(b"\0", 1)[0].decode("latin-1").strip(),
                value.split(b"\0", 1)[0].decode("latin-1").strip())

    first = [record(i) for i in range(3)]
    if [k for k, _ in first] != ["FORMAT", "NUM_HEADER_BLOCKS", "NUM_PARAMS"]:
        raise fail(path, "does not start with FORMAT, NUM_HEADER_BLOCKS, NUM_PARAMS; it is not an RPC III file")
    if not (WHOLE.fullmatch(first[1][1]) and WHOLE.fullmatch(first[2][1])):
        raise fail(path, f"has NUM_HEADER_BLOCKS = {first[1][1]!r} and NUM_PARAMS = {first[2][1]!r}, which are "
                          f"not both whole numbers; {REPAIR}")
    blocks, n_params = int(first[1][1]), int(first[2][1])
    if not 3 <= n_params <= blocks * _BLOCK // _RECORD:
        raise fail(path, f"has NUM_PARAMS {n_params} for {blocks} header blocks (3 to {blocks * 4} records); the "
                          f"header is damaged; {REPAIR}")
    if blocks * _BLOCK > len(raw):
        raise fail(path, f"has NUM_HEADER_BLOCKS = {blocks} ({blocks * _BLOCK} bytes) but the file has "
                          f"{len(raw)} bytes; {REPAIR}")
    head: dict[str, str] = {}
    for i in range(n_params):
        k, v = record(i)
        if k and head.setdefault(k, v) != v:
            raise fail(path, f"gives {k} twice, as {head[k]!r} and as {v!r}, and either could be meant; fix: "
                              "delete the wrong record in RPC's header editor")
    return head


def _scale(head, path, c: int, name: str) -> float:
    text = head.get(f"SCALE.CHAN_{c}")
    try:
        scale = float(text)
    except (TypeError, ValueError):
        scale = math.nan
    if not math.isfinite(scale) or scale == 0:
        what = f"no SCALE.CHAN_{c} key" if text is None else f"SCALE.CHAN_{c} = {text!r}"
        raise fail(path, f"has {what} for channel {name!r} (DESC.CHAN_{c}), so its int16 counts give "
                          f"no values; fix: write the channel's units per count as SCALE.CHAN_{c}")
    return scale


def read_rpc3(path) -> Rpc3Data:
    """Read an RPC III time-history file.

    Every count of the header is checked against what the file holds before it sizes anything,
    so a damaged or hostile header costs no more time and memory than the file's own bytes.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    Rpc3Data

    Raises
    ------
    MeasuredDataError
        One sentence naming the file and the key or channel at fault, and the fix: not an RPC III
        time history, a count that is not a whole number or more than the file holds (SAMPLES
        beyond the frames present), a key given twice with two values, DELTA_T outside
        [:data:`MIN_DELTA_T_S`, :data:`MAX_DELTA_T_S`] s, a START_TIME that is not a finite
        number, a zero or non-finite SCALE.CHAN_n, a FORMAT whose byte order the channels'
        LOWER_LIMIT/UPPER_LIMIT contradict, a NaN or infinite sample
        (:mod:`rigsim.correction.io.rpc3_layout`).
    """
    raw = read_bytes(path, memory_per_byte=9.0)  # 8.9 measured: the bytes, int16 to float64, scaled
    head = _header(raw, path)
    fmt = head["FORMAT"].upper()
    order = BYTE_ORDERS.get(fmt)
    if order is None:
        raise fail(path, f"has FORMAT {head['FORMAT']!r}; only binary files can be read; fix: convert it to "
                          "BINARY in RPC")
    if head.get("FILE_TYPE", "TIME_HISTORY").upper() != "TIME_HISTORY":
        raise fail(path, f"has FILE_TYPE {head['FILE_TYPE']!r}, not TIME_HISTORY; fix: give a time history "
                          "(.rsp, .drv, .tim)")
    kind = head.get("DATA_TYPE", "SHORT_INTEGER").upper()
    if kind not in ("SHORT_INTEGER", "FLOATING_POINT"):
        raise fail(path, f"has DATA_TYPE {head['DATA_TYPE']!r}; fix: export it from RPC as SHORT_INTEGER or "
                          "FLOATING_POINT")
    if count(head, "PARTITIONS", path, 1) != 1 or count(head, "HALF_FRAMES", path, 0) != 0:
        raise fail(path, f"has PARTITIONS = {head.get('PARTITIONS', '1')!r} and HALF_FRAMES = "
                          f"{head.get('HALF_FRAMES', '0')!r}, a layout this reader does not read; fix: export it "
                          "from RPC with one partition and whole frames")
    dtype = np.dtype(order + ("i2" if kind == "SHORT_INTEGER" else "f4"))
    offset = int(head["NUM_HEADER_BLOCKS"]) * _BLOCK
    n_ch, ppg, groups, n = layout(head, path, int(head["NUM_PARAMS"]), len(raw) - offset, dtype.itemsize)
    dt, start = times(head, path)
    names = tuple(head.get(f"DESC.CHAN_{c}", "") or f"CHAN_{c}" for c in range(1, n_ch + 1))
    units = tuple(head.get(f"UNITS.CHAN_{c}", "") for c in range(1, n_ch + 1))
    scales = None
    if kind == "SHORT_INTEGER":
        scales = np.array([_scale(head, path, c + 1, names[c]) for c in range(n_ch)])
    if groups == 0:  # no frames: nothing to lay out (the sizes of a group need not be array sizes)
        data = np.zeros((n_ch, 0))
    else:
        data = samples(raw, head, path, dtype, offset, (n_ch, ppg, groups), n, scales, names)
    return Rpc3Data(names=names, units=units, data=data, dt_s=dt, start_s=start, header=dict(head))


def _check_text(key: str, value: str, path) -> None:
    for what, text, limit in (("key", key, _KEY), ("value", value, _RECORD - _KEY)):
        try:
            size = len(text.encode("latin-1"))
        except UnicodeEncodeError:
            raise MeasuredDataError(f"header {what} {text!r} for {str(path)!r} has characters outside latin-1; "
                                    "RPC III cannot store it") from None
        if any(c in text for c in "\n\r\0"):
            raise MeasuredDataError(f"header {what} {text!r} for {str(path)!r} has a line break or NUL; RPC III "
                                    "keeps one line per value; shorten it to one line")
        if size > limit or (what == "key" and not text):
            raise MeasuredDataError(f"header {what} {text!r} for {str(path)!r} is {size} bytes; RPC III allows "
                                    f"1 to {limit} for a {what}; shorten it")


def _num(x: float) -> str:
    """Shortest exact decimal, with a point (``1e-05`` -> ``0.00001``, ``1e-226`` -> ``1.0e-226``):
    some readers take a value without a point for an integer."""
    text = np.format_float_positional(float(x), trim="0")
    return text if len(text) <= 40 else np.format_float_scientific(float(x), trim="0")


def write_rpc3(path, names: Sequence[str], units: Sequence[str], data: np.ndarray, dt_s: float, *,
               start_s: float = 0.0, time_type: str = "RESPONSE", extra: Mapping[str, str] | None = None,
               pts_per_frame: int = 1024, frames_per_group: int = 2, dest=None) -> None:
    """Write channels ``data`` (shape (channels, samples)) as an int16 RPC III time history.

    Parameters
    ----------
    path : str or os.PathLike
        Named in errors; the bytes go to ``dest`` (a path) when given, else to ``path``.
    names, units : sequence of str
        DESC.CHAN_n and UNITS.CHAN_n (at most 96 latin-1 bytes each).
    data : numpy.ndarray, shape (channels, samples), finite
    dt_s : float, s
        DELTA_T.
    start_s : float, s
        Time of the first sample, written as START_TIME (a key of this module) when not 0.
    time_type : str
        TIME_TYPE: ``"RESPONSE"`` (.rsp, .tim) or ``"DRIVE"`` (.drv).
    extra : Mapping[str, str]
        More header keys (keys up to 32, values up to 96 latin-1 bytes); keys the writer derives from
        the data (:data:`STRUCTURAL_KEYS`, ``*.CHAN_n``) are skipped.
    """
    data = np.atleast_2d(np.asarray(data, dtype=float))
    n_ch, n = data.shape
    if n_ch < 1 or n < 1 or len(names) != n_ch or len(units) != n_ch:
        raise MeasuredDataError(f"RPC III file {str(path)!r} needs one name and unit per channel and samples")
    if not np.all(np.isfinite(data)):
        raise MeasuredDataError(f"RPC III file {str(path)!r} cannot hold a NaN or infinite sample; remove or "
                                "interpolate it")
    last = max(abs(start_s), abs(start_s + (n - 1) * dt_s))
    if not (math.isfinite(last) and MIN_DELTA_T_S <= dt_s <= MAX_DELTA_T_S
            and math.ulp(last) <= TIME_RESOLUTION * dt_s):
        raise MeasuredDataError(f"RPC III file {str(path)!r} cannot hold a record sampled every {dt_s:g} s from "
                                f"{start_s:g} s, which its readers refuse (steps of {MIN_DELTA_T_S:g} to "
                                f"{MAX_DELTA_T_S:g} s, times float64 tells apart); resample the record or start its "
                                "time near 0")
    ppg = pts_per_frame * frames_per_group
    groups = -(-n // ppg)
    frames = groups * frames_per_group  # whole groups: readers differ on a partly filled last one
    absmax = np.max(np.abs(data), axis=1)
    scales = absmax / INT_FULL_SCALE
    scales[~(scales > 0)] = 1.0  # all zeros, or a peak so small its step underflows: every count is 0
    head: dict[str, str] = {
        "FORMAT": "BINARY_IEEE_LITTLE_END", "NUM_HEADER_BLOCKS": "", "NUM_PARAMS": "", "FILE_TYPE": "TIME_HISTORY",
        "TIME_TYPE": time_type, "DATE": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%S"),
        "OPERATION": "rigsim rigsim.correction.io.rpc3", "DELTA_T": _num(dt_s), "CHANNELS": str(n_ch),
        "PTS_PER_FRAME": str(pts_per_frame), "PTS_PER_GROUP": str(ppg), "FRAMES": str(frames), "SAMPLES": str(n),
        "DATA_TYPE": "SHORT_INTEGER", "INT_FULL_SCALE": str(INT_FULL_SCALE), "BYPASS_FILTER": "0",
        "HALF_FRAMES": "0", "REPEATS": "1", "PARTITIONS": "1", "PART.CHAN_1": "1", "PART.NCHAN_1": str(n_ch)}
    if start_s != 0.0:
        head["START_TIME"] = _num(start_s)
    for c in range(n_ch):
        head.update({f"DESC.CHAN_{c + 1}": names[c], f"UNITS.CHAN_{c + 1}": units[c],
                     f"SCALE.CHAN_{c + 1}": _num(scales[c]), f"MAP.CHAN_{c + 1}": str(c + 1),
                     f"LOWER_LIMIT.CHAN_{c + 1}": _num(data[c].min()),
                     f"UPPER_LIMIT.CHAN_{c + 1}": _num(data[c].max())})
    for k, v in (extra or {}).items():
        if not is_structural(str(k)):
            head[str(k)] = str(v)
    n_params = len(head)
    blocks = -(-n_params // (_BLOCK // _RECORD))
    head["NUM_HEADER_BLOCKS"], head["NUM_PARAMS"] = str(blocks), str(n_params)
    out = bytearray()
    for k, v in head.items():
        _check_text(k, v, path)
        out += k.encode("latin-1").ljust(_KEY, b"\0") + v.encode("latin-1").ljust(_RECORD - _KEY, b"\0")
    out += b"\0" * (blocks * _BLOCK - len(out))
    q = np.clip(np.rint(data / scales[:, None]), -INT_FULL_SCALE, INT_FULL_SCALE).astype("<i2")
    padded = np.concatenate([q, np.repeat(q[:, -1:], groups * ppg - n, axis=1)], axis=1)
    out += padded.reshape(n_ch, groups, ppg).transpose(1, 0, 2).tobytes()
    with open(dest if dest is not None else path, "wb") as fh:
        fh.write(out)
