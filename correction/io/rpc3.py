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
the file, before anything is sized by them. DELTA_T must be the step of a measured record
(:data:`MIN_DELTA_T_S` to :data:`MAX_DELTA_T_S`), START_TIME must leave the samples' times apart
in float64 (:data:`TIME_RESOLUTION`), SCALE.CHAN_n must be finite and not 0, and every sample
finite. A key given twice with two values is refused (either could be meant); the same value
given twice is read once, as it reads the same whichever record is taken.

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

from correction.io.measured_core import MeasuredDataError, read_bytes

__all__ = ["INT_FULL_SCALE", "MIN_DELTA_T_S", "MAX_DELTA_T_S", "TIME_RESOLUTION", "Rpc3Data", "read_rpc3",
           "write_rpc3", "STRUCTURAL_KEYS"]

INT_FULL_SCALE = 32752
#: Shortest and longest sampling step (DELTA_T, s) of a measured record: a rig's data acquisition
#: samples between 1 MHz and 0.1 Hz (slow channels such as temperatures). A shorter step is a
#: damaged header, and the correction sizes its filters' impulse responses in samples of the
#: record's step (``correction.output.correction_filter.transient_lengths``): at 10 MHz they take GBs.
MIN_DELTA_T_S = 1e-6
MAX_DELTA_T_S = 10.0
#: A step printed with 7 significant digits from a float32 (9.999999e-07) is taken at its rate.
_STEP_ROUNDING = 1e-6
#: Largest float64 spacing of the samples' times, as a fraction of DELTA_T: with a START_TIME so
#: large that its times round coarser than this, the steps of the time axis are not uniform.
TIME_RESOLUTION = 1e-3
_RECORD, _KEY, _BLOCK = 128, 32, 512
_WHOLE = re.compile(r"\+?[0-9]+")
#: What each number of the header gives, for the errors.
_MEANS = {"CHANNELS": "channels", "FRAMES": "frames", "PTS_PER_FRAME": "points in a frame",
          "PTS_PER_GROUP": "points in a group", "SAMPLES": "samples", "PARTITIONS": "partitions",
          "HALF_FRAMES": "half frames", "DELTA_T": "sampling step in s (1 / the sampling rate in Hz)",
          "START_TIME": "time of the first sample in s"}
_REPAIR = "fix: copy the file again from the rig's computer or repair its header in RPC"
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


def _fail(path, text: str) -> MeasuredDataError:
    return MeasuredDataError(f"RPC III file {str(path)!r} {text}")


def _header(raw: bytes, path) -> dict[str, str]:
    """Every header key -> value; a key given twice with two values is refused, a repeat of the
    same value is kept once (the file reads the same whichever record is taken)."""
    def record(i: int) -> tuple[str, str]:
        rec = raw[i * _RECORD:(i + 1) * _RECORD]
        if len(rec) < _RECORD:
            raise _fail(path, f"ends inside its header, at record {i + 1}; the file is truncated; {_REPAIR}")
        key, value = rec[:_KEY], rec[_KEY:]
        return (key.split(b"\0", 1)[0].decode("latin-1").strip(),
                value.split(b"\0", 1)[0].decode("latin-1").strip())

    first = [record(i) for i in range(3)]
    if [k for k, _ in first] != ["FORMAT", "NUM_HEADER_BLOCKS", "NUM_PARAMS"]:
        raise _fail(path, "does not start with FORMAT, NUM_HEADER_BLOCKS, NUM_PARAMS; it is not an RPC III file")
    if not (_WHOLE.fullmatch(first[1][1]) and _WHOLE.fullmatch(first[2][1])):
        raise _fail(path, f"has NUM_HEADER_BLOCKS = {first[1][1]!r} and NUM_PARAMS = {first[2][1]!r}, which are "
                          f"not both whole numbers; {_REPAIR}")
    blocks, n_params = int(first[1][1]), int(first[2][1])
    if not 3 <= n_params <= blocks * _BLOCK // _RECORD:
        raise _fail(path, f"has NUM_PARAMS {n_params} for {blocks} header blocks (3 to {blocks * 4} records); the "
                          f"header is damaged; {_REPAIR}")
    if blocks * _BLOCK > len(raw):
        raise _fail(path, f"has NUM_HEADER_BLOCKS = {blocks} ({blocks * _BLOCK} bytes) but the file has "
                          f"{len(raw)} bytes; {_REPAIR}")
    head: dict[str, str] = {}
    for i in range(n_params):
        k, v = record(i)
        if k and head.setdefault(k, v) != v:
            raise _fail(path, f"gives {k} twice, as {head[k]!r} and as {v!r}, and either could be meant; fix: "
                              "delete the wrong record in RPC's header editor")
    return head


