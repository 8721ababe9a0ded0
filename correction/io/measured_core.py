"""What every reader and writer of measured channels shares: the result (checked as it is built,
from a file or in Python, on the uniform time axis of :mod:`rigsim.correction.io.measured_time`), the
error (:mod:`rigsim.correction.io.measured_error`), SI conversion of one channel, the safe opening of an
input file (a regular file that fits in memory) and the safe writing of an output file.

Used by :mod:`rigsim.correction.io.measured` (the public API) and the format modules
(:mod:`rigsim.correction.io.measured_csv`, :mod:`rigsim.correction.io.rpc3`, :mod:`rigsim.correction.io.measured_lab`); it
imports none of them.
"""

from __future__ import annotations

import math
import os
import pathlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from rigsim.correction.io.atomic import atomic_path, available_memory_bytes, open_regular, read_regular, size_text
from rigsim.correction.io.measured_error import MeasuredDataError
from rigsim.correction.io.measured_time import checked_rate, time_grid
from rigsim.correction.io.measured_units import lookup_unit, suffix_unit

__all__ = ["MeasuredDataError", "MeasuredChannels", "TIME_KEYS", "TIME_START_KEY", "READ_MEMORY_PER_BYTE", "read_bytes",
           "open_input", "is_time_name", "to_si", "make_channels", "check_channel", "check_output", "atomic_output"]

#: Names (case-insensitive, unit decoration removed) that make a column the time column.
TIME_KEYS = frozenset({"time", "t", "zeit", "time_s", "time_ms", "time_us", "t_s", "t_ms", "zeit_s", "zeit_ms",
                       "times", "sec", "seconds", "time_sec", "timestamp_s", "x_value"})
#: Metadata key of the first sample's time (s) as the file or the caller gave it, when not 0
#: (a time-of-day clock, epoch seconds): :attr:`MeasuredChannels.time_s` starts at 0.
TIME_START_KEY = "time_start_s"


def is_time_name(name: str) -> bool:
    """True for a column name that marks the time axis (``time``, ``Time``, ``t``, ``zeit``, ``time_ms``...).

    Case-insensitive, except a lone ``T`` (a temperature or a torque more often than a time)."""
    n = name.strip()
    return n.lower() in TIME_KEYS and n != "T"


