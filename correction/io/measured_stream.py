"""The data lines of a delimited text file, streamed into float columns.

:class:`Stream` parses blocks of lines and keeps only the columns read, each a float array
(allocated for the rows the file's size suggests, grown and cut to the rows read), so memory is
the result plus one block. A block is parsed by numpy's C reader when it can hold only plain
numbers in the file's decimal mark, once whole quoted fields are unquoted and one thousands
separator that groups digits by threes is taken out (the decimal mark known); else field by
field (:meth:`rigsim.correction.io.measured_numbers.NumberFormat.read`), which also gathers the evidence
for the decimal mark and refuses what is not a number. The first block, the lines that gave the
layout, is always read field by field. Errors name the file line of the row: skipped lines
(blank, comments) are counted.
"""

from __future__ import annotations

import re
from array import array
from bisect import bisect_right
from itertools import repeat

import numpy as np

from rigsim.correction.io.measured_core import MeasuredDataError
from rigsim.correction.io.measured_numbers import SPACES, NumberFormat

__all__ = ["SKIP_PREFIXES", "BLOCK_CHARS", "Stream", "split_fields", "check_widths"]

#: Lines below the header that are skipped (``;`` may start a row of a semicolon file).
SKIP_PREFIXES = ("#", "//", "%")
#: Characters of lines parsed at once.
BLOCK_CHARS = 1 << 22
_BLANKS = re.compile(r"[ \t]+")
_GROUPERS = ",.'" + SPACES
_QUOTED: dict[str, re.Pattern] = {}


def split_fields(line: str, delimiter: str | None) -> list[str]:
    """The fields of one line as written (not stripped, the last one with the line's ``\\n`` if
    any; a quoted field without its quotes and with ``""`` read as ``"``); ``delimiter`` None:
    runs of blanks (space, tab)."""
    if delimiter is None:
        return _BLANKS.split(line.strip(" \t\n"))
    if '"' not in line:
        return line.split(delimiter)
    pattern = _QUOTED.get(delimiter)
    if pattern is None:
        e, blank = re.escape(delimiter), "[" + " \t".replace(delimiter, "") + "]*"
        pattern = _QUOTED[delimiter] = re.compile(
            rf'(?:^|{e})(?:{blank}"([^"]*(?:""[^"]*)*)"{blank}(?={e}|$)|([^{e}]*))')
    return [q.replace('""', '"') if q else p for q, p in pattern.findall(line)]


def check_widths(rows: list[list[str]], width: int, line_of, path) -> None:
    """Refuse the first of ``rows`` (fields) without ``width`` fields (or one more, empty: a
    trailing delimiter), naming its file line ``line_of(i)``."""
    lens = np.fromiter(map(len, rows), np.int64, len(rows))
    for i in np.flatnonzero(lens != width).tolist():
        if lens[i] != width + 1 or rows[i][-1].strip():
            raise MeasuredDataError(f"line {line_of(i)} of {str(path)!r} has {lens[i]} fields but the header has "
                                    f"{width}; fix: give the row one field per column")


class _Lines:
    """The file line of each data row: the row's index plus an offset, which grows at each
    skipped line (kept only where it changes)."""

    def __init__(self):
        self.rows, self.offsets = array("q"), array("q")

    def add(self, row0: int, numbers) -> None:
        """Rows from ``row0`` are on file lines ``numbers`` (an int: the first of consecutive lines)."""
        if isinstance(numbers, int):
            off = np.array([numbers - row0])
        else:
            off = numbers - np.arange(row0, row0 + numbers.size)
        change = np.flatnonzero(np.diff(off, prepend=self.offsets[-1] if self.offsets else off[0] - 1))
        self.rows.extend((row0 + change).tolist())
        self.offsets.extend(off[change].tolist())

    def __call__(self, row: int) -> int:
        return int(row + self.offsets[bisect_right(self.rows, row) - 1])


def _grouping(b: np.ndarray, p: np.ndarray, sep: int, mark: int, ends: np.ndarray) -> bool:
    """The bytes ``b`` (five of padding each side) at ``p`` are thousands separators ``sep``
    grouping digits by threes: 1 to 3 digits not starting with 0 (after no digit, ``sep``,
    ``mark`` or exponent), then groups of exactly three, in a field (ending before ``ends``, one
    per separator) without an exponent."""
    digit = (b >= 48) & (b <= 57)
    ok = digit[p - 1] & digit[p + 1] & digit[p + 2] & digit[p + 3] & ~digit[p + 4]
    middle = (b[p - 4] == sep) & digit[p - 2] & digit[p - 3]
    run = np.where(~digit[p - 2], 1, np.where(~digit[p - 3], 2, np.where(~digit[p - 4], 3, 4)))
    before = b[p - 1 - run]
    first = (run <= 3) & (b[p - run] != 48) & (before != sep) & (before != mark) & (before != 101) & (before != 69)
    if not np.all(ok & (middle | first)):
        return False
    exponents = np.flatnonzero((b == 101) | (b == 69))
    if not exponents.size:
        return True
    e = np.searchsorted(exponents, p)
    within = e < exponents.size
    return not np.any(exponents[np.minimum(e, exponents.size - 1)][within] < ends[within])