def _int(head, key, path, default=None) -> int:
    """Count ``key`` (``"12"``, ``"12.0"``, ``"1.2e1"``), exact for any number of digits."""
    text = head.get(key)
    if text is None:
        if default is None:
            raise _fail(path, f"has no {key} key, so its data cannot be laid out; fix: add {key} = the number of "
                              f"{_MEANS[key]} it was recorded with")
        return default
    if _WHOLE.fullmatch(text):
        return int(text)
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0 and value == int(value)):
        raise _fail(path, f"has {key} = {text!r}, not a whole number of {_MEANS[key]}; fix: set {key} to the "
                          f"number of {_MEANS[key]} it was recorded with")
    return int(value)


def _float(head, key, path) -> float:
    text = head.get(key)
    if text is None:
        raise _fail(path, f"has no {key} key; fix: add {key} = the {_MEANS[key]}")
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise _fail(path, f"has {key} = {text!r}, not a finite number; fix: write the {_MEANS[key]} as {key}")
    return value


def _layout(head, path, n_params: int, size: int, itemsize: int) -> tuple[int, int, int, int]:
    """(channels, points per group, groups, samples), each checked against what the file holds
    (``n_params`` header records, ``size`` bytes of data) before anything is allocated for it."""
    n_ch, ppf, ppg, frames = (_int(head, k, path) for k in ("CHANNELS", "PTS_PER_FRAME", "PTS_PER_GROUP", "FRAMES"))
    if n_ch < 1:
        raise _fail(path, "has CHANNELS = 0; fix: set CHANNELS to the number of channels recorded")
    if n_ch > n_params:  # each channel has records of its own: DESC.CHAN_n, SCALE.CHAN_n...
        raise _fail(path, f"has CHANNELS = {head['CHANNELS']!r}, not a whole number of channels the file can hold "
                          f"(its header has {n_params} records, a channel needs its own DESC.CHAN_n, SCALE.CHAN_n); "
                          "fix: set CHANNELS to the number of channels recorded")
    if ppf < 1 or ppg < ppf or ppg % ppf:
        raise _fail(path, f"has PTS_PER_FRAME {ppf} and PTS_PER_GROUP {ppg}, which do not describe a record (a "
                          "group is a whole number of frames of at least one point); fix: set them as recorded")
    groups = -(-frames // (ppg // ppf))
    need = groups * ppg * n_ch * itemsize  # Python ints: no overflow
    if need > size:
        raise _fail(path, f"is truncated: its header asks for {groups * ppg * n_ch} values (CHANNELS {n_ch} x "
                          f"PTS_PER_GROUP {ppg} x {groups} groups of FRAMES {frames}), {need} bytes, but the file "
                          f"holds {size} bytes of data; fix: check FRAMES and CHANNELS or copy the whole file again")
    n = frames * ppf
    if "SAMPLES" in head:
        n = min(n, _int(head, "SAMPLES", path))
    return n_ch, ppg, groups, n


def _times(head, path, n: int) -> tuple[float, float]:
    """(DELTA_T, START_TIME), s: a step of a measured record, and times float64 tells apart."""
    dt = _float(head, "DELTA_T", path)
    if not (MIN_DELTA_T_S <= dt * (1 + _STEP_ROUNDING) and dt <= MAX_DELTA_T_S):
        raise _fail(path, f"has DELTA_T = {head['DELTA_T']!r} s, not the sampling step of a measured record "
                          f"({MIN_DELTA_T_S:g} to {MAX_DELTA_T_S:g} s, 1 MHz to 0.1 Hz); fix: write the step in s "
                          "(1 / the sampling rate in Hz) as DELTA_T")
    start = _float(head, "START_TIME", path) if "START_TIME" in head else 0.0
    spacing = math.ulp(max(abs(start), abs(start + max(n - 1, 0) * dt)))
    if spacing > TIME_RESOLUTION * dt:
        raise _fail(path, f"has START_TIME = {head.get('START_TIME', '0')!r} s, so large that float64 rounds its "
                          f"samples' times to {spacing:.3g} s, more than {TIME_RESOLUTION:g} of DELTA_T ({dt:g} s); "
                          "fix: give START_TIME relative to the start of the test (e.g. 0)")
    return dt, start


def _scale(head, path, c: int, name: str) -> float:
    text = head.get(f"SCALE.CHAN_{c}")
    try:
        scale = float(text)
    except (TypeError, ValueError):
        scale = math.nan
    if not math.isfinite(scale) or scale == 0:
        what = f"no SCALE.CHAN_{c} key" if text is None else f"SCALE.CHAN_{c} = {text!r}"
        raise _fail(path, f"has {what} for channel {name!r} (DESC.CHAN_{c}), so its int16 counts give "
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
        time history, a count that is not a whole number or more than the file holds, a key
        given twice with two values, DELTA_T outside [:data:`MIN_DELTA_T_S`,
        :data:`MAX_DELTA_T_S`] s, a START_TIME whose times float64 cannot tell apart (see
        :data:`TIME_RESOLUTION`), a zero or non-finite SCALE.CHAN_n, a NaN or infinite sample.
    """
    raw = read_bytes(path, memory_per_byte=9.0)  # 8.9 measured: the bytes, int16 to float64, scaled
    head = _header(raw, path)
    fmt = head["FORMAT"].upper()
    order = {"BINARY": "<", "BINARY_IEEE_LITTLE_END": "<", "BINARY_IEEE_BIG_END": ">"}.get(fmt)
    if order is None:
        raise _fail(path, f"has FORMAT {head['FORMAT']!r}; only binary files can be read; fix: convert it to "
                          "BINARY in RPC")
    if head.get("FILE_TYPE", "TIME_HISTORY").upper() != "TIME_HISTORY":
        raise _fail(path, f"has FILE_TYPE {head['FILE_TYPE']!r}, not TIME_HISTORY; fix: give a time history "
                          "(.rsp, .drv, .tim)")
    kind = head.get("DATA_TYPE", "SHORT_INTEGER").upper()
    if kind not in ("SHORT_INTEGER", "FLOATING_POINT"):
        raise _fail(path, f"has DATA_TYPE {head['DATA_TYPE']!r}; fix: export it from RPC as SHORT_INTEGER or "
                          "FLOATING_POINT")
    if _int(head, "PARTITIONS", path, 1) != 1 or _int(head, "HALF_FRAMES", path, 0) != 0:
        raise _fail(path, f"has PARTITIONS = {head.get('PARTITIONS', '1')!r} and HALF_FRAMES = "
                          f"{head.get('HALF_FRAMES', '0')!r}, a layout this reader does not read; fix: export it "
                          "from RPC with one partition and whole frames")
    dtype = np.dtype(order + ("i2" if kind == "SHORT_INTEGER" else "f4"))
    offset = int(head["NUM_HEADER_BLOCKS"]) * _BLOCK
    n_ch, ppg, groups, n = _layout(head, path, int(head["NUM_PARAMS"]), len(raw) - offset, dtype.itemsize)
    dt, start = _times(head, path, n)
    names = tuple(head.get(f"DESC.CHAN_{c}", "") or f"CHAN_{c}" for c in range(1, n_ch + 1))
    units = tuple(head.get(f"UNITS.CHAN_{c}", "") for c in range(1, n_ch + 1))
    scales = None
    if kind == "SHORT_INTEGER":
        scales = np.array([_scale(head, path, c + 1, names[c]) for c in range(n_ch)])
    if groups == 0:  # no frames: nothing to lay out (the sizes of a group need not be array sizes)
        data = np.zeros((n_ch, 0))
    else:
        block = np.frombuffer(raw, dtype=dtype, count=groups * ppg * n_ch, offset=offset)
        data = block.reshape(groups, n_ch, ppg).transpose(1, 0, 2).reshape(n_ch, groups * ppg)[:, :n].astype(float)
    if scales is not None:
        with np.errstate(over="ignore"):  # an overflow is reported below, naming the channel
            data *= scales[:, None]
    if data.size and not (math.isfinite(data.max()) and math.isfinite(data.min())):  # NaN propagates: no mask
        c, i = divmod(int(np.argmax(~np.isfinite(data))), n)
        why = f"its counts times SCALE.CHAN_{c + 1} = {head[f'SCALE.CHAN_{c + 1}']!r} exceed float64" if (
            scales is not None) else "a float32 sample that is not finite"
        raise _fail(path, f"has the value {data[c, i]} in channel {names[c]!r} (DESC.CHAN_{c + 1}) at sample {i} "
                          f"(t = {start + i * dt:.9g} s), {why}; fix: remove or interpolate it in RPC")
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
        "OPERATION": "rigsim correction.io.rpc3", "DELTA_T": _num(dt_s), "CHANNELS": str(n_ch),
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
