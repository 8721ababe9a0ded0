"""rigsim.correction.io.tomlfile: strict reading of TOML files, one-line errors raised as the caller's class.

Expected messages are the ones the project's readers (scenario files, sweep grids, actuator
files) give, written out here. The property test feeds a few hundred random byte strings
(seeded) through the reader: whatever the bytes, the answer is a dict or the given error.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigsim.correction.io.tomlfile import check_keys, number, read_toml


class FileProblem(Exception):
    """Not a ValueError: shows that the class passed in is the one raised."""


def _one_line(exc: BaseException) -> str:
    msg = str(exc)
    assert msg and "\n" not in msg and "\r" not in msg, f"not one line: {msg!r}"
    return msg


# ------------------------------------------------------------------ read_toml

def test_reads_a_valid_file(tmp_path):
    p = tmp_path / "ok.toml"
    p.write_text('speed_kmh = 72.0\n[road]\nroughness = "medium"\n', encoding="utf-8")
    assert read_toml(p, "scenario file") == {"speed_kmh": 72.0, "road": {"roughness": "medium"}}
    assert read_toml(str(p), "scenario file") == read_toml(p, "scenario file")


def test_a_missing_file_is_named(tmp_path):
    p = tmp_path / "missing.toml"
    with pytest.raises(FileProblem) as err:
        read_toml(p, "grid file", FileProblem)
    assert _one_line(err.value) == f"grid file {str(p)!r} does not exist"


def test_a_directory_is_not_a_toml_file(tmp_path):
    with pytest.raises(FileProblem) as err:
        read_toml(tmp_path, "scenario file", FileProblem)
    assert _one_line(err.value) == f"scenario file {str(tmp_path)!r} is a directory, not a TOML file"


def test_a_file_that_is_not_utf8_cannot_be_read(tmp_path):
    p = tmp_path / "latin1.toml"
    p.write_bytes('name = "Stra\u00dfe"\n'.encode("latin-1"))
    with pytest.raises(FileProblem) as err:
        read_toml(p, "actuator file", FileProblem)
    msg = _one_line(err.value)
    assert msg.startswith(f"cannot read actuator file {str(p)!r}: ")
    assert "utf-8" in msg


def _refuse_reading(monkeypatch):
    """Make every open fail as an unreadable file does (root reads files whatever their mode)."""
    import os

    def refuse(path, *args, **kwargs):
        raise PermissionError(13, "Permission denied", os.fspath(path))
    monkeypatch.setattr(os, "open", refuse)


def test_an_unreadable_file_says_why(tmp_path, monkeypatch):
    p = tmp_path / "locked.toml"
    p.write_text("a = 1\n", encoding="utf-8")
    _refuse_reading(monkeypatch)
    with pytest.raises(FileProblem) as err:
        read_toml(p, "grid file", FileProblem)
    msg = _one_line(err.value)
    assert msg.startswith(f"cannot read grid file {str(p)!r}: ") and "Permission denied" in msg


def test_a_directory_reported_as_permission_denied_is_still_a_directory(tmp_path, monkeypatch):
    _refuse_reading(monkeypatch)  # what Windows does for a directory
    with pytest.raises(FileProblem) as err:
        read_toml(tmp_path, "grid file", FileProblem)
    assert _one_line(err.value) == f"grid file {str(tmp_path)!r} is a directory, not a TOML file"


def test_invalid_toml_gives_tomllibs_line_and_column(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("a = 1\nb = \n", encoding="utf-8")
    with pytest.raises(FileProblem) as err:
        read_toml(p, "scenario file", FileProblem)
    msg = _one_line(err.value)
    assert msg.startswith(f"scenario file {str(p)!r} is not valid TOML: ")
    assert "(at line 2, column 5)" in msg


@pytest.mark.parametrize("text", [
    "a = " + "1" * 5000 + "\n",  # beyond int()'s 4300 digits
    "a = " + "[" * 5000 + "]" * 5000 + "\n",  # beyond the recursion limit
])
def test_pathological_toml_is_refused_as_invalid(tmp_path, text):
    p = tmp_path / "deep.toml"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(FileProblem) as err:
        read_toml(p, "grid file", FileProblem)
    assert _one_line(err.value).startswith(f"grid file {str(p)!r} is not valid TOML: ")


def test_a_path_with_a_newline_still_gives_one_line(tmp_path):
    p = tmp_path / "two\nlines.toml"
    with pytest.raises(ValueError) as err:  # the default class
        read_toml(p, "scenario file")
    assert _one_line(err.value).endswith("does not exist")


# ------------------------------------------------------------------ check_keys

def test_check_keys_accepts_known_keys():
    check_keys({"seed": 7, "road": {}}, {"seed": "", "road": "", "name": ""}, "")  # a mapping's keys count


def test_unknown_key_names_the_closest_valid_one():
    with pytest.raises(FileProblem) as err:
        check_keys({"payload_kg": 1.0, "paylod_kg": 3640.0}, ["payload_kg", "mass_kg"], "vehicle.", FileProblem)
    assert _one_line(err.value) == "unknown key vehicle.paylod_kg; did you mean 'payload_kg'?"


def test_unknown_key_without_a_close_one_lists_the_valid_keys():
    with pytest.raises(ValueError) as err:
        check_keys({"zzz": 1}, ("den", "num"), "")
    assert _one_line(err.value) == "unknown key zzz; valid keys are den, num"


def test_an_unknown_quoted_key_is_shown_quoted_on_one_line():
    with pytest.raises(FileProblem) as err:
        check_keys({"a\nb": 1}, ["ab"], "road.", FileProblem)
    assert _one_line(err.value) == "unknown key road.'a\\nb'; did you mean 'ab'?"


# ------------------------------------------------------------------ number

def test_number_returns_a_float():
    assert number("seed", 7) == 7.0 and isinstance(number("seed", 7), float)
    assert number("road.waviness", 2.0, lo=0.5, hi=5.0) == 2.0
    assert number("lead_in_s", 0.5, lo=0.5) == 0.5  # a closed bound admits itself


@pytest.mark.parametrize("value, kw, message", [
    (True, {}, "speed_kmh must be a number, got True"),
    ("fast", {}, "speed_kmh must be a number, got 'fast'"),
    ([1.0], {}, "speed_kmh must be a number, got [1.0]"),
    (math.nan, {}, "speed_kmh must be finite, got nan"),
    (-math.inf, {}, "speed_kmh must be finite, got -inf"),
    (0.0, {"lo": 0, "lo_open": True}, "speed_kmh must be > 0, got 0.0"),
    (0.4, {"lo": 0.5}, "speed_kmh must be >= 0.5, got 0.4"),
    (250, {"lo": 0, "hi": 200}, "speed_kmh must be <= 200, got 250"),
    (1 << 2000, {}, "speed_kmh must be finite, got an integer of 2001 bits"),
])
def test_number_refuses_in_one_line_naming_the_key(value, kw, message):
    with pytest.raises(FileProblem) as err:
        number("speed_kmh", value, error=FileProblem, **kw)
    assert _one_line(err.value) == message


# ------------------------------------------------------------------ property: random bytes

TOKENS = [b"a", b"b", b"key", b"=", b" = ", b" ", b"\n", b"\r\n", b"\t", b"[", b"]", b"[[", b"]]", b"{", b"}",
          b",", b".", b'"', b"'", b'"""', b"#", b"\\", b"1", b"-2", b"3.5", b"1e999", b"0x1F", b"nan", b"inf",
          b"true", b"1979-05-27", b"07:32:00", b"_", b"+", b"\xc3\xa9", b"\xff", b"\x00"]


