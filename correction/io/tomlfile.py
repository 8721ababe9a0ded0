"""Strict reading of the project's TOML files: one helper for scenario files, sweep grids, actuator files.

Every user file the project reads is TOML, and every reader wants the same three things: the file
parsed or refused in one sentence that names it, no key it does not know (a typo must not be
ignored silently), and numbers that are numbers, finite and in range. This module does them
once, for any layer: it lives in :mod:`correction`, the lowest layer that reads user files, and
imports nothing of the project but :mod:`rigsim.correction.io.atomic` (how a file is opened, read and
written), so the correction toolkit works on its own and the scenarios can build on it.

* :func:`path_text`: a path given as ``str``, ``bytes`` or ``os.PathLike`` as text, or one
  sentence naming what it should have been;
* :func:`read_toml`: path -> dict, or one sentence: missing file, a directory, a named pipe or
  a device, a file over 16 MiB, unreadable or not UTF-8 (a UTF-8 byte-order mark is read, a
  UTF-16 or UTF-32 one named), invalid TOML (with tomllib's line and column);
* :func:`check_keys`: refuse an unknown key, naming the closest valid one
  (``difflib.get_close_matches``, cutoff 0.5) or else listing the valid keys;
* :func:`number`: a TOML value as a finite float within optional bounds;
* :func:`toml_text` and :func:`write_toml`: a document of tables, numbers, strings, booleans and
  arrays written as TOML (atomically: a temporary file in the same folder, then a rename), for
  the files the project writes for itself to read back (actuator files).

Each takes the exception class to raise (``error``, default ``ValueError``), so a reader raises
its own (``ScenarioError``, ``ActuatorFileError``...). Messages are single lines; paths and
values appear as ``repr`` so that a newline in them cannot break the line.
"""

from __future__ import annotations

import difflib
import math
import os
import pathlib
import re
import tomllib
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