def _ungroup(text: str, sep: str, mark: str, delimiter: str | None) -> str | None:
    """``text`` without the thousands separator ``sep``, or None when some ``sep`` does not
    group digits by threes (:func:`_grouping`)."""
    if sep in "\u00a0\u202f":  # one byte in the check below
        if "\x01" in text:
            return None
        text, sep = text.replace(sep, "\x01"), "\x01"
    b = np.frombuffer(("\n" * 5 + text + "\n" * 5).encode("utf-8"), dtype=np.uint8)
    p = np.flatnonzero(b == ord(sep))
    ends = np.flatnonzero((b == 10) | ((b == 32) | (b == 9) if delimiter is None else (b == ord(delimiter))))
    return text.replace(sep, "") if _grouping(b, p, ord(sep), ord(mark), ends[np.searchsorted(ends, p)]) else None


def _unquote(text: str, delimiter: str | None, mark: str | None, grouping: bool) -> str | None:
    """``text`` without its double quotes when each pair quotes a whole field (the opening quote
    after a delimiter or a line start, the closing one before a delimiter or a line end, on one
    line, no quote between them); a delimiter inside a pair becomes a point when it is the
    decimal ``mark``, or is taken out when ``grouping`` allows it as a thousands separator and it
    groups digits (:func:`_grouping`). None otherwise."""
    if delimiter is None:
        return None
    b = np.frombuffer(("\n" * 5 + text + "\n" * 5).encode("utf-8"), dtype=np.uint8)
    q = np.flatnonzero(b == 34)
    if q.size % 2:
        return None
    opening, closing = q[0::2], q[1::2]
    d, lines = ord(delimiter), np.flatnonzero(b == 10)
    if not (np.all((b[opening - 1] == d) | (b[opening - 1] == 10)) and np.all((b[closing + 1] == d)
                                                                               | (b[closing + 1] == 10))
            and np.array_equal(np.searchsorted(lines, opening), np.searchsorted(lines, closing))):
        return None
    keep = b != 34
    delims = np.flatnonzero(b == d)
    k = np.searchsorted(opening, delims) - 1  # the last opening quote before each delimiter
    inside = (k >= 0) & (delims < closing[np.maximum(k, 0)])
    p = delims[inside]
    if p.size:
        if mark == delimiter:
            b = b.copy()
            b[p] = 46
        elif mark is None or not grouping or not _grouping(b, p, d, ord(mark), closing[k[inside]]):
            return None
        else:
            keep[p] = False
    return b[keep].tobytes().decode("utf-8")[5:-5]


def _skips(lines: list[str]) -> bool:
    """Some line is blank or a comment (lines starting with a digit or later never are)."""
    if min(lines) >= "0":
        return False
    return any(not (s := ln.strip()) or s.startswith(SKIP_PREFIXES) for ln in lines)


