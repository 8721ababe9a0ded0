"""What every reader and writer of measured channels shares: the result, the error, SI
conversion of one channel, the uniform time axis, the safe opening of an input file (a regular
file that fits in memory) and the safe writing of an output file.

Used by :mod:`correction.io.measured` (the public API) and the format modules
(:mod:`correction.io.measured_csv`, :mod:`correction.io.rpc3`, :mod:`correction.io.measured_lab`); it
imports none of them.
"""

from __future__ import annotations

import os
import pathlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from correction.io.atomic import atomic_path, available_memory_bytes, open_regular, read_regular, size_text
from correction.io.measured_units import lookup_unit, suffix_unit

__all__ = ["MeasuredDataError", "MeasuredChannels", "TIME_KEYS", "READ_MEMORY_PER_BYTE", "read_bytes", "open_input",
           "is_time_name", "to_si", "uniform_rate", "make_channels", "check_output", "atomic_output"]

#: Names (case-insensitive, unit decoration removed) that make a column the time column.
TIME_KEYS = frozenset({"time", "t", "zeit", "time_s", "time_ms", "time_us", "t_s", "t_ms", "zeit_s", "zeit_ms",
                       "times", "sec", "seconds", "time_sec", "timestamp_s", "x_value"})


class MeasuredDataError(ValueError):
    """A measured-data file that cannot be used as written; the message is one sentence."""


def is_time_name(name: str) -> bool:
    """True for a column name that marks the time axis (``time``, ``Time``, ``t``, ``zeit``, ``time_ms``...).

    Case-insensitive, except a lone ``T`` (a temperature or a torque more often than a time)."""
    n = name.strip()
    return n.lower() in TIME_KEYS and n != "T"


@dataclass(frozen=True)
class MeasuredChannels:
    """Channels of one measured file on one uniform time axis, in SI units.

    Attributes
    ----------
    time_s : numpy.ndarray, shape (n,), s
        The time of each sample as the file gives it (not shifted to 0); read-only.
    data : Mapping[str, numpy.ndarray]
        Channel name (without unit decoration) -> values, shape (n,), in ``units[name]``; read-only.
    units : Mapping[str, str]
        Channel name -> its SI unit (``"N"``, ``"m"``, ``"Pa"``, ``"1"`` dimensionless, ``""`` when the
        file gives none: the values are then taken as they stand).
    source_units : Mapping[str, str]
        Channel name -> the unit as the file wrote it (``"kN"``, ``"mm"``; ``""`` when none).
    fs_hz : float, Hz
        Sampling rate of the uniform time axis.
    metadata : Mapping[str, str]
        What the file carries besides the data: the CSV ``# key: value`` preamble, the RPC III header,
        the MDF4 comment and properties, the TDMS properties.
    path : str
        The file read.
    format : str
        ``"csv"``, ``"rpc3"``, ``"mdf4"`` or ``"tdms"``.
    time_name : str
        The time column as named in the file (``"time"`` when the format has none).
    """

    time_s: np.ndarray
    data: Mapping
    units: Mapping
    source_units: Mapping
    fs_hz: float
    metadata: Mapping
    path: str
    format: str
    time_name: str = "time"

    @property
    def names(self) -> tuple[str, ...]:
        """Channel names in file order."""
        return tuple(self.data)

    @property
    def n_samples(self) -> int:
        return int(self.time_s.size)

    def array(self, names=None) -> np.ndarray:
        """Channels ``names`` (default: all) as columns of one array, shape (n, k), SI."""
        names = self.names if names is None else list(names)
        return np.column_stack([self.data[n] for n in names]) if names else np.empty((self.n_samples, 0))

    def to_dict(self) -> dict:
        """A summary for JSON (no sample values): path, format, rate, channels and units, metadata."""
        return {"path": self.path, "format": self.format, "fs_hz": self.fs_hz, "n_samples": self.n_samples,
                "time_name": self.time_name, "start_s": float(self.time_s[0]) if self.n_samples else None,
                "units": dict(self.units), "source_units": dict(self.source_units), "metadata": dict(self.metadata)}


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def make_channels(*, time_s, data: Mapping, units: Mapping, source_units: Mapping, fs_hz: float,
                  metadata: Mapping, path, fmt: str, time_name: str = "time") -> MeasuredChannels:
    """Build a :class:`MeasuredChannels` with read-only arrays and mappings."""
    return MeasuredChannels(
        time_s=_frozen(time_s), data=MappingProxyType({k: _frozen(v) for k, v in data.items()}),
        units=MappingProxyType(dict(units)), source_units=MappingProxyType(dict(source_units)),
        fs_hz=float(fs_hz), metadata=MappingProxyType({str(k): str(v) for k, v in metadata.items()}),
        path=str(path), format=fmt, time_name=time_name)


def to_si(name: str, values: np.ndarray, unit: str | None, path, what: str = "column"):
    """Convert one channel to SI: ``(values in SI, SI unit, unit as written)``.

    ``unit`` is the unit written for the channel (None or ``""``: none; then a name suffix such as
    ``_N``, ``_mm`` or ``_ms`` gives it, or the values are taken as SI with SI unit ``""``).

    Raises
    ------
    MeasuredDataError
        The unit is not in :data:`correction.io.measured_units.UNITS` (naming the channel and the unit).
    """
    written = "" if unit is None else unit.strip()
    if written in ("", "NONE", "none", "None"):
        written = suffix_unit(name)
    found = lookup_unit(written)
    if found is None:
        raise MeasuredDataError(f"{what} {name!r} of {str(path)!r} is in {written!r}, a unit this reader does not "
                                "know; fix: convert it to SI (N, m, Pa, s...) or leave the channel out")
    si_unit, factor, offset = found
    v = np.asarray(values, dtype=float)
    if factor != 1.0:
        v = v * factor
    if offset != 0.0:
        v = v + offset
    return v, si_unit, written