@dataclass(frozen=True)
class MeasuredChannels:
    """Channels of one measured file on one uniform time axis, in SI units.

    Built from a file by the readers, or in Python (directly or by :func:`make_channels`): either
    way ``time_s`` must be a uniform axis (:func:`~rigsim.correction.io.measured_time.uniform_rate`)
    whose rate ``fs_hz`` is, and each channel one finite value per time; a contradiction is one
    :class:`MeasuredDataError` sentence naming the argument. ``time_s`` is then made relative to
    its first sample, the first sample's time kept as ``metadata[TIME_START_KEY]``.

    Attributes
    ----------
    time_s : numpy.ndarray, shape (n,), s
        The time of each sample from the first: ``np.arange(n) / fs_hz``; read-only.
    data : Mapping[str, numpy.ndarray]
        Channel name (without unit decoration) -> values, shape (n,), in ``units[name]``; read-only.
    units : Mapping[str, str]
        Channel name -> its SI unit (``"N"``, ``"m"``, ``"Pa"``, ``"1"`` dimensionless, ``""`` when the
        file gives none: the values are then taken as they stand).
    source_units : Mapping[str, str]
        Channel name -> the unit as the file wrote it (``"kN"``, ``"mm"``; ``""`` when none).
    fs_hz : float, Hz
        Sampling rate of the uniform time axis (at most
        :data:`~rigsim.correction.io.measured_time.MAX_RATE_HZ`).
    metadata : Mapping[str, str]
        What the file carries besides the data: the CSV ``# key: value`` preamble, the RPC III header,
        the MDF4 comment and properties, the TDMS properties; and :data:`TIME_START_KEY`, the time
        (s) of the first sample as given, when not 0.
    path : str
        The file read.
    format : str
        ``"csv"``, ``"rpc3"``, ``"mdf4"`` or ``"tdms"``.
    time_name : str
        The time column as named in the file (``"time"`` when the format has none).
    dialect : Mapping[str, object]
        How the reader read the file (empty when built in Python): CSV ``delimiter`` (``"blanks"``:
        runs of blanks), ``decimal`` (None: no field decided it), ``thousands`` (as given, else None),
        ``header_line`` (1-based), ``units_row``, ``encoding``; RPC III ``byte_order``, ``data_type``;
        MDF4 ``version``; TDMS ``time`` (``"channel"`` or ``"waveform"`` properties).

    Examples
    --------
    A record built in memory: 10 s of one wheel force at 1 kHz.

    >>> import numpy as np
    >>> from rigsim.correction.io.measured import MeasuredChannels
    >>> t = np.arange(10_000) / 1000.0
    >>> force = 40e3 + 2e3 * np.sin(2 * np.pi * 3.0 * t)
    >>> record = MeasuredChannels(time_s=t, data={"Fz_FL": force}, units={"Fz_FL": "N"},
    ...                           source_units={"Fz_FL": "N"}, fs_hz=1000.0, metadata={},
    ...                           path="", format="csv")
    >>> print(record.fs_hz, "Hz,", float(record.time_s[-1]), "s,", record.units["Fz_FL"])
    1000.0 Hz, 9.999 s, N

    A rate the time axis contradicts is refused in one sentence:

    >>> from rigsim.correction.io.measured import MeasuredDataError
    >>> try:  # doctest: +ELLIPSIS
    ...     MeasuredChannels(time_s=t, data={"Fz_FL": force}, units={"Fz_FL": "N"},
    ...                      source_units={"Fz_FL": "N"}, fs_hz=500.0, metadata={}, path="",
    ...                      format="csv")
    ... except MeasuredDataError as exc:
    ...     print(exc)
    fs_hz = 500 Hz contradicts time_s, whose steps give 1000 Hz; fix: give fs_hz = ...
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
    dialect: Mapping = field(default_factory=lambda: MappingProxyType({}))

    def __post_init__(self):
        t = _frozen(self.time_s, "time_s")
        if t.ndim != 1:
            raise MeasuredDataError(f"argument 'time_s' has shape {t.shape}; fix: give one time (s) per sample")
        rate, tol = checked_rate(t, "time_s", lambda i: f"time_s[{i}]", "argument")
        fs = self.fs_hz if isinstance(self.fs_hz, (int, float, np.number)) else math.nan
        if not (math.isfinite(fs) and fs > 0):
            raise MeasuredDataError(f"fs_hz = {self.fs_hz!r} Hz is not a sampling rate; fix: give the rate of time_s, "
                                    f"{rate:.9g} Hz")
        if abs(fs - rate) > max(tol, 1e-12) * rate:
            raise MeasuredDataError(f"fs_hz = {fs:g} Hz contradicts time_s, whose steps give {rate:.9g} Hz; fix: give "
                                    "fs_hz = (len(time_s) - 1) / (time_s[-1] - time_s[0]) or the time_s it was "
                                    "sampled on")
        data = {k: _frozen(v, f"data[{k!r}]") for k, v in self.data.items()}
        for k, v in data.items():
            check_channel(v, t.size, f"data[{k!r}]")
        meta = {str(k): str(v) for k, v in self.metadata.items()}
        if t[0] != 0.0:
            meta[TIME_START_KEY] = repr(float(t[0]))
        for name, value in (("time_s", _frozen(time_grid(t.size, float(fs), t))), ("fs_hz", float(fs)),
                            ("data", MappingProxyType(data)), ("units", MappingProxyType(dict(self.units))),
                            ("source_units", MappingProxyType(dict(self.source_units))),
                            ("metadata", MappingProxyType(meta)), ("path", str(self.path))):
            object.__setattr__(self, name, value)

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
        try:
            start = float(self.metadata.get(TIME_START_KEY, 0.0))
        except ValueError:
            start = None
        return {"path": self.path, "format": self.format, "fs_hz": self.fs_hz, "n_samples": self.n_samples,
                "time_name": self.time_name, "start_s": start,
                "units": dict(self.units), "source_units": dict(self.source_units), "metadata": dict(self.metadata)}


def check_channel(values: np.ndarray, n: int, what: str) -> None:
    """Refuse channel ``what`` (``"channel 'Fz'"``, ``"data['Fz']"``) unless ``values`` is one
    finite value for each of ``n`` times."""
    if values.shape != (n,):
        raise MeasuredDataError(f"{what} has shape {values.shape} but time_s has ({n},); fix: give one value per time")
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise MeasuredDataError(f"{what} is {float(values[bad[0]])} at sample {int(bad[0])}; fix: remove or "
                                "interpolate the missing samples")


def _frozen(a, name: str = "values") -> np.ndarray:
    """``a`` as a read-only float array: itself when it is one, else a copy (the caller's stays
    writable); one sentence naming argument ``name`` when it is not numbers."""
    if isinstance(a, np.ndarray) and a.dtype == np.float64 and not a.flags.writeable:
        return a
    try:
        a = np.array(a, dtype=float)
    except (TypeError, ValueError):
        raise MeasuredDataError(f"argument {name} is not numbers; fix: give an array of floats") from None
    a.setflags(write=False)
    return a


def make_channels(*, time_s, data: Mapping, units: Mapping, source_units: Mapping, fs_hz: float,
                  metadata: Mapping, path, fmt: str, time_name: str = "time",
                  dialect: Mapping | None = None) -> MeasuredChannels:
    """Build a :class:`MeasuredChannels` (checked, read-only, ``time_s`` from 0) of format ``fmt``."""
    return MeasuredChannels(time_s=time_s, data=data, units=units, source_units=source_units, fs_hz=fs_hz,
                            metadata=metadata, path=path, format=fmt, time_name=time_name,
                            dialect=MappingProxyType(dict(dialect or {})))


def to_si(name: str, values: np.ndarray, unit: str | None, path, what: str = "column"):
    """Convert one channel to SI: ``(values in SI, SI unit, unit as written)``.

    ``unit`` is the unit written for the channel (None or ``""``: none; then a name suffix such as
    ``_N``, ``_mm`` or ``_ms`` gives it, or the values are taken as SI with SI unit ``""``).

    Raises
    ------
    MeasuredDataError
        The unit is not in :data:`rigsim.correction.io.measured_units.UNITS` (naming the channel and the unit).
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

    The temporary file is :func:`rigsim.correction.io.atomic.atomic_path`'s, named with this host and pid:
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