VALUES = [b"1", b"-2", b"3.5", b"1e999", b"nan", b"-inf", b"0x" + b"f" * 600, b"true", b'"s"', b"[1, 2.5]",
          b"{ x = 1 }", b"1979-05-27"]


def _walk(doc, prefix=""):
    """Every (key, value) of a parsed document, tables included, with dotted names."""
    for key, value in doc.items():
        yield f"{prefix}{key}", value
        if isinstance(value, dict):
            yield from _walk(value, f"{prefix}{key}.")


def test_random_bytes_give_a_dict_or_the_given_error(tmp_path):
    rng = np.random.default_rng(20240611)
    outcomes = {"dict": 0, "error": 0}
    p = tmp_path / "random.toml"
    for i in range(400):
        if i % 3 == 0:  # any bytes: mostly not UTF-8
            data = rng.integers(0, 256, size=int(rng.integers(0, 120)), dtype=np.uint8).tobytes()
        elif i % 3 == 1:  # TOML-like tokens: reach the parser, rarely parse
            data = b"".join(TOKENS[k] for k in rng.integers(0, len(TOKENS), size=int(rng.integers(0, 30))))
        else:  # lines "key = value", one byte in three files overwritten at random
            data = b"".join(TOKENS[rng.integers(0, 3)] + b" = " + VALUES[rng.integers(0, len(VALUES))] + b"\n"
                            for _ in range(int(rng.integers(0, 4))))
            if data and rng.random() < 1 / 3:
                buf = bytearray(data)
                buf[int(rng.integers(0, len(buf)))] = int(rng.integers(0, 256))
                data = bytes(buf)
        p.write_bytes(data)
        try:
            doc = read_toml(p, "grid file", FileProblem)
        except FileProblem as exc:
            assert str(p) in _one_line(exc) or repr(str(p)) in str(exc)
            outcomes["error"] += 1
            continue
        assert isinstance(doc, dict)
        outcomes["dict"] += 1
        for where, value in _walk(doc):  # the two other helpers on whatever was parsed
            for call in (lambda: number(where, value, lo=0, hi=1e3, error=FileProblem),
                         lambda: check_keys(value if isinstance(value, dict) else {where: value}, ["a"], "x.",
                                            FileProblem)):
                try:
                    call()
                except FileProblem as exc:
                    _one_line(exc)
    assert outcomes["dict"] >= 60 and outcomes["error"] >= 200, outcomes
