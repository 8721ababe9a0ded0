"""Measured channels of a rig test: one reader, and writers, for the files test labs keep.

``rigsim correct`` and ``rigsim identify --from-file`` read real rig data through this module,
without a simulator. The format follows the file's extension:

=====================  =========  ===================================================
extension              format     how
=====================  =========  ===================================================
.csv .txt .dat         ``csv``    :mod:`rigsim.correction.io.measured_csv` (delimiter, decimal mark,
                                  thousands separator, preamble, units row, units
                                  in headers: sniffed; streamed)
.rsp .drv .tim .rpc    ``rpc3``   :mod:`rigsim.correction.io.rpc3` (MTS RPC III, own code)
.mf4 .mdf              ``mdf4``   ``asammdf`` (the ``lab`` extra), :mod:`rigsim.correction.io.measured_lab`
.tdms                  ``tdms``   ``nptdms`` (the ``lab`` extra), :mod:`rigsim.correction.io.measured_lab`
=====================  =========  ===================================================

Every channel comes back in SI (:mod:`rigsim.correction.io.measured_units`: kN -> N, mm -> m, bar -> Pa,
ms -> s, % -> fraction...), with the unit as written kept in ``source_units``; a channel without
unit is taken as SI (a name suffix ``_N``, ``_m``, ``_Pa``, ``_s``, ``_ms`` gives its unit; with
none, its SI unit and ``source_units`` entry are ``""``). The time axis must be uniform (1 % of a
step, no gap) at a rate of at most :data:`~rigsim.correction.io.measured_core.MAX_RATE_HZ`; ``fs_hz`` is
its rate, read within the axis's resolution
(:func:`~rigsim.correction.io.measured_core.uniform_rate`), and ``time_s`` starts at 0: the first
sample's time as the file gives it (a time-of-day clock, epoch seconds, RPC III's START_TIME) is
``metadata["time_start_s"]`` when not 0. Every refusal is one :class:`MeasuredDataError`
sentence naming the file, the column or channel, the line or unit, and the fix.

Metadata: the CSV ``# key: value`` preamble; the RPC III header keys other than those that lay
out the data (:data:`rigsim.correction.io.rpc3.STRUCTURAL_KEYS`, ``*.CHAN_n``); the MDF4 header comment and
properties; the TDMS file and group properties. The writers put metadata back in the same places.
"""

from __future__ import annotations

import pathlib
from collections.abc import Mapping

import numpy as np

from rigsim.correction.io.measured_core import (TIME_KEYS, TIME_START_KEY, MeasuredChannels, MeasuredDataError, atomic_output,
                                      check_channel, check_output, make_channels, to_si)
from rigsim.correction.io.measured_time import round_rate, time_grid, uniform_rate

__all__ = ["MeasuredDataError", "MeasuredChannels", "TIME_KEYS", "READ_FORMATS", "WRITE_FORMATS",
           "read_channels", "write_channels", "format_of"]

#: Extension -> format read.
READ_FORMATS = {".csv": "csv", ".txt": "csv", ".dat": "csv", ".rsp": "rpc3", ".drv": "rpc3", ".tim": "rpc3",
                ".rpc": "rpc3", ".mf4": "mdf4", ".mdf": "mdf4", ".tdms": "tdms"}
#: Extension -> format written.
WRITE_FORMATS = READ_FORMATS


def format_of(path, formats: Mapping = READ_FORMATS) -> str:
    """``"csv"``, ``"rpc3"``, ``"mdf4"`` or ``"tdms"`` from the extension; one sentence otherwise."""
    ext = pathlib.Path(path).suffix.lower()
    if ext not in formats:
        raise MeasuredDataError(f"{str(path)!r} has extension {ext or '(none)'!r}; give a .csv/.txt/.dat (text), "
                                ".rsp/.drv/.tim/.rpc (RPC III), .mf4/.mdf (MDF4) or .tdms file")
    return formats[ext]


