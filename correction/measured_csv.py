"""Measured channels as delimited text (.csv, .txt, .dat), the way DAQ software writes them.

Read (:func:`read_table`, then :func:`channels_from_table`):

* encoding: UTF-8 (a BOM is stripped), UTF-16 with a BOM, else Windows-1252 (``µm``, ``°C`` of
  older German DAQ exports); a file with NUL bytes is refused as binary;
* line ends ``\\n``, ``\\r\\n`` or ``\\r``; blank lines are skipped;
* a preamble of comment lines (``#``, ``;``, ``%``, ``//``) and blank lines before the header;
  ``# key: value`` (or ``key = value``) lines become ``metadata[key]`` (a key given twice: its
  values joined by a newline), other comment lines ``metadata["comment"]``;
* the delimiter: tab, semicolon or comma, the first of these that splits the header into two or
  more fields and most of the first 50 data lines into as many (else the first that splits the
  header); when none splits the header, runs of blanks (``.dat`` tables); double-quoted fields;
  a trailing delimiter on every line is dropped;
* the header line; units in it as ``Fz_FL [kN]``, ``Fz_FL[kN]``, ``Fz_FL (kN)``, ``Kraft/kN``,
  ``Kraft in kN`` (parentheses, slash and "in" only around a known unit), or as a suffix
  (``time_ms``, ``force_N``: the suffix stays part of the name); channel names are returned without
  the bracketed decoration;
* an optional units row right below the header (``s;kN;mm``, ``[s]``, ``(N)``): the first line
  below the header when none of its fields is a number;
* the decimal mark: a comma when some field reads ``12,5`` (the German default with ``;`` or tab,
  or quoted in a comma file), else a point; with a decimal comma, ``1.234,5`` is 1234.5.

Data rows must have as many fields as the header (line named otherwise). A column with no
number at all (a status text) is ignored unless selected; a selected column must be numbers on
every row (line and value named otherwise), finite (NaN/inf named), non-empty.
"""

from __future__ import annotations

import codecs
import csv
import re
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from correction.measured_core import MeasuredDataError, is_time_name, make_channels, read_bytes, to_si, uniform_rate
from correction.measured_units import split_name_unit, strip_unit_field

__all__ = ["COMMENT_PREFIXES", "TextTable", "read_table", "column_values", "channels_from_table", "write_csv"]

COMMENT_PREFIXES = ("#", ";", "%", "//")
_NUMBER = re.compile(r"[+-]?(\d[\d.,_]*|[.,]\d+)([eE][+-]?\d+)?|[+-]?(nan|inf|infinity)", re.I)
_COMMA_DECIMAL = re.compile(r"[+-]?(\d{1,3}(\.\d{3})+|\d*),\d+([eE][+-]?\d+)?")
_THOUSANDS = re.compile(r"[+-]?\d{1,3}(\.\d{3})+(,\d*)?([eE][+-]?\d+)?")
_KEY_VALUE = re.compile(r"^\s*(?P<key>[^:=]*?[^:=\s])\s*(?::|=)\s?(?P<value>.*)$")


