"""Numbers in delimited text files: each field's decimal mark and thousands separator, read
unambiguously or refused.

A field is a number when it reads, after an optional sign ``+``/``-``, as

* digits with at most one decimal mark, ``.`` or ``,``, and an optional exponent (``12,5``,
  ``-0.25``, ``.5``, ``1,5e-03``, ``1E5``);
* digits grouped by threes with one thousands separator -- ``,``, ``.``, ``'``, a space, a
  no-break space U+00A0 or a narrow no-break space U+202F -- the first group 1 to 3 digits not
  starting with 0, then an optional decimal mark (the other of ``.`` and ``,``) and fraction, no
  exponent (``21,988.5``, ``1.234.567``, ``21 988,5``, ``21'988.5``);
* ``nan``, ``inf``: numbers, refused as missing samples by the readers.

What a field tells about the decimal mark:

* it decides: one ``.`` or ``,`` followed by other than three digits (``12,5``, ``0.25``,
  ``1.2345``), after a 0 or nothing (``0,125``, ``.500``), after more than three digits
  (``1234.567``), or before an exponent (``1.234e3``); two different separators, the last one
  the decimal mark (``1.234,5``, ``21 988,5``); a ``,`` or ``.`` grouping two or more groups
  (``1,234,567``: the decimal mark is the other one);
* it is ambiguous: one ``.`` or ``,`` between 1 to 3 digits (not starting with 0) and exactly
  three (``21,988``, ``1.500``): a decimal mark (21.988) or a thousands separator (21988);
* it tells nothing: digits alone, or grouped by ``'`` or a space without a decimal part.

A file has one decimal mark. The fields of the columns read (the time column and the chosen
channels, every row) that decide it must agree: a file where one field decides a decimal point
and another a decimal comma is refused naming both places. Ambiguous fields read with that mark
(``21,988`` is 21.988 in a file with decimal commas, 21988 in one with decimal points). When
some field is ambiguous and no field decides, the file is refused naming the column, with the
fix: ``decimal=`` (``--decimal``) or ``thousands=`` (``--thousands``).

Given ``decimal=``, a field with the other mark is refused; given ``thousands=``, only that
separator groups digits (``"none"``: none does, ``"space"``: a space, U+00A0 or U+202F).
Either settles every ambiguous field; ``thousands=","`` implies ``decimal="."`` and
``thousands="."`` implies ``decimal=","``.
"""

from __future__ import annotations

import re
from collections.abc import Callable

import numpy as np

from rigsim.correction.io.measured_core import MeasuredDataError

__all__ = ["SPACES", "DECIMALS", "THOUSANDS", "WIDE", "LONGEST", "CHUNK", "CHUNK_CHARS", "NumberFormat", "classify"]

#: The blanks that group digits: space, no-break space U+00A0, narrow no-break space U+202F.
SPACES = " \u00a0\u202f"
#: ``decimal=`` values.
DECIMALS = (".", ",")
#: ``thousands=`` values -> the characters that group digits (``""``: none).
THOUSANDS = {"none": "", ",": ",", ".": ".", "'": "'", "space": SPACES}

# a field's status (classify): a number telling nothing, deciding a mark, ambiguous, or not a number
PLAIN, POINT, COMMA, AMB_POINT, AMB_COMMA = 0, 1, 2, 3, 4
EMPTY, BAD, GROUPING = -1, -2, -3
_MARK = {POINT: ".", COMMA: ","}
_DECIDE = {".": POINT, ",": COMMA}
_AMBIGUOUS = {AMB_POINT: ".", AMB_COMMA: ","}
_OTHER = {".": ",", ",": "."}
_NAME = {".": "point", ",": "comma"}
_BLANKS = "'" + SPACES
#: Longest field (characters) classified with others in one fixed-width array: a float64 printed
#: exactly takes at most 24 characters, 1,234,567,890.123456789 grouped 23.
WIDE = 40
#: Longest field (characters) read as a number: a float64 printed in full without exponent takes
#: up to 309 digits before the point (1.8e308) or some 770 after it (the smallest subnormal);
#: numpy's parser takes a time that grows faster than the length beyond.
LONGEST = 1 << 10
#: Fields classified at once, and characters (the longest field's, times the fields) of one
#: fixed-width array: 4 MB of UCS-4.
CHUNK, CHUNK_CHARS = 1 << 16, 1 << 20
_NUMBER_CHARS = re.compile("[0-9+.,eE'_" + SPACES + "-]*")


def _floats(a: np.ndarray):
    """``a`` (strings) as floats, and a mask of the fields that are numbers."""
    try:
        return a.astype(float), np.ones(a.size, dtype=bool)
    except ValueError:
        out, ok = np.full(a.size, np.nan), np.zeros(a.size, dtype=bool)
        for i, s in enumerate(a.tolist()):
            try:
                out[i], ok[i] = float(s), True
            except ValueError:
                pass
        return out, ok