def uniform_rate(t: np.ndarray, name: str, where: Callable[[int], str]) -> float:
    """Sampling rate (Hz) of a uniform time axis ``t`` (s); errors name the first bad place.

    ``where(i)`` names sample ``i`` (``"line 12"``, ``"sample 12"``). A step may differ from the
    median by 1 % (rounding of the written times), not more (a gap or a jitter).
    """
    n = t.size
    if n < 2:
        raise MeasuredDataError(f"time {name!r} has {n} samples; at least two are needed")
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise MeasuredDataError(f"column {name!r} does not increase at {where(i)} (t = {t[i]:.9g} s after "
                                f"{t[i - 1]:.9g} s); fix: sort the rows and remove duplicates")
    dt = float(np.median(steps))
    off = np.flatnonzero(np.abs(steps - dt) > 0.01 * dt)
    if off.size:
        i = int(off[0]) + 1
        raise MeasuredDataError(f"column {name!r} is not uniform at {where(i)} (step {steps[i - 1]:.6g} s from "
                                f"t = {t[i - 1]:.9g} s, the file's step is {dt:.6g} s); fix: resample the file to "
                                "a uniform grid")
    return float((n - 1) / (t[-1] - t[0]))


def check_output(path, *, overwrite: bool, inputs=()) -> pathlib.Path:
    """Refuse writing onto an input file, or onto an existing file without ``overwrite``."""
    out = pathlib.Path(path)
    for inp in inputs:
        if inp is None:
            continue
        p = pathlib.Path(inp)
        try:
            same = out.exists() and p.exists() and os.path.samefile(out, p)
        except OSError:
            same = False
        if same or out.resolve() == p.resolve():
            raise MeasuredDataError(f"output {str(path)!r} is the input file {str(inp)!r}; write to a new file")
    if out.exists() and not overwrite:
        raise MeasuredDataError(f"output {str(path)!r} exists; pass --force (overwrite=True) to replace it")
    if out.exists() and out.is_dir():
        raise MeasuredDataError(f"output {str(path)!r} is a folder; name a file")
    return out


def atomic_output(path: pathlib.Path, write: Callable[[str], None]) -> None:
    """Call ``write(temp_path)`` on a temporary file beside ``path`` that keeps its extension
    (asammdf, nptdms and the RPC III writer pick the format by it), then flush it to disk and
    rename it over ``path``; the temporary file is removed if ``write`` fails.

    The temporary file is :func:`correction.io.atomic.atomic_path`'s, named with this host and pid:
    one left by a writer that was killed is removed by the next write to the same ``path``.
    """
    with atomic_path(path, keep_suffix=True) as tmp:
        write(str(tmp))


#: Peak memory of reading a measured file whole, bytes per byte of the file: the bytes, the text,
#: the lines and the arrays (measured on 32-72 MB files: CSV read whole 4.2, RPC III 8.9 with
#: int16 samples, TDMS 2.2, MDF4 5.5 of the channels read). A file whose size times this is more
#: than the available memory is refused before it is read.
READ_MEMORY_PER_BYTE = 5.0


def open_input(path, memory_per_byte: float | None = READ_MEMORY_PER_BYTE):
    """A measured-data file opened for reading (binary), refused in one sentence when it is
    missing, not a regular file (a named pipe, a device, a socket, a directory: reading it could
    wait for ever or never end) or too large to read in the memory available.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    memory_per_byte : float or None
        Peak memory of reading the file, bytes per byte of the file (:data:`READ_MEMORY_PER_BYTE`);
        None: no limit (a reader that maps the file and reads only the channels asked for).

    Returns
    -------
    io.BufferedReader
        The open file; the caller closes it.

    Raises
    ------
    MeasuredDataError
        ``"input file 'PATH' does not exist"``, ``"... is a named pipe (FIFO), not a regular file: ..."``,
        ``"... is 30 GiB; reading it takes about 5 times that in memory ..."``.
    """
    fh = open_regular(path, "input file", error=MeasuredDataError)
    limit = _limit(memory_per_byte)
    if limit is not None:
        size = os.fstat(fh.fileno()).st_size
        if size > limit[0]:
            fh.close()
            raise MeasuredDataError(f"input file {str(path)!r} is {size_text(size)}{limit[1]}")
    return fh


def _limit(memory_per_byte: float | None) -> tuple[int, str] | None:
    """The largest measured file that can be read now (bytes), and the end of the sentence that
    refuses a larger one; None when there is no limit or the available memory is unknown."""
    avail = available_memory_bytes() if memory_per_byte else None
    if avail is None:
        return None
    clause = (f"; reading it takes about {memory_per_byte:g} times that in memory and {size_text(avail)} is "
              "available: cut the record into shorter files (or free memory)")
    return int(avail / memory_per_byte), clause


def read_bytes(path, memory_per_byte: float = READ_MEMORY_PER_BYTE) -> bytes:
    """The bytes of a measured-data file, read whole.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    memory_per_byte : float
        Peak memory of the reader that parses the bytes, bytes per byte of the file
        (:data:`READ_MEMORY_PER_BYTE`; a reader that needs more passes its own).

    Returns
    -------
    bytes

    Raises
    ------
    MeasuredDataError
        As :func:`open_input`, or when the file cannot be read (an I/O error, not enough memory).
    """
    limit = _limit(memory_per_byte)
    return read_regular(path, "input file", max_bytes=None if limit is None else limit[0],
                        too_large="" if limit is None else limit[1], error=MeasuredDataError)