def read_channels(path, *, time_col: str | None = None, channels=None, decimal: str | None = None,
                  thousands: str | None = None) -> MeasuredChannels:
    """Read the channels of a measured file, in SI, on its uniform time axis.

    Parameters
    ----------
    path : str or os.PathLike
        .csv/.txt/.dat, .rsp/.drv/.tim/.rpc, .mf4/.mdf or .tdms.
    time_col : str, optional
        The time column or channel (CSV, TDMS; MDF4: its master channel); default: the one column
        with a time name (``time``, ``Time [s]``, ``t``, ``zeit``, ``time_ms``...; see
        :data:`TIME_KEYS`). RPC III files have no time column (DELTA_T gives the time).
    channels : sequence of str, optional
        Channels to read, in this order (names without unit decoration; a CSV header as written
        is accepted too). Default: every numeric channel (CSV: every column with a number in its
        first lines; text columns are ignored).
    decimal : {".", ","}, optional
        Text files: the decimal mark; default: decided by the fields of the columns read, an
        ambiguous file refused (:mod:`rigsim.correction.io.measured_numbers`). Other formats: leave it out.
    thousands : {"none", ",", ".", "'", "space"}, optional
        Text files: the one thousands separator (``"space"``: a space, U+00A0 or U+202F;
        ``","`` implies ``decimal="."``, ``"."`` implies ``decimal=","``); default: detected.

    Returns
    -------
    MeasuredChannels

    Raises
    ------
    MeasuredDataError
        One sentence naming the file and the column, line, unit, key or extra at fault.
    """
    fmt = format_of(path)
    if isinstance(channels, str):
        channels = [channels]
    channels = None if channels is None else list(channels)
    if fmt == "csv":
        from rigsim.correction.io.measured_csv import read_csv_channels

        return read_csv_channels(path, time_col=time_col, channels=channels, decimal=decimal, thousands=thousands)
    if decimal is not None or thousands is not None:
        raise MeasuredDataError(f"{str(path)!r} is a {fmt} file, which stores numbers, not text; leave the decimal "
                                "mark and thousands separator (--decimal, --thousands) out")
    if fmt == "rpc3":
        return _read_rpc(path, time_col, channels)
    from rigsim.correction.io import measured_lab

    reader = measured_lab.read_mdf if fmt == "mdf4" else measured_lab.read_tdms
    return reader(path, time_col=time_col, channels=channels)


def _read_rpc(path, time_col, channels) -> MeasuredChannels:
    from rigsim.correction.io.rpc3 import BYTE_ORDERS, STEP_ROUNDING, is_structural, read_rpc3

    if time_col is not None:
        raise MeasuredDataError(f"RPC III file {str(path)!r} has no time column (DELTA_T gives the time); leave "
                                "time_col out")
    r = read_rpc3(path)
    index = {n: k for k, n in enumerate(r.names)}  # one pass: a file may hold many channels
    if len(index) != len(r.names):
        from collections import Counter

        dup = sorted(n for n, times in Counter(r.names).items() if times > 1)
        raise MeasuredDataError(f"channel {dup[0]!r} appears more than once in {str(path)!r} (DESC.CHAN_n); "
                                "rename one in RPC")
    chosen = list(r.names) if channels is None else channels
    missing = [c for c in chosen if c not in index]
    if missing:
        listed = ", ".join(r.names[:20]) + (f" and {len(r.names) - 20} more" if len(r.names) > 20 else "")
        raise MeasuredDataError(f"channel {missing[0]!r} is not in {str(path)!r}; its channels are {listed}")
    if len(set(chosen)) != len(chosen):
        raise MeasuredDataError(f"channels {chosen!r} name a channel twice; name each once")
    n = r.data.shape[1]
    if n < 2:
        raise MeasuredDataError(f"RPC III file {str(path)!r} has {n} samples; at least two are needed")
    data, units, src = {}, {}, {}
    for c in chosen:
        k = index[c]
        data[c], units[c], src[c] = to_si(c, r.data[k], r.units[k], path, what="channel")
    meta = {k: v for k, v in r.header.items() if not is_structural(k)}
    order = BYTE_ORDERS[r.header["FORMAT"].upper()]
    dialect = {"byte_order": "little-endian" if order == "<" else "big-endian",
               "data_type": r.header.get("DATA_TYPE", "SHORT_INTEGER").upper()}
    if r.start_s != 0.0:
        meta[TIME_START_KEY] = repr(r.start_s)
    fs = round_rate(1.0 / r.dt_s, STEP_ROUNDING)
    t = time_grid(n, fs)
    t.setflags(write=False)  # the record's own: kept, not copied
    return make_channels(time_s=t, data=data, units=units, source_units=src, fs_hz=fs, metadata=meta,
                         path=path, fmt="rpc3", dialect=dialect)


