"""Measured channels as delimited text (.csv, .txt, .dat), the way DAQ software writes them.

Read (:func:`read_csv_channels`):

* encoding: UTF-8 (a BOM is stripped), UTF-16 with a BOM, else Windows-1252 (``µm``, ``°C`` of
  older German DAQ exports); a file with NUL bytes is refused as binary;
* line ends ``\\n``, ``\\r\\n`` or ``\\r``; blank lines and lines starting with ``#``, ``//`` or
  ``%`` below the header are skipped; lines of any length;
* a preamble of comment lines (``#``, ``;``, ``%``, ``//``) and blank lines before the header;
  ``# key: value`` (or ``key = value``) lines become ``metadata[key]`` (a key given twice: its
  values joined by a newline), other comment lines ``metadata["comment"]``;
* the delimiter: tab, semicolon or comma, the first of these that splits the header into two or
  more fields and most of the first 50 data lines into as many (else the first that splits the
  header); when none splits the header, runs of blanks (``.dat`` tables); double-quoted fields
  (``""`` a quote inside); a trailing delimiter on every line is dropped;
* the header line; units in it as ``Fz_FL [kN]``, ``Fz_FL[kN]``, ``Fz_FL (kN)``, ``Kraft/kN``,
  ``Kraft in kN`` (parentheses, slash and "in" only around a known unit), or as a suffix
  (``time_ms``, ``force_N``: the suffix stays part of the name); channel names are returned without
  the bracketed decoration;
* an optional units row right below the header (``s;kN;mm``, ``[s]``, ``(N)``): the first line
  below the header when none of its fields is a number;
* numbers: decimal mark ``.`` or ``,``, thousands separators ``,`` ``.`` ``'``, space, U+00A0,
  U+202F, detected from every field of the columns read, or named (``decimal=``,
  ``thousands=``); :mod:`rigsim.correction.io.measured_numbers` gives the rules (an ambiguous file is
  refused, never guessed).

The file is streamed: the first lines (up to :data:`SAMPLE_LINES` data lines, about
:data:`SAMPLE_CHARS` characters) give the layout, then blocks of lines of about
:data:`rigsim.correction.io.measured_stream.BLOCK_CHARS` characters are parsed; only the columns read are
kept, as floats (:mod:`rigsim.correction.io.measured_stream`). Data rows must have as many fields as the
header (line named otherwise). A column with no number in the first lines (a status text) is
ignored unless selected; a selected column must be numbers on every row, finite and non-empty
(column, line, value and file named otherwise).
"""

from __future__ import annotations

import codecs
import io
import os
import re
from collections import Counter
from itertools import chain
from collections.abc import Mapping
from types import MappingProxyType

import numpy as np

from rigsim.correction.io.measured_core import MeasuredChannels, MeasuredDataError, is_time_name, open_input, to_si
from rigsim.correction.io.measured_time import uniform_rate
from rigsim.correction.io.measured_numbers import NumberFormat, classify
from rigsim.correction.io.measured_stream import SKIP_PREFIXES, Stream, check_widths, split_fields
from rigsim.correction.io.measured_units import split_name_unit, strip_unit_field

__all__ = ["COMMENT_PREFIXES", "SAMPLE_LINES", "SAMPLE_CHARS", "MAX_COLUMNS", "read_csv_channels", "check_names",
           "write_csv"]

COMMENT_PREFIXES = ("#", ";", "%", "//")
#: The first lines read for the layout: at most this many data lines...
SAMPLE_LINES = 500
#: ... and about this many characters.
SAMPLE_CHARS = 1 << 20
#: Most columns a header may have: an Excel worksheet holds 16 384 (Microsoft, "Excel
#: specifications and limits"), far more channels than a rig records; a wider header is refused
#: before it is split.
MAX_COLUMNS = 16384
_NUMBER = re.compile(r"[+-]?(\d[\d.,_' \u00a0\u202f]*|[.,]\d+)([eE][+-]?\d+)?|[+-]?(nan|inf|infinity)", re.I)
_KEY_VALUE = re.compile(r"^\s*(?P<key>[^:=]*?[^:=\s])\s*(?::|=)\s?(?P<value>.*)$")