class Stream:
    """Columns ``cols`` (named ``names``) of the data lines of a file with ``width`` columns.

    Feed it the first data lines (:meth:`first`), then the open file (:meth:`rest`); :meth:`finish`
    gives the columns and the file line of each row.
    """

    def __init__(self, path, delimiter: str | None, width: int, cols: list[int], names: list[str],
                 fmt: NumberFormat, capacity: int):
        self.path, self.d, self.width, self.cols, self.names, self.fmt = str(path), delimiter, width, cols, names, fmt
        self.last = (width - 1) in cols  # numpy's reader then refuses a row too short
        self.values = [np.empty(capacity) for _ in cols]
        self.ambiguous: list = [None] * len(cols)
        self.first_ambiguous: list = [None] * len(cols)
        self.rows = 0
        self.lines = _Lines()

    def first(self, sample: list[tuple[int, str]]) -> None:
        """The data lines that gave the layout, as (file line, text)."""
        if sample:
            numbers = np.array([n for n, _ in sample], dtype=np.int64)
            self._block([ln for _, ln in sample], numbers, None, fast=False)

    def rest(self, fh, number: int) -> None:
        """The rest of the open text file ``fh``, whose line ``number`` was the last read."""
        while True:
            lines = fh.readlines(BLOCK_CHARS)  # whole lines, each with its "\n" (but maybe the last)
            if not lines:
                return
            first, number = number + 1, number + len(lines)
            if _skips(lines):
                keep = [i for i, ln in enumerate(lines) if (s := ln.strip()) and not s.startswith(SKIP_PREFIXES)]
                lines = [lines[i] for i in keep]
                numbers = first + np.array(keep, dtype=np.int64)
            else:
                numbers = first
            if lines:
                self._block(lines, numbers, "".join(lines), fast=True)
            del lines

    def _block(self, lines: list[str], numbers, text: str | None, fast: bool) -> None:
        row0 = self.rows
        self.lines.add(row0, numbers)
        if isinstance(numbers, int):
            def line_of(i):
                return numbers + i
        else:
            def line_of(i):
                return int(numbers[i])
        values, amb = (self._fast(lines, text, line_of) if fast else None), None
        if values is None:
            values, amb = self._checked(lines, line_of)
        self._store(row0, values, amb)

    def _fast(self, lines: list[str], text: str, line_of):
        """The block by numpy's reader, or None when it may hold more than plain numbers in the
        file's decimal mark, digits grouped by threes with one thousands separator (then
        :meth:`_checked` reads it)."""
        mark, d, groupers = self.fmt.mark, self.d, self.fmt.thousands
        if '"' in text:
            if mark == d and "." in text:
                return None
            text = _unquote(text, d, mark, groupers is None or (d or "") in groupers)
            if text is None:
                return None
            mark = "." if mark == d else mark  # quoted decimal commas are points now
            lines = text.split("\n")
            if lines[-1] == "":
                lines.pop()
        if (d is None and ("\u00a0" in text or "\u202f" in text)) or not self._counted(lines, text):
            return None
        if mark is None:  # nothing decided yet: only digits, signs, exponents
            return None if "." in text or ("," in text and d != ",") else self._load(lines, lines, line_of)
        if mark == "." or "." not in text:
            plain = lines if mark == "." or d == "," or "," not in text else text.replace(",", ".").split("\n")
            values = self._load(plain, lines, line_of)
            if values is not None:
                return values
        seps = [c for c in (groupers if groupers is not None else _GROUPERS)
                if c not in (mark, d) and c in text and not (d is None and c == " ")]
        if len(seps) != 1 or (mark == "," and d == ","):
            return None
        text = _ungroup(text, seps[0], mark, d)
        if text is None or (mark == "," and "." in text):
            return None
        return self._load((text.replace(",", ".") if mark == "," else text).split("\n"), lines, line_of)

    def _counted(self, lines: list[str], text: str) -> bool:
        """Every line has as many fields as the header (plus a trailing delimiter)."""
        d, n, w = self.d, len(lines), self.width
        if d is None:
            return not np.any(np.fromiter(map(len, map(str.split, lines)), np.int64, n) != w)
        if self.last and text.count(d) == n * (w - 1):  # numpy's reader refuses a line too short
            return True
        counts = np.fromiter(map(str.count, lines, repeat(d)), np.int64, n)
        return all(counts[i] == w and lines[i].rstrip().endswith(d) for i in np.flatnonzero(counts != w - 1).tolist())

    def _load(self, src: list[str], lines: list[str], line_of):
        """``src`` (the block's lines, maybe rewritten to plain numbers) by numpy's reader; None
        when some field read is not a plain number."""
        try:
            arr = np.loadtxt(src, delimiter=self.d, usecols=self.cols, dtype=float, comments=None, ndmin=2,
                             quotechar=None)
        except ValueError:
            return None
        if arr.shape[0] != len(lines):
            return None
        bad = ~np.isfinite(arr)
        if bad.any():
            k = int(np.flatnonzero(bad.any(axis=0))[0])
            i = int(np.argmax(bad[:, k]))
            field = split_fields(lines[i], self.d)[self.cols[k]].strip()
            raise self.fmt.missing(self.names[k], field, line_of(i))
        return arr

    def _checked(self, lines: list[str], line_of):
        """The block field by field: counts, numbers, decimal marks checked; values and the
        fields still ambiguous."""
        rows = [split_fields(ln, self.d) for ln in lines]
        check_widths(rows, self.width, line_of, self.path)
        table = np.empty((len(rows), len(self.cols)), dtype=object)  # the fields' own strings: no fixed width
        for k, j in enumerate(self.cols):
            table[:, k] = [r[j].strip() for r in rows]
        values, amb = self.fmt.read(table, self.names, line_of)
        if amb is not None:
            for k in np.flatnonzero(amb.any(axis=0)).tolist():
                if self.first_ambiguous[k] is None:
                    i = int(np.flatnonzero(amb[:, k])[0])
                    self.first_ambiguous[k] = (line_of(i), str(table[i, k]))
        return values, amb

    def _store(self, row0: int, values: np.ndarray, amb) -> None:
        end = row0 + values.shape[0]
        size = self.values[0].size
        if end > size:
            size = max(end, int(size * 1.5) + 16)
            for v in self.values:
                v.resize(size, refcheck=False)
            for a in self.ambiguous:
                if a is not None:
                    a.resize(size, refcheck=False)
        for k, v in enumerate(self.values):
            v[row0:end] = values[:, k]
            if amb is not None and amb[:, k].any():
                if self.ambiguous[k] is None:
                    self.ambiguous[k] = np.zeros(size, dtype=np.int8)
                self.ambiguous[k][row0:end] = amb[:, k]
        self.rows = end

    def finish(self):
        """(the columns, each cut to the rows read, ambiguous fields settled; row -> file line)."""
        n = self.rows
        for k, v in enumerate(self.values):
            v.resize(n, refcheck=False)
            if self.ambiguous[k] is not None:
                self.fmt.settle(v, self.ambiguous[k][:n], self.names[k], self.first_ambiguous[k])
                self.ambiguous[k] = None
        return self.values, self.lines