def _ambiguous(b: np.ndarray) -> np.ndarray:
    """Fields of ``b`` (one ``.``, numbers) with 1-3 digits, not from 0, before exactly three."""
    point = np.char.find(b, ".")
    signed = (np.char.startswith(b, "-") | np.char.startswith(b, "+")).astype(int)
    before = point - signed
    exponent = (np.char.find(b, "e") >= 0) | (np.char.find(b, "E") >= 0)
    zero = np.char.startswith(np.char.lstrip(b, "+-"), "0")
    return (np.char.str_len(b) - point - 1 == 3) & (before >= 1) & (before <= 3) & ~exponent & ~zero


def _grouped(f: np.ndarray, count: dict, thousands: str | None, status, value, at: np.ndarray) -> None:
    """Fields ``f`` (at ``at`` of ``status``, ``value``) with two or more separators, or a ``'`` or
    blank: digits grouped by threes with one thousands separator ``t``, then an optional decimal
    mark ``d`` and fraction; anything else is not a number."""
    blanks = sum((count[c] > 0).astype(int) for c in _BLANKS)
    t, d = np.full(f.size, "", dtype="<U1"), np.full(f.size, "", dtype="<U1")
    for c in _BLANKS:
        t[count[c] > 0] = c
    points, commas = count["."], count[","]
    one_blank = blanks == 1
    d[one_blank & (points == 1) & (commas == 0)] = "."
    d[one_blank & (commas == 1) & (points == 0)] = ","
    ok = one_blank & (points + commas <= 1)
    none = blanks == 0
    first_p, first_c = np.char.find(f, "."), np.char.find(f, ",")
    last_p, last_c = np.char.rfind(f, "."), np.char.rfind(f, ",")
    for sep, mark, seps, marks, last_sep, first_mark in ((".", ",", points, commas, last_p, first_c),
                                                       (",", ".", commas, points, last_c, first_p)):
        alone = none & (seps >= 1) & (marks == 0)
        before = none & (seps >= 1) & (marks == 1) & (last_sep < first_mark)
        t[alone | before], d[before] = sep, mark
        ok |= alone | before
    signed = (np.char.startswith(f, "+") | np.char.startswith(f, "-")).astype(np.int64)
    exponent = np.maximum(np.char.find(f, "e"), np.char.find(f, "E"))
    end = np.where(d != "", np.char.find(f, np.where(d != "", d, ".")),
                   np.where(exponent >= 0, exponent, np.char.str_len(f)))
    groups = np.where(ok, np.char.count(f, np.where(ok, t, ".")), 0)
    lead = end - signed - 4 * groups  # digits before the first separator
    ok &= (lead >= 1) & (lead <= 3) & ~np.char.startswith(f, "0", signed) & (exponent < 0)
    ok &= np.char.rfind(f, np.where(ok, t, ".")) < end
    pos = np.full(f.size, -1, dtype=np.int64)
    for m in range(int(groups[ok].max()) if ok.any() else 0):
        live = ok & (groups > m)
        nxt = np.char.find(f, np.where(live, t, "."), pos + 1)
        ok &= ~live | (nxt == signed + lead + 4 * m)
        pos = np.where(live, nxt, pos)
    v, parsed = _floats(np.char.replace(np.char.replace(f, np.where(ok, t, "."), np.where(ok, "", ".")), ",", "."))
    ok &= parsed
    code = np.where(d == ".", POINT, np.where(d == ",", COMMA, np.where(t == ",", POINT, np.where(t == ".", COMMA,
                                                                                                   PLAIN))))
    if thousands is not None:
        code = np.where(np.isin(t, list(thousands)), code, GROUPING)
    status[at] = np.where(ok, code, BAD)
    value[at] = np.where(ok & (code != GROUPING), v, np.nan)