@dataclass
class TextTable:
    """A delimited text file: header, units, data lines; columns split when asked for."""

    headers: list[str]
    names: list[str]
    units: list  # per column: unit written (header or units row), None when none
    data_lines: list[str]
    lines: np.ndarray  # file line (1-based) of each data line
    first: list[str]  # the first data line's fields
    metadata: dict = field(default_factory=dict)
    delimiter: str | None = ","
    decimal: str = "."
    _columns: list | None = None
    _fast: dict = field(default_factory=dict)

    @property
    def columns(self) -> list:
        """Per column, its fields as written (stripped), numpy arrays of str."""
        if self._columns is None:
            rows = [_trim(r, len(self.headers)) for r in _split(self.data_lines, self.delimiter)]
            self._columns = [np.array([r[j] for r in rows], dtype=str) for j in range(len(self.headers))]
        return self._columns

    def field(self, i: int, j: int) -> str:
        """Field ``j`` of data line ``i``, as written (stripped)."""
        return _split([self.data_lines[i]], self.delimiter)[0][j]

    def preload(self, cols: list[int]) -> None:
        """Parse columns ``cols`` at once with numpy's C reader when the file allows it; any doubt
        (a thousands separator, a field that is not a number) leaves them to the checked path."""
        if not cols or (self.decimal == "," and (self.delimiter == "," or any("." in x for x in self.data_lines))):
            return
        lines = self.data_lines if self.decimal == "." else [x.replace(",", ".") for x in self.data_lines]
        try:
            arr = np.loadtxt(lines, delimiter=self.delimiter, usecols=cols, dtype=float, comments=None,
                             quotechar='"', ndmin=2)
        except ValueError:
            return
        self._fast.update({j: arr[:, k] for k, j in enumerate(cols)})


def _decode(path) -> str:
    raw = read_bytes(path)
    if raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        return raw.decode("utf-16")
    if raw.startswith(codecs.BOM_UTF8):
        raw = raw[len(codecs.BOM_UTF8):]
    if b"\x00" in raw[:65536]:
        raise MeasuredDataError(f"input file {str(path)!r} is binary, not delimited text; export it as CSV or give "
                                "an .rsp, .mf4 or .tdms file")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("cp1252", errors="replace")


def _split(lines: list[str], delimiter: str | None) -> list[list[str]]:
    if delimiter is None:
        return [ln.split() for ln in lines]
    return [[f.strip() for f in row] for row in csv.reader(lines, delimiter=delimiter)]