def _open(path, legacy: bool = False) -> io.TextIOWrapper:
    """The file as text with universal line ends: UTF-16 (BOM), UTF-8, or Windows-1252 when
    ``legacy``; a file that is missing, not a regular file or too large is refused
    (:func:`~rigsim.correction.io.measured_core.open_input`: the columns read, float64 from fields of at least
    two bytes with their delimiter, take at most four times the file)."""
    raw = open_input(path, memory_per_byte=4.0)
    try:
        head = raw.read(65536)
    except OSError as exc:
        raw.close()
        raise MeasuredDataError(f"cannot read input file {str(path)!r}: {exc.strerror}") from None
    raw.seek(0)
    if head.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        return io.TextIOWrapper(raw, encoding="utf-16", newline=None)
    bom = head.startswith(codecs.BOM_UTF8)
    if b"\x00" in head[3 if bom else 0:]:
        raw.close()
        raise MeasuredDataError(f"input file {str(path)!r} is binary, not delimited text; export it as CSV or give "
                                "an .rsp, .mf4 or .tdms file")
    if legacy:
        raw.seek(3 if bom else 0)
        return io.TextIOWrapper(raw, encoding="cp1252", errors="replace", newline=None)
    return io.TextIOWrapper(raw, encoding="utf-8-sig", newline=None)


def _fields(line: str, delimiter: str | None) -> list[str]:
    return [f.strip() for f in split_fields(line, delimiter)]