def classify(fields, thousands: str | None = None):
    """Status (``PLAIN``, ``POINT``, ``COMMA``, ``AMB_POINT``, ``AMB_COMMA``; ``EMPTY``, ``BAD``,
    ``GROUPING``: grouped by a separator other than ``thousands``) and value of each stripped
    field of ``fields`` (a sequence or array of str); an ambiguous field's value reads its
    separator as the decimal mark.

    Memory and time follow the fields' own length: a field longer than :data:`LONGEST`
    characters, or longer than :data:`WIDE` and holding other than the characters of a number (a
    note), is not a number at once; the others are classified in fixed-width arrays of fields of about one
    length, at most :data:`CHUNK` fields and :data:`CHUNK_CHARS` characters of width times fields
    each."""
    fields = fields.ravel().tolist() if isinstance(fields, np.ndarray) else list(fields)
    status, value = np.zeros(len(fields), dtype=np.int8), np.full(len(fields), np.nan)
    lengths = np.fromiter(map(len, fields), np.int64, len(fields))
    for i in np.flatnonzero(lengths > WIDE).tolist():
        if lengths[i] > LONGEST or not _NUMBER_CHARS.fullmatch(fields[i]):
            status[i], lengths[i] = BAD, -1
    order = np.argsort(lengths, kind="stable")
    order = order[lengths[order] >= 0]
    start = 0
    while start < order.size:
        stop = min(start + CHUNK, order.size)
        while stop - start > 1 and (stop - start) * lengths[order[stop - 1]] > CHUNK_CHARS:
            stop = start + (stop - start) // 2
        at = order[start:stop]
        status[at], value[at] = _classified(np.array([fields[i] for i in at.tolist()], dtype=str), thousands)
        start = stop
    return status, value


def _classified(a: np.ndarray, thousands: str | None):
    """:func:`classify` of the fixed-width array ``a``."""
    status, value = np.zeros(a.size, dtype=np.int8), np.full(a.size, np.nan)
    count = {c: np.char.count(a, c) for c in ".,'_" + SPACES}
    others = count["'"] + sum(count[c] for c in SPACES)
    seps = count["."] + count[","] + others
    status[np.char.str_len(a) == 0] = EMPTY
    status[count["_"] > 0] = BAD
    plain = np.flatnonzero((seps == 0) & (status == PLAIN))
    if plain.size:
        value[plain], ok = _floats(a[plain])
        status[plain[~ok]] = BAD
    one = np.flatnonzero((seps == 1) & (others == 0) & (status == PLAIN))
    if one.size:
        b = np.char.replace(a[one], ",", ".")
        value[one], ok = _floats(b)
        comma = count[","][one] == 1
        amb = ok & _ambiguous(b)
        status[one] = np.where(~ok, BAD, np.where(amb, np.where(comma, AMB_COMMA, AMB_POINT),
                                                   np.where(comma, COMMA, POINT)))
    rest = np.flatnonzero(((seps > 1) | (others > 0)) & (status == PLAIN))
    if rest.size:
        _grouped(a[rest], {c: n[rest] for c, n in count.items()}, thousands, status, value, rest)
    return status, value


def _shown(text: str) -> str:
    """``text`` for a message: a field longer than :data:`WIDE` cut, with its length."""
    return text if len(text) <= WIDE else f"{text[:WIDE]}... ({len(text)} characters)"


def _first(mask: np.ndarray):
    """(row, column) of the first True of ``mask`` (rows, columns), column by column; (None, None)."""
    cols = np.flatnonzero(mask.any(axis=0))
    if not cols.size:
        return None, None
    j = int(cols[0])
    return int(np.argmax(mask[:, j])), j