def _validated(channels):
    """(time (n,), {name: (n,)}, {name: unit}) from a MeasuredChannels-like object; checks only."""
    try:
        t = np.asarray(channels.time_s, dtype=float)
        data = {str(k): np.asarray(v, dtype=float) for k, v in channels.data.items()}
    except (AttributeError, TypeError, ValueError) as exc:
        raise MeasuredDataError(f"channels to write need time_s and data (name -> numbers): {exc}") from None
    units = dict(getattr(channels, "units", None) or {})
    if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise MeasuredDataError("time_s to write must be at least two finite, increasing times in s")
    if not data:
        raise MeasuredDataError("there is no channel to write; give at least one")
    for name, v in data.items():
        check_channel(v, t.size, f"channel {name!r}")
    return t, data, {n: str(units.get(n, "") or "") for n in data}


def write_channels(path, channels, *, metadata: Mapping | None = None, overwrite: bool = False,
                   inputs=()) -> pathlib.Path:
    """Write channels to a file whose format follows its extension, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        .csv/.txt/.dat (comma-separated, ``time [s]`` then ``name [unit]``), .rsp/.drv/.tim/.rpc
        (RPC III int16; .drv is TIME_TYPE DRIVE), .mf4/.mdf (MDF 4.10), .tdms.
    channels : MeasuredChannels or any object with ``time_s`` (n,) s, ``data`` Mapping[name ->
        (n,)] and optionally ``units`` Mapping[name -> unit]: values are written as they are,
        labelled with these units (SI for a MeasuredChannels).
    metadata : Mapping[str, str], optional
        Written as a ``#`` preamble (CSV), header keys (RPC III), the header comment (MDF4), file
        properties (TDMS). Default: ``channels.metadata`` when it has one.
    overwrite : bool
        Replace an existing file (the CLI's ``--force``); refused otherwise.
    inputs : sequence of paths
        Files read for this output: writing onto one of them is refused.

    Returns
    -------
    pathlib.Path
        The file written.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from types import SimpleNamespace
    >>> import numpy as np
    >>> from rigsim.correction.io.measured import read_channels, write_channels
    >>> t = np.arange(2000) / 1000.0
    >>> channels = SimpleNamespace(time_s=t, data={"Fz_FL": 40e3 + 1e3 * np.sin(2 * np.pi * t)},
    ...                            units={"Fz_FL": "N"})
    >>> path = write_channels(pathlib.Path(tempfile.mkdtemp()) / "forces.rsp", channels)
    >>> back = read_channels(path)
    >>> back.format, back.fs_hz, list(back.data)
    ('rpc3', 1000.0, ['Fz_FL'])
    """
    fmt = format_of(path, WRITE_FORMATS)
    out = check_output(path, overwrite=overwrite, inputs=inputs)
    t, data, units = _validated(channels)
    meta = dict(getattr(channels, "metadata", None) or {}) if metadata is None else dict(metadata)
    meta = {str(k): str(v) for k, v in meta.items()}
    if fmt == "csv":
        from rigsim.correction.io.measured_csv import check_names, write_csv

        check_names(list(data), "time", "CSV")
        atomic_output(out, lambda tmp: write_csv(tmp, t, data, units, meta))
    elif fmt == "rpc3":
        from rigsim.correction.io.rpc3 import write_rpc3

        fs = uniform_rate(t, "time_s", lambda i: f"sample {i}")
        ext = out.suffix.lower()
        kind = {".drv": "DRIVE", ".rsp": "RESPONSE"}.get(ext, meta.get("TIME_TYPE", "RESPONSE"))
        extra = {k: v for k, v in meta.items() if k != "TIME_TYPE"}
        atomic_output(out, lambda tmp: write_rpc3(out, list(data), [units[n] for n in data], np.array(list(
            data.values())), 1.0 / fs, start_s=float(t[0]), time_type=kind, extra=extra, dest=tmp))
    else:
        from rigsim.correction.io import measured_lab

        if fmt == "mdf4":
            measured_lab.need("asammdf", ".mf4", "writing")
            atomic_output(out, lambda tmp: measured_lab.write_mdf(tmp, t, data, units, meta))
        else:
            measured_lab.need("nptdms", ".tdms", "writing")
            atomic_output(out, lambda tmp: measured_lab.write_tdms(tmp, t, data, units, meta))
    return out