def _split_header(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:  # keep "Time [s]" together in a blank-separated header
        return re.findall(r"\S+(?:\s*[\[(][^\])]*[\])])?", line)
    return _fields(line, delimiter)


def _trim(row: list[str], width: int) -> list[str]:
    """Drop one empty field after the last column (a trailing delimiter)."""
    return row[:-1] if len(row) == width + 1 and not row[-1].strip() else row


def _sniff(header: str, sample: list[str]) -> str | None:
    """Tab, semicolon or comma: of those that split the header into two or more fields, the first
    that splits most sample lines into as many (else the first of them); None: blanks."""
    fits = []
    for d in ("\t", ";", ","):
        head = _split_header(header, d)
        if head and head[-1] == "":
            head = head[:-1]
        if len(head) >= 2:
            rows = [_trim(split_fields(r, d), len(head)) for r in sample]
            if not rows or sum(len(r) == len(head) for r in rows) * 2 > len(rows):
                return d
            fits.append(d)
    return fits[0] if fits else None


def _comment(line: str, meta: dict) -> None:
    body = line[2:] if line.startswith("//") else line[1:]
    m = _KEY_VALUE.match(body)
    key, value = (m.group("key"), m.group("value").rstrip()) if m else ("comment", body.strip())
    meta[key] = value if key not in meta else f"{meta[key]}\n{value}"


def _is_units_row(row: list[str]) -> bool:
    """No field is a number, except a dimensionless "1", and some field is not empty."""
    return any(f and f != "1" for f in row) and not any(_NUMBER.fullmatch(f) and f != "1" for f in row)


def _head(fh, path):
    """(metadata, header line number, header, first data lines as (line number, text), lines read)."""
    meta: dict[str, str] = {}
    number = 0
    for line in iter(fh.readline, ""):
        number += 1
        s = line.strip()
        if s and not s.startswith(COMMENT_PREFIXES):
            break
        if s:
            _comment(s, meta)
    else:
        raise MeasuredDataError(f"input file {str(path)!r} is empty; it needs a header line and data rows")
    header, at, sample, chars = line.rstrip("\n"), number, [], 0
    d = max(("\t", ";", ","), key=header.count)
    fields = header.count(d) + (not header.rstrip().endswith(d)) if d in header else sum(
        1 for _ in re.finditer(r"\S+", header))
    if fields > MAX_COLUMNS:
        raise MeasuredDataError(f"the header (line {at}) of {str(path)!r} has {fields} fields, more than the "
                                f"{MAX_COLUMNS} columns of an Excel worksheet and any rig's channels; fix: export "
                                "only the channels needed")
    while len(sample) < SAMPLE_LINES and chars < SAMPLE_CHARS:
        line = fh.readline()
        if not line:
            break
        number += 1
        s = line.strip()
        if s and not s.startswith(SKIP_PREFIXES):
            sample.append((number, line.rstrip("\n")))
            chars += len(line)
    if not sample:
        raise MeasuredDataError(f"input file {str(path)!r} has a header (line {at}) but no data rows")
    return meta, at, header, sample, number


def _find(names: list[str], headers: list[str], name: str, path, option: str) -> int:
    for key in (names, headers):
        if name in key:
            return key.index(name)
    low = [n.lower() for n in names]
    if low.count(name.lower()) == 1:
        return low.index(name.lower())
    raise MeasuredDataError(f"{option} {name!r} is not a column of {str(path)!r}; its columns are "
                            f"{', '.join(n for n in names if n)}")


def _time_column(names, headers, path, time_col: str | None) -> int:
    """Index of the time column: ``time_col`` if given, else the one column with a time name."""
    if time_col is not None:
        return _find(names, headers, time_col, path, "time column")
    hits = [j for j, n in enumerate(names) if is_time_name(n)]
    if len(hits) > 1:
        raise MeasuredDataError(f"{str(path)!r} has several time columns ({', '.join(names[j] for j in hits)}); "
                                "name the one to use (time_col)")
    if not hits:
        raise MeasuredDataError(f"{str(path)!r} has no time column (named time, t, zeit, time_s, time_ms...); add "
                                f"one or name it (time_col); its columns are {', '.join(names)}")
    return hits[0]


def _layout(fh, path):
    """Metadata, delimiter, header, names, units, the first data rows (after a units row), the
    number of the last line read and the dialect (delimiter, header line, units row)."""
    meta, at, header, sample, number = _head(fh, path)
    d = _sniff(header, [ln for _, ln in sample[:50]])
    head = _split_header(header, d)
    if head and head[-1] == "":
        head = head[:-1]
    names, units = map(list, zip(*(split_name_unit(x) for x in head))) if head else ([], [])
    first = _trim(_fields(sample[0][1], d), len(head))
    units_row = len(first) == len(head) and _is_units_row(first)
    if units_row:
        for j, f in enumerate(first):
            u = strip_unit_field(f)
            if u:
                if units[j] is not None and units[j] != u:
                    raise MeasuredDataError(f"column {names[j]!r} of {str(path)!r} says {units[j]!r} in the header "
                                            f"but {u!r} in the units row (line {sample[0][0]}); fix one of them")
                units[j] = u
        sample = sample[1:]
    dialect = {"delimiter": "blanks" if d is None else d, "header_line": at, "units_row": units_row}
    return meta, d, head, names, units, sample, number, dialect


def _numeric_columns(rows: list[list[str]], width: int) -> list[bool]:
    """Per column: some field of ``rows`` (each ``width`` fields) is a number (a text column otherwise)."""
    if not rows:
        return [False] * width
    status, _ = classify(list(chain.from_iterable(rows)))
    return list((status.reshape(len(rows), width) >= 0).any(axis=0))


def _select(path, names, headers, units, numeric, time_col, channels) -> tuple[int, list[int]]:
    dup = sorted(n for n, c in Counter(names).items() if n and c > 1)
    if dup:
        raise MeasuredDataError(f"column {dup[0]!r} appears more than once in the header of {str(path)!r}")
    jt = _time_column(names, headers, path, time_col)
    if channels is None:
        cols = [j for j in range(len(names)) if j != jt and numeric[j]]
        nameless = [j for j in cols if not names[j]]
        if nameless:
            raise MeasuredDataError(f"column {nameless[0] + 1} of {str(path)!r} has numbers but no name in the "
                                    "header; name it")
    else:
        cols = [_find(names, headers, c, path, "channel") for c in channels]
        if jt in cols:
            raise MeasuredDataError(f"channel {names[jt]!r} is the time column of {str(path)!r}; leave it out")
        if len(set(cols)) != len(cols):
            raise MeasuredDataError(f"channels {list(channels)!r} name a column twice; name each once")
    _, t_unit, t_src = to_si(names[jt], np.empty(0), units[jt], path)
    if t_unit not in ("s", ""):
        raise MeasuredDataError(f"time column {names[jt]!r} of {str(path)!r} is in {t_src!r}, not a unit of time; "
                                "fix: give it in s or ms")
    for j in cols:
        to_si(names[j], np.empty(0), units[j], path)  # an unknown unit, before the file is read
    return jt, cols


def _frozen(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def read_csv_channels(path, *, time_col: str | None = None, channels=None, decimal: str | None = None,
                      thousands: str | None = None) -> MeasuredChannels:
    """Read a delimited text file as :class:`~rigsim.correction.io.measured_core.MeasuredChannels`, in SI,
    streaming it; see the module docstring.

    Parameters
    ----------
    path : str or os.PathLike
    time_col : str, optional
        The time column; default: the one column with a time name.
    channels : list of str, optional
        Columns to read, in this order; default: every column with a number in the first lines.
    decimal : {".", ","}, optional
        The decimal mark; default: detected (:mod:`rigsim.correction.io.measured_numbers`).
    thousands : {"none", ",", ".", "'", "space"}, optional
        The thousands separator; default: detected.

    Raises
    ------
    MeasuredDataError
        One sentence naming the file and the column, line or value at fault, and the fix.
    """
    NumberFormat(path, decimal, thousands)  # the arguments, before the file is opened
    try:
        return _read(path, False, time_col, channels, decimal, thousands)
    except UnicodeDecodeError:
        return _read(path, True, time_col, channels, decimal, thousands)


def _read(path, legacy, time_col, channels, decimal, thousands) -> MeasuredChannels:
    with _open(path, legacy) as fh:
        meta, d, head, names, units, sample, number, dialect = _layout(fh, path)
        dialect["encoding"] = {"utf-8-sig": "utf-8"}.get(fh.encoding, fh.encoding)
        width = len(head)
        rows = [_trim(_fields(ln, d), width) for _, ln in sample]
        check_widths(rows, width, lambda i: sample[i][0], path)
        jt, cols = _select(path, names, head, units, _numeric_columns(rows, width), time_col, channels)
        size = os.fstat(fh.fileno()).st_size
        per_line = max(1.0, sum(len(ln) + 1 for _, ln in sample) / max(1, len(sample)))
        stream = Stream(path, d, width, [jt, *cols], [names[j] or f"#{j + 1}" for j in [jt, *cols]],
                        NumberFormat(path, decimal, thousands), capacity=int(size / per_line * 1.1) + 16)
        stream.first(sample)
        if stream.ambiguous[0] is None and stream.rows > 1:  # the time axis and its rate, before the rest is read
            t, _, _ = to_si(names[jt], stream.values[0][:stream.rows], units[jt], path)
            uniform_rate(t, names[jt], lambda i: f"line {stream.lines(i)} of {str(path)!r}")
        stream.rest(fh, number)
    values, where = stream.finish()
    dialect.update(decimal=stream.fmt.mark, thousands=stream.fmt.given[1])
    if values[0].size < 2:
        raise MeasuredDataError(f"input file {str(path)!r} has {values[0].size} data rows; at least two are needed")
    t_name = names[jt]
    t, _, _ = to_si(t_name, values[0], units[jt], path)
    values[0] = None
    fs = uniform_rate(t, t_name, lambda i: f"line {where(i)} of {str(path)!r}")
    data, si, src = {}, {}, {}
    for k, j in enumerate(cols, start=1):
        v, si[names[j]], src[names[j]] = to_si(names[j], values[k], units[j], path)
        values[k] = None
        data[names[j]] = _frozen(v)
    return MeasuredChannels(time_s=_frozen(t), data=MappingProxyType(data), units=MappingProxyType(si),
                            source_units=MappingProxyType(src), fs_hz=float(fs),
                            metadata=MappingProxyType({str(k): str(v) for k, v in meta.items()}), path=str(path),
                            format="csv", time_name=t_name, dialect=MappingProxyType(dialect))


def check_names(names, time_name: str, fmt: str) -> None:
    """Refuse channel names that would not read back as themselves from a CSV header."""
    for n in names:
        if not isinstance(n, str) or not n or n != n.strip() or any(c in n for c in ',"[]\n\r\t;'):
            raise MeasuredDataError(f"channel name {n!r} cannot be written to {fmt}: names must be non-empty, without "
                                    "blanks around them or any of , ; \" [ ] and line breaks; rename it")
        if split_name_unit(n) != (n, None) or is_time_name(n) or n == time_name or n.startswith(COMMENT_PREFIXES):
            raise MeasuredDataError(f"channel name {n!r} would read back as a unit decoration, a time column or a "
                                    f"comment from {fmt}; rename it")


def write_csv(path: str, time_s: np.ndarray, data: Mapping, units: Mapping, metadata: Mapping) -> None:
    """Write ``time [s]`` and each channel ``name [unit]`` as comma-separated text, metadata as a
    ``# key: value`` preamble (a multi-line value gives one line each). Values are written
    exactly (shortest repr of the float)."""
    check_names(list(data), "time", "CSV")
    out = []
    for k, v in metadata.items():
        k = str(k)
        if not k.strip() or any(c in k for c in ":=\n\r") or k != k.strip():
            raise MeasuredDataError(f"metadata key {k!r} cannot be written to CSV (no ':', '=', line breaks or "
                                    "surrounding blanks); rename it")
        out += [f"# {k}: {line}".rstrip() for line in (str(v).splitlines() or [""])]
    out.append(",".join(["time [s]"] + [f"{n} [{units.get(n, '')}]" if units.get(n, "") else n for n in data]))
    cols = [np.asarray(time_s, dtype=float)] + [np.asarray(v, dtype=float) for v in data.values()]
    text_cols = [list(map(repr, c.tolist())) for c in cols]
    out += [",".join(row) for row in zip(*text_cols)]
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(out) + "\n")