class NumberFormat:
    """The decimal mark and thousands separator of one file: given, or decided by its fields.

    Parameters
    ----------
    path : str or os.PathLike
        The file (for messages).
    decimal : {".", ","}, optional
        The decimal mark; default: decided by the fields.
    thousands : {"none", ",", ".", "'", "space"}, optional
        The one thousands separator; default: any, where the grouping says so.
    """

    def __init__(self, path, decimal: str | None = None, thousands: str | None = None):
        self.path = str(path)
        if decimal is not None and decimal not in DECIMALS:
            raise MeasuredDataError(f"decimal mark {decimal!r} for {self.path!r} is not '.' or ','; give one of them "
                                    "(--decimal, decimal=)")
        if thousands is not None and thousands not in THOUSANDS:
            raise MeasuredDataError(f"thousands separator {thousands!r} for {self.path!r} is not one of "
                                    f"{', '.join(THOUSANDS)}; give one of them (--thousands, thousands=)")
        if decimal is not None and thousands is not None and decimal == thousands:
            raise MeasuredDataError(f"decimal mark and thousands separator for {self.path!r} are both {decimal!r}; "
                                    "give two different ones (--decimal, --thousands)")
        self.given = (decimal, thousands)
        self.thousands = None if thousands is None else THOUSANDS[thousands]
        self.decimal = decimal if decimal is not None else _OTHER.get(self.thousands or "")
        self.seen: dict[str, tuple] = {}  # decimal mark -> (column, line, field) that first decided it

    @property
    def mark(self) -> str | None:
        """The decimal mark, given or decided by the fields read so far; None: not yet known."""
        if self.decimal is not None:
            return self.decimal
        return next(iter(self.seen)) if len(self.seen) == 1 else None

    def _given(self) -> str:
        d, t = self.given
        parts = ([f"decimal mark {d!r}"] if d else []) + ([f"thousands separator {t!r}"] if t else [])
        return " and ".join(parts)

    def _note(self, mark: str, name: str, line: int, text: str) -> None:
        other = self.seen.get(_OTHER[mark])
        if other is not None:
            where = "it" if other[0] == name else f"column {other[0]!r}"
            raise MeasuredDataError(
                f"column {name!r} of {self.path!r} writes {_shown(text)!r} at line {line} (decimal {_NAME[mark]}) but "
                f"{where} writes {other[2]!r} at line {other[1]} (decimal {_NAME[_OTHER[mark]]}); fix: export the file "
                "with one decimal mark")
        self.seen.setdefault(mark, (name, line, _shown(text)))

    def _settle(self, status: np.ndarray, value: np.ndarray) -> None:
        """Read the ambiguous fields as the given separators or the known decimal mark say."""
        for code, sep in _AMBIGUOUS.items():
            if self.thousands is not None:
                grouping = sep in self.thousands
            elif self.mark is not None:
                grouping = sep != self.mark
            else:
                continue
            hit = status == code
            if grouping:
                value[hit] = np.round(value[hit] * 1000.0)  # 21.988 -> 21988, exactly
            status[hit] = _DECIDE[_OTHER[sep] if grouping else sep]

    def read(self, fields: np.ndarray, names: list[str], line_of: Callable[[int], int]):
        """A block of rows of the columns read (``fields`` shape (rows, columns), str or object
        holding str, stripped, in file order) as floats.

        Returns
        -------
        values : numpy.ndarray, shape of ``fields``
            The numbers; an ambiguous field still undecided reads its separator as the decimal mark.
        ambiguous : numpy.ndarray of int8 or None
            ``AMB_POINT``/``AMB_COMMA`` where a field is still ambiguous (for :meth:`settle`), else 0.

        Raises
        ------
        MeasuredDataError
            A field that is empty, not a number (with the given separators), not finite, or with
            a decimal mark other than the one of the fields read before (naming column and line).
        """
        status, value = classify(fields.ravel(), self.thousands)
        status, value = status.reshape(fields.shape), value.reshape(fields.shape)
        self._settle(status, value)
        if self.decimal is not None:
            status[status == _DECIDE[_OTHER[self.decimal]]] = GROUPING
        i, j = _first(status < 0)
        if i is not None:
            text, line, name = _shown(str(fields[i, j])), line_of(i), names[j]
            if status[i, j] == EMPTY:
                raise MeasuredDataError(f"column {name!r} is empty at line {line} of {self.path!r}; fix: fill the gap "
                                        "or leave the column out")
            if status[i, j] == GROUPING:
                raise MeasuredDataError(f"column {name!r} is not a number with the {self._given()} given at line "
                                        f"{line} ({text!r}) of {self.path!r}; fix: give the separators the file uses "
                                        "(--decimal, --thousands) or leave the column out")
            raise MeasuredDataError(f"column {name!r} is not numeric at line {line} ({text!r}) of {self.path!r}; fix: "
                                    "give numbers only, or leave the column out")
        for code, mark in _MARK.items():
            i, j = _first(status == code)
            if i is not None:
                self._note(mark, names[j], line_of(i), str(fields[i, j]))
        self._settle(status, value)
        i, j = _first(~np.isfinite(value))
        if i is not None:
            raise self.missing(names[j], str(fields[i, j]), line_of(i))
        amb = (status == AMB_POINT) | (status == AMB_COMMA)
        return value, (np.where(amb, status, 0).astype(np.int8) if amb.any() else None)

    def missing(self, name: str, text: str, line: int) -> MeasuredDataError:
        """The refusal of a NaN or infinite sample."""
        return MeasuredDataError(f"column {name!r} has {_shown(text)!r} at line {line} of {self.path!r}; fix: remove "
                                 "or interpolate the missing samples")

    def settle(self, values: np.ndarray, ambiguous: np.ndarray, name: str, first: tuple[int, str]) -> None:
        """Read a column's ambiguous fields (``ambiguous`` from :meth:`read`) with the file's
        decimal mark, in place; refuse when nothing decided it (``first``: line and field of the first)."""
        mark = self.mark
        if mark is None:
            line, text = first
            v = float(text.replace(",", "."))
            raise MeasuredDataError(
                f"column {name!r} of {self.path!r} writes {text!r} at line {line}, which reads {v:.10g} with a decimal "
                f"{_NAME[text.strip('+-0123456789')]} or {round(v * 1000):d} with a thousands separator, and no field "
                "of the columns read decides; fix: name the decimal mark (--decimal . or --decimal ,; decimal=) or "
                "the thousands separator (--thousands; thousands=)")
        grouped = ambiguous == (AMB_COMMA if mark == "." else AMB_POINT)
        values[grouped] = np.round(values[grouped] * 1000.0)