__all__ = ["MAX_TOML_BYTES", "path_text", "read_toml", "check_keys", "number", "toml_text", "write_toml"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
#: The largest TOML file read, bytes: the project's files (scenarios, grids, actuator files) are
#: a few KiB; a file this large is the wrong file.
MAX_TOML_BYTES = 16 * 2**20
#: Byte-order marks of the encodings a text editor may save a file in instead of UTF-8, longest first
#: (UTF-32's little-endian mark begins with UTF-16's).
_FOREIGN_BOMS = ((b"\xff\xfe\x00\x00", "UTF-32"), (b"\x00\x00\xfe\xff", "UTF-32"), (b"\xff\xfe", "UTF-16"),
                 (b"\xfe\xff", "UTF-16"))


def path_text(path, what: str, error: type[Exception] = ValueError) -> str:
    """A path given as ``str``, ``bytes`` (the file system's encoding) or ``os.PathLike``, as text.

    Parameters
    ----------
    path : str, bytes or os.PathLike
        The path as the caller gave it.
    what : str
        What the path names, for the message: a keyword (``"record"``) or ``"actuator file"``.
    error : type of Exception
        The class raised.

    Returns
    -------
    str
        ``os.fsdecode(path)``.

    Raises
    ------
    error
        ``"{what} must name a file (a str, bytes or os.PathLike path), got NoneType"``, or an empty path.
    """
    try:
        text = os.fsdecode(path)
    except TypeError:
        raise error(f"{what} must name a file (a str, bytes or os.PathLike path), got {type(path).__name__}") from None
    if not text:
        raise error(f"{what} '' names no file; give the file's path")
    return text


def read_toml(path: str | os.PathLike, what: str, error: type[Exception] = ValueError, *,
              max_bytes: int = MAX_TOML_BYTES) -> dict:
    """Read and parse a TOML file (UTF-8), refusing any problem in one sentence.

    The file must be a regular file of at most ``max_bytes``: a named pipe, a device (``/dev/zero``)
    or a socket is refused without waiting on it (:func:`rigsim.correction.io.atomic.open_regular`), a file
    larger than any TOML file the project reads without reading it.

    Parameters
    ----------
    path : str, bytes or os.PathLike
        The file.
    what : str
        What the file is, for the messages, e.g. ``"scenario file"``, ``"grid file"``,
        ``"actuator file"``.
    error : type of Exception
        The class raised (called with the message as its only argument).
    max_bytes : int
        The largest file read, bytes (:data:`MAX_TOML_BYTES`).

    Returns
    -------
    dict
        The parsed document (``tomllib.loads``; line ends ``\\r\\n`` and ``\\r`` read as ``\\n``, a
        leading UTF-8 byte-order mark skipped).

    Raises
    ------
    error
        ``"{what} 'PATH' does not exist"``; ``"{what} 'PATH' is a directory, not a TOML file"``;
        ``"{what} 'PATH' is a named pipe (FIFO), not a TOML file; ..."`` (a device, a socket alike);
        ``"{what} 'PATH' is 20 MiB, more than the 16 MiB a TOML file may have; ..."``;
        ``"cannot read {what} 'PATH': <reason>"`` (permissions, not UTF-8, ...);
        ``"{what} 'PATH' is UTF-16 (its byte-order mark says so), not UTF-8; ..."``;
        ``"{what} 'PATH' is not valid TOML: <tomllib's message with line and column>"``.
    """
    from rigsim.correction.io.atomic import read_regular, size_text

    p = pathlib.Path(path_text(path, what, error))
    name = repr(str(p))
    raw = read_regular(p, what, max_bytes=max_bytes, error=error, expected="a TOML file",
                       too_large=f", more than the {size_text(max_bytes)} a TOML file may have; check the path")
    for bom, encoding in _FOREIGN_BOMS:
        if raw.startswith(bom):
            raise error(f"{what} {name} is {encoding} (its byte-order mark says so), not UTF-8; save it as UTF-8")
    try:
        text = raw.decode("utf-8-sig").replace("\r\n", "\n").replace("\r", "\n")
    except UnicodeDecodeError as exc:
        raise error(f"cannot read {what} {name}: {_one_line(exc)}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{what} {name} is not valid TOML: {_one_line(exc)}") from None
    except ValueError:  # tomllib passes on int()'s limit of 4300 decimal digits
        raise error(f"{what} {name} is not valid TOML: an integer has thousands of digits "
                    "(TOML integers are 64-bit)") from None
    except RecursionError:  # arrays or inline tables nested thousands deep
        raise error(f"{what} {name} is not valid TOML: its arrays or inline tables are nested too "
                    "deeply to parse") from None


def check_keys(table: Mapping, valid: Iterable[str], where: str, error: type[Exception] = ValueError) -> None:
    """Refuse the first key of ``table`` that is not in ``valid``.

    Parameters
    ----------
    table : Mapping
        A parsed TOML table.
    valid : iterable of str
        The keys it may have (a mapping's keys count).
    where : str
        Prefix of the key in the message, dot included: ``""`` at the top level of a file,
        ``"road."`` for the table ``[road]``.
    error : type of Exception
        The class raised.

    Raises
    ------
    error
        ``"unknown key {where}{key}; did you mean 'x'?"`` with the closest valid key
        (``difflib.get_close_matches``, cutoff 0.5), or, when none is close,
        ``"unknown key {where}{key}; valid keys are a, b, c"`` (sorted). A key that is not a
        bare TOML key (letters, digits, ``_``, ``-``) is shown quoted, as ``repr``.
    """
    valid = [str(k) for k in valid]
    for key in table:
        if key not in valid:
            shown = key if isinstance(key, str) and _BARE_KEY.fullmatch(key) else repr(key)
            raise error(f"unknown key {where}{shown}{_closest(str(key), valid)}")


def number(where: str, value: Any, *, lo: float | None = None, hi: float | None = None, lo_open: bool = False,
           error: type[Exception] = ValueError) -> float:
    """A TOML value as a finite float, within ``[lo, hi]`` (or ``(lo, hi]`` with ``lo_open``).

    Parameters
    ----------
    where : str
        The key's full name for the message, e.g. ``"road.waviness"``.
    value : object
        The parsed value. An int or a float; a bool is refused (TOML ``true`` is not 1).
    lo, hi : float, optional
        Bounds, in the unit of the key (inclusive unless ``lo_open``).
    lo_open : bool
        Refuse ``value == lo`` too.
    error : type of Exception
        The class raised.

    Returns
    -------
    float
        The value, in the unit of the key.

    Raises
    ------
    error
        ``"{where} must be a number, got ..."``, ``"{where} must be finite, got ..."``,
        ``"{where} must be >= lo, got ..."`` (``>`` with ``lo_open``), ``"{where} must be <= hi, got ..."``.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise error(f"{where} must be a number, got {_show(value)}")
    try:
        v = float(value)
    except OverflowError:  # an int beyond the float range (tomllib reads any size of integer)
        raise error(f"{where} must be finite, got an integer of {value.bit_length()} bits") from None
    if not math.isfinite(v):
        raise error(f"{where} must be finite, got {value!r}")
    if lo is not None and (v < lo or (lo_open and v == lo)):
        raise error(f"{where} must be {'>' if lo_open else '>='} {lo:g}, got {value!r}")
    if hi is not None and v > hi:
        raise error(f"{where} must be <= {hi:g}, got {value!r}")
    return v


def _closest(key: str, valid: list[str]) -> str:
    match = difflib.get_close_matches(key, valid, n=1, cutoff=0.5)
    if match:
        return f"; did you mean {match[0]!r}?"
    return f"; valid keys are {', '.join(sorted(valid))}"


def _show(value: Any) -> str:
    try:
        return repr(value)
    except ValueError:  # holds an int of more than 4300 decimal digits
        return f"a {type(value).__name__} too large to print"


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())


def _key(key) -> str:
    key = str(key)
    return key if _BARE_KEY.fullmatch(key) else _string(key)


def _string(text: str) -> str:
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _value(value, where: str) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, Mapping):
        return "{ " + ", ".join(f"{_key(k)} = {_value(v, f'{where}.{k}')}" for k, v in value.items()) + " }"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_value(v, where) for v in value) + "]"
    raise TypeError(f"{where}: cannot write a {type(value).__name__} to TOML")


def toml_text(doc: Mapping) -> str:
    """A document as TOML text: mappings become tables (``[a]``, ``[a.b]``), the rest key = value.

    Parameters
    ----------
    doc : Mapping
        Nested mappings of str keys; values: bool, int, float (NaN and infinities as TOML's
        ``nan``, ``inf``), str, sequences or numpy arrays of those, or mappings inside a
        sequence (inline tables).

    Returns
    -------
    str
        UTF-8 TOML that :func:`read_toml` (``tomllib``) reads back to the same values.
    """
    lines: list[str] = []

    def table(mapping: Mapping, prefix: tuple[str, ...]) -> None:
        subs = [(k, v) for k, v in mapping.items() if isinstance(v, Mapping)]
        plain = [(k, v) for k, v in mapping.items() if not isinstance(v, Mapping)]
        if prefix and (plain or not subs):
            lines.append(("\n" if lines else "") + "[" + ".".join(prefix) + "]")
        for k, v in plain:
            lines.append(f"{_key(k)} = {_value(v, '.'.join(prefix + (str(k),)))}")
        for k, v in subs:
            table(v, prefix + (_key(k),))

    table(doc, ())
    return "\n".join(lines) + "\n"


def write_toml(path: str | os.PathLike, doc: Mapping) -> None:
    """Write ``doc`` (see :func:`toml_text`) to ``path`` atomically: a temporary file, then a rename."""
    from rigsim.correction.io.atomic import atomic_write_text

    atomic_write_text(path, toml_text(doc))