def _split_header(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:  # keep "Time [s]" together in a blank-separated header
        return re.findall(r"\S+(?:\s*[\[(][^\])]*[\])])?", line)
    return _split([line], delimiter)[0]


def _trim(row: list[str], width: int) -> list[str]:
    """Drop one empty field after the last column (a trailing delimiter)."""
    return row[:-1] if len(row) == width + 1 and row[-1] == "" else row


def _sniff(header: str, sample: list[str]) -> str | None:
    """Tab, semicolon or comma: of those that split the header into two or more fields, the first
    that splits most sample lines into as many (else the first of them); None: blanks."""
    fits = []
    for d in ("\t", ";", ","):
        head = _split_header(header, d)
        if head and head[-1] == "":
            head = head[:-1]
        if len(head) >= 2:
            rows = [_trim(r, len(head)) for r in _split(sample, d)]
            if not rows or sum(len(r) == len(head) for r in rows) * 2 > len(rows):
                return d
            fits.append(d)
    return fits[0] if fits else None


def _preamble(lines: list[str], meta: dict) -> int:
    i = 0
    while i < len(lines):
        s = lines[i].strip()
        if s and not s.startswith(COMMENT_PREFIXES):
            return i
        if s:
            body = s[2:] if s.startswith("//") else s[1:]
            m = _KEY_VALUE.match(body)
            key, value = (m.group("key"), m.group("value").rstrip()) if m else ("comment", body.strip())
            meta[key] = value if key not in meta else f"{meta[key]}\n{value}"
        i += 1
    return i


def _is_units_row(row: list[str]) -> bool:
    """No field is a number, except a dimensionless "1", and some field is not empty."""
    return any(f and f != "1" for f in row) and not any(_NUMBER.fullmatch(f) and f != "1" for f in row)


def read_table(path) -> TextTable:
    """Split a delimited text file into named columns of fields; see the module docstring."""
    lines = re.split(r"\r\n|\r|\n", _decode(path))
    meta: dict[str, str] = {}
    h = _preamble(lines, meta)
    if h >= len(lines):
        raise MeasuredDataError(f"input file {str(path)!r} is empty; it needs a header line and data rows")
    body = [(i + 1, ln) for i, ln in enumerate(lines[h + 1:], start=h + 1)
            if ln.strip() and not ln.lstrip().startswith(("#", "//", "%"))]
    d = _sniff(lines[h], [ln for _, ln in body[:50]]) if body else ","
    head = _split_header(lines[h], d)
    if head and head[-1] == "":
        head = head[:-1]
    if not body:
        raise MeasuredDataError(f"input file {str(path)!r} has a header (line {h + 1}) but no data rows")
    data_lines = [ln for _, ln in body]
    line_no = [n for n, _ in body]
    split = [split_name_unit(x) for x in head]
    names = [n for n, _ in split]
    units = [u for _, u in split]
    rows = [_trim(r, len(head)) for r in _split(data_lines[:501], d)]
    if _is_units_row(rows[0]) and len(rows[0]) == len(head):
        for j, f in enumerate(rows[0]):  # the units row
            u = strip_unit_field(f)
            if u:
                if units[j] is not None and units[j] != u:
                    raise MeasuredDataError(f"column {names[j]!r} of {str(path)!r} says {units[j]!r} in the header "
                                            f"but {u!r} in the units row (line {line_no[0]}); fix one of them")
                units[j] = u
        rows, data_lines, line_no = rows[1:], data_lines[1:], line_no[1:]
    columns = None
    if d is None:
        counts = [len(x.split()) for x in data_lines]
    elif not any('"' in x for x in data_lines):  # no quotes: a count of delimiters
        counts = [x.count(d) + 1 - (x.rstrip().endswith(d) and x.count(d) == len(head)) for x in data_lines]
    else:
        full = [_trim(r, len(head)) for r in _split(data_lines, d)]
        counts = [len(r) for r in full]
        columns = [np.array([r[j] for r in full], dtype=str) for j in range(len(head))]
    bad = next((i for i, c in enumerate(counts) if c != len(head)), None)
    if bad is not None:
        raise MeasuredDataError(f"line {line_no[bad]} of {str(path)!r} has {counts[bad]} fields but the header has "
                                f"{len(head)}; fix the row")
    decimal = "," if any(_COMMA_DECIMAL.fullmatch(f) for row in rows for f in row) else "."
    return TextTable(headers=head, names=names, units=units, data_lines=data_lines,
                     lines=np.array(line_no, dtype=int), first=rows[0] if rows else [], metadata=meta, delimiter=d,
                     decimal=decimal, _columns=columns)


def _parse(text: str, decimal: str) -> float | None:
    if decimal == ",":
        if "." in text:
            if not _THOUSANDS.fullmatch(text):
                return None
            text = text.replace(".", "")
        text = text.replace(",", ".")
    try:
        return float(text)
    except ValueError:
        return None


def _convert(fields: np.ndarray, decimal: str):
    """All fields as floats, or None when some field is not a number."""
    try:
        return (np.char.replace(fields, ",", ".") if decimal == "," else fields).astype(float)
    except ValueError:
        values = [_parse(f, decimal) for f in fields]
        return None if any(v is None for v in values) else np.array(values, dtype=float)


def is_text_column(table: TextTable, j: int) -> bool:
    """True for a column without a single number (a status or comment text, or empty)."""
    if not table.first or _parse(table.first[j], table.decimal) is not None:
        return False
    return not any(_parse(f, table.decimal) is not None for f in table.columns[j])


def column_values(table: TextTable, j: int, path) -> np.ndarray:
    """Column ``j`` as finite floats; one sentence naming the column, line and value otherwise."""
    name = table.names[j] or f"#{j + 1}"
    values = table._fast.get(j)
    if values is None:
        fields = table.columns[j]
        values = _convert(fields, table.decimal)
        if values is None:
            i = next(i for i, f in enumerate(fields) if _parse(f, table.decimal) is None)
            if fields[i] == "":
                raise MeasuredDataError(f"column {name!r} is empty at line {table.lines[i]} of {str(path)!r}; fix: "
                                        "fill the gap or leave the column out")
            raise MeasuredDataError(f"column {name!r} is not numeric at line {table.lines[i]} ({str(fields[i])!r}); "
                                    "fix: give numbers only, or leave the column out")
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        i = int(bad[0])
        raise MeasuredDataError(f"column {name!r} has {table.field(i, j)!r} at line {table.lines[i]}; fix: remove or "
                                "interpolate the missing samples")
    return values


def _find(table: TextTable, name: str, path, option: str) -> int:
    for key in (table.names, table.headers):
        if name in key:
            return key.index(name)
    low = [n.lower() for n in table.names]
    if low.count(name.lower()) == 1:
        return low.index(name.lower())
    raise MeasuredDataError(f"{option} {name!r} is not a column of {str(path)!r}; its columns are "
                            f"{', '.join(n for n in table.names if n)}")


def time_column(table: TextTable, path, time_col: str | None = None) -> int:
    """Index of the time column: ``time_col`` if given, else the one column with a time name."""
    if time_col is not None:
        return _find(table, time_col, path, "time column")
    hits = [j for j, n in enumerate(table.names) if is_time_name(n)]
    if len(hits) > 1:
        raise MeasuredDataError(f"{str(path)!r} has several time columns ({', '.join(table.names[j] for j in hits)}); "
                                "name the one to use (time_col)")
    if not hits:
        raise MeasuredDataError(f"{str(path)!r} has no time column (named time, t, zeit, time_s, time_ms...); add "
                                f"one or name it (time_col); its columns are {', '.join(table.names)}")
    return hits[0]


def channels_from_table(table: TextTable, path, *, time_col=None, channels=None):
    """:class:`~correction.measured_core.MeasuredChannels` of a table: the time column, the chosen
    channels (default: every column with numbers) converted to SI, the uniform rate."""
    dup = sorted({n for n in table.names if n and table.names.count(n) > 1})
    if dup:
        raise MeasuredDataError(f"column {dup[0]!r} appears more than once in the header of {str(path)!r}")
    if table.lines.size < 2:
        raise MeasuredDataError(f"input file {str(path)!r} has {table.lines.size} data rows; at least two are needed")
    jt = time_column(table, path, time_col)
    if channels is None:
        cols = [j for j in range(len(table.names)) if j != jt and not is_text_column(table, j)]
        nameless = [j for j in cols if not table.names[j]]
        if nameless:
            raise MeasuredDataError(f"column {nameless[0] + 1} of {str(path)!r} has numbers but no name in the "
                                    "header; name it")
    else:
        cols = [_find(table, c, path, "channel") for c in channels]
        if jt in cols:
            raise MeasuredDataError(f"channel {table.names[jt]!r} is the time column of {str(path)!r}; leave it out")
        if len(set(cols)) != len(cols):
            raise MeasuredDataError(f"channels {list(channels)!r} name a column twice; name each once")
    table.preload(sorted({jt, *cols}))
    t_name = table.names[jt]
    t, t_unit, t_src = to_si(t_name, column_values(table, jt, path), table.units[jt], path)
    if t_unit not in ("s", ""):
        raise MeasuredDataError(f"time column {t_name!r} of {str(path)!r} is in {t_src!r}, not a unit of time; "
                                "fix: give it in s or ms")
    fs = uniform_rate(t, t_name, lambda i: f"line {table.lines[i]}")
    data, units, src = {}, {}, {}
    for j in cols:
        data[table.names[j]], units[table.names[j]], src[table.names[j]] = to_si(
            table.names[j], column_values(table, j, path), table.units[j], path)
    meta = dict(table.metadata)
    return make_channels(time_s=t, data=data, units=units, source_units=src, fs_hz=fs, metadata=meta,
                         path=path, fmt="csv", time_name=t_name), jt


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
