"""``rigsim info FILE``: what a measured file holds, read as ``rigsim correct`` and ``rigsim identify
--from-file`` read it, before its channels are mapped.

::

    rigsim info FILE [--time-col NAME] [--decimal MARK] [--thousands SEP] [--json]

``FILE`` is read by :func:`rigsim.correction.io.measured.read_channels` (every format of
:data:`rigsim.correction.io.measured.READ_FORMATS`); printed are the format and the dialect the reader
found (:attr:`rigsim.correction.io.measured.MeasuredChannels.dialect`: a text file's delimiter, decimal
mark, thousands separator, header line, units row and encoding; an RPC III file's byte order and
data type; an MDF4 file's version; where a TDMS file's time comes from), the time column and its
first sample (s), the rate (Hz), the number of samples, the duration (s: samples / rate) and each
channel with its unit as the file writes it and its SI unit (the values ``rigsim correct`` works
on). ``--json`` prints the same as one JSON object. A file the reader refuses is one sentence on
stderr and exit code 2 (:func:`rigsim.scenarios.cli.main.main`); nothing is written.
"""

from __future__ import annotations

import argparse
import json
import textwrap

from rigsim.scenarios.core.flags import add_command, add_number_format, add_time_col

__all__ = ["add_parser", "cmd_info", "summary", "FORMAT_NAMES"]

#: The reader's format -> its name as printed.
FORMAT_NAMES = {"csv": "CSV (delimited text)", "rpc3": "RPC III", "mdf4": "MDF4", "tdms": "TDMS"}

#: A dialect key of the readers -> its label as printed, in the order printed.
_LABELS = {"delimiter": "delimiter", "decimal": "decimal mark", "thousands": "thousands separator",
           "header_line": "header on line", "units_row": "units row", "encoding": "encoding", "byte_order": "byte order",
           "data_type": "data type", "version": "version", "time": "time from"}
#: TDMS: where the time comes from, as printed.
_TIME_FROM = {"channel": "a time channel", "waveform": "the waveform properties (wf_increment)"}


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``rigsim info`` (``func=cmd_info``)."""
    p = add_command(subparsers, "info", "list a measured file's channels, units, rate, duration and dialect",
                    "Reads it as rigsim correct does, so the names printed are those --columns, --map, --pairs and "
                    "--identify take.")
    p.add_argument("file", metavar="FILE", help="measured file: CSV (any dialect), RPC III, MDF4 or TDMS")
    add_time_col(p)
    add_number_format(p)
    p.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    p.set_defaults(func=cmd_info)
    return p


def summary(record) -> dict:
    """What ``rigsim info`` prints of a read file, as plain JSON types.

    Parameters
    ----------
    record : rigsim.correction.io.measured.MeasuredChannels
        The file as read.

    Returns
    -------
    dict
        ``path``, ``format``, ``dialect``, ``time_name``, ``start_s`` (s, the first sample's time as
        the file gives it), ``fs_hz`` (Hz), ``n_samples``, ``duration_s`` (s, ``n_samples / fs_hz``),
        ``channels`` (each ``name``, ``unit`` as written, ``si_unit``) and ``metadata``.
    """
    base = record.to_dict()
    return {"path": base["path"], "format": base["format"], "dialect": dict(record.dialect),
            "time_name": base["time_name"], "start_s": base["start_s"], "fs_hz": float(record.fs_hz),
            "n_samples": int(record.n_samples), "duration_s": record.n_samples / float(record.fs_hz),
            "channels": [{"name": n, "unit": record.source_units.get(n, ""), "si_unit": record.units.get(n, "")}
                         for n in record.names],
            "metadata": base["metadata"]}


def _shown(key: str, value) -> str:
    """One dialect value as printed."""
    if value is None:
        return "not given" if key == "thousands" else "not decided (no fraction read)"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if key == "time":
        return _TIME_FROM.get(value, str(value))
    if key == "delimiter":
        return {"\t": "tab", "blanks": "blanks"}.get(value, repr(value))
    if key in ("decimal", "thousands") and len(value) == 1:
        return repr(value)
    return str(value)


def _text(info: dict) -> str:
    keys = [k for k in _LABELS if k in info["dialect"]] + [k for k in info["dialect"] if k not in _LABELS]
    dialect = ", ".join(f"{_LABELS.get(k, k)} {_shown(k, info['dialect'][k])}" for k in keys)
    start = "" if not info["start_s"] else f", first sample at {info['start_s']:.9g} s"
    lines = [f"file      {info['path']}",
             f"format    {FORMAT_NAMES.get(info['format'], info['format'])}",
             textwrap.fill(f"dialect   {dialect or '-'}", 78, subsequent_indent=" " * 10, break_long_words=False),
             f"time      {info['time_name']!r}{start}",
             f"rate      {info['fs_hz']:.9g} Hz",
             f"samples   {info['n_samples']}",
             f"duration  {info['duration_s']:.9g} s",
             f"channels  {len(info['channels'])}"]
    rows = [("name", "unit in file", "SI unit")] + [(c["name"], c["unit"] or "-", c["si_unit"] or "-")
                                                     for c in info["channels"]]
    widths = [max(len(r[k]) for r in rows) for k in range(2)]
    lines += [f"  {a:{widths[0]}}  {b:{widths[1]}}  {c}" for a, b, c in rows]
    return "\n".join(lines)


def cmd_info(args) -> int:
    """Run ``rigsim info``; returns 0, raises MeasuredDataError (one sentence) for a file it cannot read."""
    from rigsim.correction.io.measured import read_channels

    record = read_channels(args.file, time_col=args.time_col, decimal=args.decimal, thousands=args.thousands)
    info = summary(record)
    print(json.dumps(info, indent=2) if args.json else _text(info))
    return 0
