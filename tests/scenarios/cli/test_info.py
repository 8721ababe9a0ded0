"""``rigsim info FILE`` (scenarios/cli/info.py): on a file of each format the readers take, written
here by the project's own writers (``write_channels``, ``write_rpc3``), the channels (name, unit as
written, SI unit), the rate, the number of samples, the duration and the dialect printed are those
of the file written; a file the reader refuses is one sentence on stderr and exit code 2."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from rigsim.correction.io.measured import READ_FORMATS, write_channels
from rigsim.correction.io.rpc3 import write_rpc3
from rigsim.scenarios.cli.main import main

#: The record written: 600 samples at 200 Hz, so 3 s; a force labelled kN, a length mm.
RATE_HZ, N = 200.0, 600
UNITS = {"Fz_FL": "kN", "Weg_FL": "mm"}


def _record():
    t = np.arange(N) / RATE_HZ
    return SimpleNamespace(time_s=t, data={"Fz_FL": 20.0 + np.sin(2 * np.pi * t), "Weg_FL": 5.0 * np.cos(t)},
                           units=UNITS, metadata={"rig": "dyntrac"})


def _info(capsys, *argv) -> tuple[int, str, str]:
    code = main(["info", *map(str, argv)])
    out, err = capsys.readouterr()
    return code, out, err


def _field(text: str, key: str) -> str:
    return next(line[len(key):].strip() for line in text.splitlines() if line.startswith(key + " "))


def _dialect(text: str) -> str:
    """The dialect printed, its wrapped lines joined."""
    return " ".join(text.split("\ndialect ", 1)[1].split("\ntime ", 1)[0].split())


def _check_common(text: str) -> None:
    assert _field(text, "rate") == "200 Hz"
    assert _field(text, "samples") == "600"
    assert _field(text, "duration") == "3 s"
    assert _field(text, "channels") == "2"
    rows = [line.split() for line in text.split("\nchannels ", 1)[1].splitlines()[1:]]
    assert rows == [["name", "unit", "in", "file", "SI", "unit"], ["Fz_FL", "kN", "N"], ["Weg_FL", "mm", "m"]]


def _lab_extra(ext: str) -> None:
    if ext in (".mf4", ".mdf"):
        pytest.importorskip("asammdf")
    if ext == ".tdms":
        pytest.importorskip("nptdms")


@pytest.mark.parametrize("ext", sorted(READ_FORMATS))
def test_every_format_the_readers_take(tmp_path, capsys, ext):
    _lab_extra(ext)
    path = write_channels(tmp_path / f"rec{ext}", _record())
    code, out, err = _info(capsys, path)
    assert (code, err) == (0, "")
    _check_common(out)
    fmt = READ_FORMATS[ext]
    assert _field(out, "format").startswith({"csv": "CSV", "rpc3": "RPC III", "mdf4": "MDF4", "tdms": "TDMS"}[fmt])
    dialect = _dialect(out)
    expected = {"csv": "delimiter ',', decimal mark '.', thousands separator not given, header on line 2, "
                       "units row no, encoding utf-8",  # line 1: the writer's '# rig: dyntrac'
                "rpc3": "byte order little-endian, data type SHORT_INTEGER",
                "mdf4": "version 4.10",
                "tdms": "time from a time channel"}[fmt]
    assert dialect == expected


def test_rpc3_written_by_its_writer_with_a_start_time(tmp_path, capsys):
    t = np.arange(N) / RATE_HZ
    path = tmp_path / "drive.rsp"
    write_rpc3(path, ["Fz_FL", "Weg_FL"], ["kN", "mm"], np.vstack([np.sin(t), np.cos(t)]), 1.0 / RATE_HZ,
               start_s=12.5)
    code, out, _ = _info(capsys, path)
    assert code == 0
    _check_common(out)
    assert _field(out, "time") == "'time', first sample at 12.5 s"


def test_a_text_dialect_is_reported_as_read(tmp_path, capsys):
    """Semicolons, decimal commas, a preamble and a units row below the header, Windows-1252."""
    path = tmp_path / "messung.txt"
    rows = "".join(f"{i / RATE_HZ:.3f};{20 + i % 7},5;{i % 5},25\n".replace(".", ",") for i in range(N))
    path.write_bytes(("# Prüfstand: DYNTRAC\n# Datum: 2024-05-01\nZeit;Fz_FL;Weg_FL\ns;kN;mm\n" + rows).encode("cp1252"))
    code, out, _ = _info(capsys, path)
    assert code == 0
    _check_common(out)
    assert _field(out, "time") == "'Zeit'"
    assert _dialect(out) == (
        "delimiter ';', decimal mark ',', thousands separator not given, header on line 3, units row yes, "
        "encoding cp1252")


def test_the_number_format_options_reach_the_reader(tmp_path, capsys):
    """A file only ``--decimal`` makes readable (every field ambiguous) is read with it."""
    path = tmp_path / "amb.csv"
    path.write_text("time;F [N]\n" + "".join(f"{i};1,500\n" for i in range(4)))
    code, _, err = _info(capsys, path)
    assert code == 2 and "--decimal" in err
    code, out, _ = _info(capsys, path, "--decimal", ",")
    assert code == 0 and "decimal mark ','" in out and _field(out, "rate") == "1 Hz"


def test_json(tmp_path, capsys):
    path = write_channels(tmp_path / "rec.csv", _record())
    code, out, _ = _info(capsys, path, "--json")
    assert code == 0
    info = json.loads(out)
    assert info["format"] == "csv" and info["fs_hz"] == RATE_HZ and info["n_samples"] == N
    assert info["duration_s"] == pytest.approx(N / RATE_HZ, rel=1e-12)
    assert info["channels"] == [{"name": "Fz_FL", "unit": "kN", "si_unit": "N"},
                                {"name": "Weg_FL", "unit": "mm", "si_unit": "m"}]
    assert info["dialect"] == {"delimiter": ",", "header_line": 2, "units_row": False, "encoding": "utf-8",
                               "decimal": ".", "thousands": None}
    assert info["metadata"]["rig"] == "dyntrac"


@pytest.mark.parametrize("case", ["missing", "garbage", "truncated_rpc", "folder", "extension", "no_time", "one_row"])
def test_a_bad_file_is_one_sentence_and_exit_2(tmp_path, capsys, case):
    good = write_channels(tmp_path / "good.rsp", _record())
    path = {"missing": tmp_path / "nothere.csv", "garbage": tmp_path / "g.csv", "truncated_rpc": tmp_path / "cut.rsp",
            "folder": tmp_path / "dir.csv", "extension": tmp_path / "rec.xyz", "no_time": tmp_path / "nt.csv",
            "one_row": tmp_path / "one.csv"}[case]
    if case == "garbage":
        path.write_text("garbage\n")
    elif case == "truncated_rpc":
        path.write_bytes(good.read_bytes()[:700])
    elif case == "folder":
        path.mkdir()
    elif case == "extension":
        path.write_text("time,F\n0,1\n1,2\n")
    elif case == "no_time":
        path.write_text("a,F\n0,1\n1,2\n")
    elif case == "one_row":
        path.write_text("time,F\n0,1\n")
    code, out, err = _info(capsys, path)
    assert code == 2 and out == ""
    assert err.startswith("rigsim: error: ") and err.count("\n") == 1 and str(path.name) in err, err
