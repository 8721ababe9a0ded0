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

from correction.measured_core import MeasuredDataError, read_bytes

__all__ = ["INT_FULL_SCALE", "Rpc3Data", "read_rpc3", "write_rpc3", "STRUCTURAL_KEYS"]

INT_FULL_SCALE = 32752
_RECORD, _KEY, _BLOCK = 128, 32, 512
_CHAN_KEY = re.compile(r"^(SCALE|MAP|LOWER_LIMIT|UPPER_LIMIT|DESC|UNITS)\.CHAN_\d+$|^PART\.N?CHAN_\d+$")
#: Keys the writer derives from the data (given metadata with these names is not written).
STRUCTURAL_KEYS = frozenset({"FORMAT", "NUM_HEADER_BLOCKS", "NUM_PARAMS", "FILE_TYPE", "CHANNELS", "DELTA_T",
                             "PTS_PER_FRAME", "PTS_PER_GROUP", "FRAMES", "SAMPLES", "DATA_TYPE", "INT_FULL_SCALE",
                             "PARTITIONS", "HALF_FRAMES", "START_TIME", "BYPASS_FILTER", "REPEATS"})


def is_structural(key: str) -> bool:
    return key in STRUCTURAL_KEYS or bool(_CHAN_KEY.match(key))


@dataclass(frozen=True)
class Rpc3Data:
    """One RPC III file: channels ``data[k]`` named ``names[k]`` in ``units[k]`` (as written).

    Attributes
    ----------
    names, units : tuple of str
    data : numpy.ndarray, shape (channels, samples), in the file's units (scaled)
    dt_s : float, s
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


def _fail(path, text: str) -> MeasuredDataError:
    return MeasuredDataError(f"RPC III file {str(path)!r} {text}")


def _header(raw: bytes, path) -> dict[str, str]:
    def record(i: int) -> tuple[str, str]:
        rec = raw[i * _RECORD:(i + 1) * _RECORD]
        if len(rec) < _RECORD:
            raise _fail(path, "ends inside its header; the file is truncated")
        key, value = rec[:_KEY], rec[_KEY:]
        return (key.split(b"\0", 1)[0].decode("latin-1").strip(),
                value.split(b"\0", 1)[0].decode("latin-1").strip())

    first = [record(i) for i in range(3)]
    if [k for k, _ in first] != ["FORMAT", "NUM_HEADER_BLOCKS", "NUM_PARAMS"]:
        raise _fail(path, "does not start with FORMAT, NUM_HEADER_BLOCKS, NUM_PARAMS; it is not an RPC III file")
    try:
        blocks, n_params = int(first[1][1]), int(first[2][1])
    except ValueError:
        raise _fail(path, "has a NUM_HEADER_BLOCKS or NUM_PARAMS that is not an integer") from None
    if not 3 <= n_params <= blocks * _BLOCK // _RECORD:
        raise _fail(path, f"has NUM_PARAMS {n_params} for {blocks} header blocks; the header is damaged")
    head: dict[str, str] = {}
    for i in range(n_params):
        k, v = record(i)
        if k:
            head[k] = v
    return head


def _int(head, key, path, default=None) -> int:
    if key not in head:
        if default is None:
            raise _fail(path, f"has no {key} key; it cannot be read")
        return default
    try:
        value = float(head[key])
    except ValueError:
        raise _fail(path, f"has {key} = {head[key]!r}, not a number") from None
    if value != int(value) or value < 0:
        raise _fail(path, f"has {key} = {head[key]!r}, not a whole number")
    return int(value)


def _float(head, key, path) -> float:
    try:
        value = float(head[key])
    except (KeyError, ValueError):
        raise _fail(path, f"has no numeric {key} key ({head.get(key)!r})") from None
    if not math.isfinite(value):
        raise _fail(path, f"has {key} = {head[key]!r}")
    return value


def read_rpc3(path) -> Rpc3Data:
    """Read an RPC III time-history file; one sentence naming the key that is wrong otherwise."""
    raw = read_bytes(path)
    head = _header(raw, path)
    fmt = head["FORMAT"].upper()
    order = {"BINARY": "<", "BINARY_IEEE_LITTLE_END": "<", "BINARY_IEEE_BIG_END": ">"}.get(fmt)
    if order is None:
        raise _fail(path, f"has FORMAT {head['FORMAT']!r}; only binary files can be read (convert it in RPC)")
    if head.get("FILE_TYPE", "TIME_HISTORY").upper() != "TIME_HISTORY":
        raise _fail(path, f"is a {head['FILE_TYPE']!r} file, not a TIME_HISTORY")
    kind = head.get("DATA_TYPE", "SHORT_INTEGER").upper()
    if kind not in ("SHORT_INTEGER", "FLOATING_POINT"):
        raise _fail(path, f"has DATA_TYPE {head['DATA_TYPE']!r}; SHORT_INTEGER or FLOATING_POINT can be read")
    if _int(head, "PARTITIONS", path, 1) != 1 or _int(head, "HALF_FRAMES", path, 0) != 0:
        raise _fail(path, "has several partitions or half frames, which this reader does not lay out")
    n_ch, ppf, ppg, frames = (_int(head, k, path) for k in ("CHANNELS", "PTS_PER_FRAME", "PTS_PER_GROUP", "FRAMES"))
    dt = _float(head, "DELTA_T", path)
    if n_ch < 1 or ppf < 1 or ppg < ppf or ppg % ppf or dt <= 0:
        raise _fail(path, f"has CHANNELS {n_ch}, PTS_PER_FRAME {ppf}, PTS_PER_GROUP {ppg}, DELTA_T {dt}, which "
                          "do not describe a record")
    n = frames * ppf
    if "SAMPLES" in head:
        n = min(n, _int(head, "SAMPLES", path))
    groups = -(-frames // (ppg // ppf))
    dtype = np.dtype(order + ("i2" if kind == "SHORT_INTEGER" else "f4"))
    offset = _int(head, "NUM_HEADER_BLOCKS", path) * _BLOCK
    count = groups * ppg * n_ch
    if len(raw) < offset + count * dtype.itemsize:
        raise _fail(path, f"is truncated: its header asks for {count} values after {offset} bytes but the file "
                          f"has {len(raw)} bytes")
    block = np.frombuffer(raw, dtype=dtype, count=count, offset=offset)
    data = block.reshape(groups, n_ch, ppg).transpose(1, 0, 2).reshape(n_ch, groups * ppg)[:, :n].astype(float)
    names, units = [], []
    for c in range(1, n_ch + 1):
        if kind == "SHORT_INTEGER":
            data[c - 1] *= _float(head, f"SCALE.CHAN_{c}", path)
        names.append(head.get(f"DESC.CHAN_{c}", "") or f"CHAN_{c}")
        units.append(head.get(f"UNITS.CHAN_{c}", ""))
    start = _float(head, "START_TIME", path) if "START_TIME" in head else 0.0
    return Rpc3Data(names=tuple(names), units=tuple(units), data=data, dt_s=dt, start_s=start, header=dict(head))


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
    ppg = pts_per_frame * frames_per_group
    groups = -(-n // ppg)
    frames = groups * frames_per_group  # whole groups: readers differ on a partly filled last one
    absmax = np.max(np.abs(data), axis=1)
    scales = np.where(absmax > 0, absmax / INT_FULL_SCALE, 1.0)
    head: dict[str, str] = {
        "FORMAT": "BINARY_IEEE_LITTLE_END", "NUM_HEADER_BLOCKS": "", "NUM_PARAMS": "", "FILE_TYPE": "TIME_HISTORY",
        "TIME_TYPE": time_type, "DATE": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%S"),
        "OPERATION": "rigsim correction.rpc3", "DELTA_T": _num(dt_s), "CHANNELS": str(n_ch),
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
