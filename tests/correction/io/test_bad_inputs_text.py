"""Delimited text read unambiguously or refused, streamed, never a traceback.

The numbers of a text file as its locale writes them (decimal mark, thousands separator), read
to the exact value or refused in one sentence naming the column, the file and the fix
(``--decimal``/``--thousands``); a long line or a very wide file read, not a csv field-limit
traceback; the file streamed in blocks (the working memory is one block, not the file); a
NaN or empty sample named by column, line and file. Expected values are the numbers as printed,
parsed by hand here (digits without separators, then ``float``).
"""

from __future__ import annotations

import time
import tracemalloc

import numpy as np
import pytest

import rigsim.correction.io.measured_csv as measured_csv
import rigsim.correction.io.measured_stream as measured_stream
from rigsim.correction.io.measured import MeasuredDataError, read_channels
from rigsim.correction.io.measured_numbers import DECIMALS, THOUSANDS
from rigsim.scenarios.cli.main import main

NBSP, NNBSP = "\u00a0", "\u202f"
GOOD_ACTUATOR = "[transfer_function]\nnum = [1.0]\nden = [2.5e-4, 0.02, 1.0]\n"


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def _refused(path, match, **kwargs) -> str:
    with pytest.raises(MeasuredDataError, match=match) as exc:
        read_channels(path, **kwargs)
    msg = str(exc.value)
    assert "\n" not in msg and repr(str(path)) in msg, msg
    return msg


@pytest.fixture()
def small_blocks(monkeypatch):
    """Layout from the first 3 data lines, then blocks of about 40 characters: the streaming
    paths (numpy's reader, a rewritten block, the checked path) on small files."""
    monkeypatch.setattr(measured_csv, "SAMPLE_LINES", 3)
    monkeypatch.setattr(measured_stream, "BLOCK_CHARS", 40)


# ------------------------------------------------------------------- thousands of English exports
ENGLISH_QUOTED = 'time_ms,Fz [N]\n0,"21,988"\n1,"22,105"\n2,"21,870"\n'  # nothing decides: refused
ENGLISH_SEMICOLON = "time_ms;Fz [N]\n0;21,988\n1;22,105\n2;21,870\n"


@pytest.mark.parametrize("text", [ENGLISH_QUOTED, ENGLISH_SEMICOLON], ids=["quoted_comma", "semicolon"])
def test_comma_thousands_alone_are_refused_naming_column_and_flags(tmp_path, text):
    p = _write(tmp_path, "en.csv", text)
    msg = _refused(p, r"column 'Fz' of .* writes '21,988' at line 2, which reads 21\.988 with a decimal comma or "
                      r"21988 with a thousands separator")
    assert "--decimal" in msg and "--thousands" in msg


@pytest.mark.parametrize("text", [ENGLISH_QUOTED, ENGLISH_SEMICOLON], ids=["quoted_comma", "semicolon"])
@pytest.mark.parametrize("kwargs, expected", [
    ({"thousands": ","}, [21988.0, 22105.0, 21870.0]),
    ({"decimal": "."}, [21988.0, 22105.0, 21870.0]),
    ({"decimal": ","}, [21.988, 22.105, 21.87]),
    ({"thousands": "none"}, [21.988, 22.105, 21.87]),
])
def test_the_flags_settle_the_ambiguous_file(tmp_path, text, kwargs, expected):
    mc = read_channels(_write(tmp_path, "en.csv", text), **kwargs)
    np.testing.assert_array_equal(mc.data["Fz"], expected)


@pytest.mark.parametrize("text, expected", [
    ('time,Fz [N]\n0.000,"21,988"\n0.001,"22,105"\n0.002,"21,870"\n', [21988.0, 22105.0, 21870.0]),  # time: point
    ('time,Fz [N]\n"0,000","21,988"\n"0,001","22,105"\n"0,002","21,870"\n', [21.988, 22.105, 21.87]),  # comma
    ("time_ms;Fz [N]\n0;21,988\n1;1,022,105\n2;21,870\n", [21988.0, 1022105.0, 21870.0]),  # two groups
    ("time_ms;Fz [N]\n0;21,988\n1;22,105.5\n2;21,870\n", [21988.0, 22105.5, 21870.0]),  # both marks
    ("time_ms;Fz [N]\n0;21,988\n1;22,5\n2;21,870\n", [21.988, 22.5, 21.87]),  # not three digits: decimal
    ("time_ms;Fz [N]\n0;21,988\n1;0,105\n2;21,870\n", [21.988, 0.105, 21.87]),  # a leading 0: decimal
    ("time_ms;Fz [N]\n0;21.988\n1;22.105\n2;1.221,870\n", [21988.0, 22105.0, 1221.87]),  # German
], ids=["file_point", "file_comma", "column_groups", "column_both", "column_decimal", "column_zero", "german"])
def test_the_column_or_the_file_decides(tmp_path, text, expected):
    np.testing.assert_array_equal(read_channels(_write(tmp_path, "d.csv", text)).data["Fz"], expected)


# ----------------------------------------------------------------- French and Swiss separators
@pytest.mark.parametrize("sep", [" ", NBSP, NNBSP], ids=["space", "nbsp", "narrow_nbsp"])
def test_french_thousands_read(tmp_path, sep):
    text = f"time;Fz [N]\n0,000;21{sep}988,5\n0,001;1{sep}022{sep}105,25\n0,002;870,0\n"
    mc = read_channels(_write(tmp_path, "fr.csv", text))
    np.testing.assert_array_equal(mc.data["Fz"], [21988.5, 1022105.25, 870.0])


def test_swiss_thousands_read(tmp_path):
    mc = read_channels(_write(tmp_path, "ch.csv", "time;Fz [N]\n0.000;21'988.5\n0.001;22'105.25\n0.002;870\n"))
    np.testing.assert_array_equal(mc.data["Fz"], [21988.5, 22105.25, 870.0])


def test_french_in_a_blank_separated_table(tmp_path):
    mc = read_channels(_write(tmp_path, "fr.dat", f"time Fz\n0,000 21{NNBSP}988,5\n0,001 22{NBSP}105,25\n"))
    np.testing.assert_array_equal(mc.data["Fz"], [21988.5, 22105.25])


@pytest.mark.parametrize("text, kwargs, match", [
    ("time;Fz\n0,000;21 988,5\n0,001;1,5\n", {"thousands": "."}, r"column 'Fz' is not a number with the thousands "
                                                                  r"separator '\.' given at line 2 \('21 988,5'\)"),
    ("time;Fz\n0.000;21,5\n0.001;1.5\n", {"decimal": "."}, r"column 'Fz' is not a number with the decimal mark '\.' "
                                                           r"given at line 2 \('21,5'\)"),
    ("time;Fz\n0.000;1.5\n0.001;1.5\n", {"decimal": ",", "thousands": ","}, r"are both ','"),
    ("time;Fz\n0.000;1.5\n0.001;1.5\n", {"decimal": ";"}, r"decimal mark ';' .* is not '\.' or ','"),
])
def test_given_separators_that_the_file_does_not_use_are_refused(tmp_path, text, kwargs, match):
    _refused(_write(tmp_path, "g.csv", text), match, **kwargs)


def test_separators_are_refused_for_binary_formats(tmp_path):
    from types import SimpleNamespace

    from rigsim.correction.io.measured import write_channels

    p = write_channels(tmp_path / "r.rsp", SimpleNamespace(time_s=[0.0, 0.001], data={"F": [1.0, 2.0]}, units={}))
    with pytest.raises(MeasuredDataError, match=r"is a rpc3 file, which stores numbers, not text; leave the decimal"):
        read_channels(p, decimal=",")


def test_the_cli_choices_are_the_readers():
    import argparse

    from rigsim.scenarios.studies.identify.command import add_number_format

    parser = argparse.ArgumentParser()
    add_number_format(parser)
    choices = {a.dest: tuple(a.choices) for a in parser._actions if a.dest in ("decimal", "thousands")}
    assert choices == {"decimal": DECIMALS, "thousands": tuple(THOUSANDS)}


# ----------------------------------------------------------------------------- contradictions
def test_columns_that_contradict_are_refused(tmp_path):
    p = _write(tmp_path, "c.csv", "time;Fz [N]\n0.000;21,5\n0.001;22,25\n0.002;21,0\n")
    _refused(p, r"column 'Fz' of .* writes '21,5' at line 2 \(decimal comma\) but column 'time' writes '0\.000' at "
                r"line 2 \(decimal point\); fix: export the file with one decimal mark")


@pytest.mark.parametrize("blocks", [False, True], ids=["first_lines", "later_block"])
def test_a_later_line_that_contradicts_is_refused_naming_it(tmp_path, request, blocks):
    if blocks:
        request.getfixturevalue("small_blocks")
    rows = "".join(f"{i / 1000:.3f};{21000 + i}.5\n" for i in range(40)) + "0.040;21,5\n0.041;1.5\n"
    p = _write(tmp_path, "late.csv", "time;Fz [N]\n" + rows)
    _refused(p, r"column 'Fz' of .* writes '21,5' at line 42 \(decimal comma\) but column 'time' writes '0\.000' at "
                r"line 2 \(decimal point\)")


# --------------------------------------------------------------------------- long and wide lines
@pytest.mark.parametrize("channels", [["Fz"], None], ids=["selected", "all"])
def test_a_long_note_in_an_unselected_column_reads(tmp_path, channels):
    note = "a remark, quoted; " * 11112  # 200 016 characters
    rows = [f'{i / 1000:.3f},{21000 + i}.5,"{note if i == 1 else "ok"}"\n' for i in range(4)]
    p = _write(tmp_path, "note.csv", "time,Fz [N],note\n" + "".join(rows))
    assert max(map(len, p.read_text().splitlines())) > 200_000
    mc = read_channels(p, channels=channels)
    assert list(mc.data) == ["Fz"]
    np.testing.assert_array_equal(mc.data["Fz"], [21000.5, 21001.5, 21002.5, 21003.5])


@pytest.mark.parametrize("channels", [None, ["c16382", "c7"]], ids=["all", "two"])
def test_as_many_columns_as_a_worksheet_read_within_seconds(tmp_path, channels):
    n = measured_csv.MAX_COLUMNS - 1  # and the time
    head = "time," + ",".join(f"c{j}" for j in range(n)) + "\n"
    rows = "".join(f"{i / 1000:.3f}," + ",".join(f"{(i + j) % 7}.5" for j in range(n)) + "\n" for i in range(3))
    p = _write(tmp_path, "wide.csv", head + rows)
    start = time.perf_counter()
    mc = read_channels(p, channels=channels)
    assert time.perf_counter() - start < 20.0
    assert len(mc.data) == (n if channels is None else 2)
    np.testing.assert_array_equal(mc.data["c7"], [0.5, 1.5, 2.5])
    np.testing.assert_array_equal(mc.data["c16382"], [(j + 16382) % 7 + 0.5 for j in range(3)])
    p.write_text(head.replace("\n", ",c_more\n") + rows)
    _refused(p, r"the header \(line 1\) of .* has 16385 fields, more than the 16384 columns")


# --------------------------------------------------------------------- missing samples, streamed
@pytest.mark.parametrize("field, match", [("nan", r"has 'nan' at line 5 of '.*s\.csv'; fix: remove or interpolate"),
                                          ("-inf", r"has '-inf' at line 5 of '.*s\.csv'"),
                                          ("", r"is empty at line 5 of '.*s\.csv'; fix: fill the gap"),
                                          ("12kN", r"is not numeric at line 5 \('12kN'\) of '.*s\.csv'")])
@pytest.mark.parametrize("blocks", [False, True], ids=["first_lines", "later_block"])
def test_a_bad_sample_is_named_by_column_line_and_file(tmp_path, request, field, match, blocks):
    if blocks:
        request.getfixturevalue("small_blocks")
    rows = [f"{i / 1000:.3f},{21000 + i}.5" for i in range(40)]
    rows[3] = f"0.003,{field}"
    p = _write(tmp_path, "s.csv", "time,Fz [N]\n" + "\n".join(rows) + "\n")
    _refused(p, r"column 'Fz' " + match)


def test_blocks_read_what_the_first_lines_read(tmp_path, small_blocks):
    """Every path of the stream over one file: plain, quoted, a comment and a blank line (file
    lines counted), thousands, decimal commas; the numbers as printed."""
    rng = np.random.default_rng(4)
    v = np.round(rng.uniform(-2e6, 2e6, 300), 3)
    lines = []
    for i, x in enumerate(v):
        s = f"{x:,.3f}" if i % 3 else f"{x:.3f}"
        s = s.replace(",", "'") if i % 5 == 1 else s
        s = f'"{s}"' if i % 7 == 2 else s
        lines.append(f"{i};{s}")
    lines.insert(120, "# a comment")
    lines.insert(200, "")
    lines.append("300;12,5")  # a decimal comma after three hundred rows of points
    p = _write(tmp_path, "b.csv", "time_ms;F\n" + "\n".join(lines) + "\n")
    _refused(p, r"column 'F' of .* writes '12,5' at line 304 \(decimal comma\)")
    p.write_text("time_ms;F\n" + "\n".join(lines[:-1]) + "\n", encoding="utf-8")
    mc = read_channels(p)
    np.testing.assert_array_equal(mc.data["F"], v)
    np.testing.assert_array_equal(mc.time_s, np.arange(300) / 1000.0)
    de = p.read_text().replace(",", "~").replace(".", ",").replace("~", ".").replace("'", ".")
    np.testing.assert_array_equal(read_channels(_write(tmp_path, "de.csv", de)).data["F"], v)


def test_the_file_is_streamed_not_held(tmp_path):
    """Python's allocations while reading 2 of 10 columns of a 30 MB file: the two result arrays
    and one block of lines, not the file's text, lines or fields."""
    rng = np.random.default_rng(2)
    n = 300_000
    p = tmp_path / "big.csv"
    data = np.column_stack([np.arange(n) / 1000] + [30e3 + 1e3 * rng.standard_normal(n) for _ in range(9)])
    np.savetxt(p, data, delimiter=",", fmt=["%.3f"] + ["%.9g"] * 9, comments="",
               header="time," + ",".join(f"F{j} [N]" for j in range(9)))
    assert p.stat().st_size > 30e6
    tracemalloc.start()
    try:
        mc = read_channels(p, channels=["F3", "F8"])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    result = mc.time_s.nbytes + sum(v.nbytes for v in mc.data.values())
    assert peak < result + 4 * measured_stream.BLOCK_CHARS, (peak / 1e6, result / 1e6)
    np.testing.assert_array_equal(mc.data["F8"], np.loadtxt(p, delimiter=",", skiprows=1, usecols=9))


# ---------------------------------------------------------------------------------- the CLI
def _forces_file(path, grouped: bool) -> None:
    """4 s at 1 kHz, time in ms, a wheel force in N written 30,125 (English thousands) or 30125."""
    rng = np.random.default_rng(1)
    f = np.round(30e3 + 1e3 * rng.standard_normal(4000)).astype(int)
    rows = "".join(f"{i};{x:,d}\n" if grouped else f"{i};{x:d}\n" for i, x in enumerate(f))
    path.write_text("time_ms;fl_N [N]\n" + rows, encoding="utf-8")


def _cli(argv, capsys):
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr()


def test_rigsim_correct_refuses_an_ambiguous_file_in_one_line_and_reads_it_with_the_flags(tmp_path, capsys):
    _forces_file(tmp_path / "en.csv", grouped=True)
    _forces_file(tmp_path / "plain.csv", grouped=False)
    (tmp_path / "act.toml").write_text(GOOD_ACTUATOR)
    base = ["correct", tmp_path / "en.csv", "--actuator", tmp_path / "act.toml", "-o"]
    code, out = _cli(base + [tmp_path / "o.csv"], capsys)
    assert code == 2 and not (tmp_path / "o.csv").exists()
    lines = out.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rigsim: error: column 'fl_N' of "), out.err
    assert "--decimal" in lines[0] and "--thousands" in lines[0] and "Traceback" not in out.err
    assert _cli(base + [tmp_path / "a.csv", "--thousands", ","], capsys)[0] == 0
    assert _cli(["correct", tmp_path / "plain.csv", "--actuator", tmp_path / "act.toml", "-o", tmp_path / "b.csv"],
                capsys)[0] == 0
    a, b = read_channels(tmp_path / "a.csv"), read_channels(tmp_path / "b.csv")
    np.testing.assert_array_equal(a.data["fl_N_corrected"], b.data["fl_N_corrected"])  # 30,125 read as 30125
    code, out = _cli(base + [tmp_path / "c.csv", "--decimal", ","], capsys)
    assert code == 0  # 30.125 N: another file, the flag obeyed
    assert abs(np.mean(read_channels(tmp_path / "c.csv").data["fl_N_corrected"]) - 30.0) < 1.0
    code, out = _cli(base + [tmp_path / "d.csv", "--thousands", "comma"], capsys)
    assert code == 2 and "invalid choice" in out.err.splitlines()[-1]


def test_rigsim_identify_passes_the_flags_to_the_reader(tmp_path, capsys):
    rows = "".join(f"{i};1,250;2,500\n" for i in range(3000))  # constant drive and LVDT, ambiguous
    (tmp_path / "rec.csv").write_text("time_ms;drive_m [mm];lvdt_m [mm]\n" + rows, encoding="utf-8")
    base = ["identify", "--from-file", tmp_path / "rec.csv", "--pairs", "fl=drive_m:lvdt_m", "--out"]
    code, out = _cli(base + [tmp_path / "o1"], capsys)
    assert code == 2 and "writes '1,250' at line 2" in out.err and "--decimal" in out.err
    code, out = _cli(base + [tmp_path / "o2", "--decimal", ","], capsys)
    assert code == 2 and "columns 'drive_m' and 'lvdt_m' must vary" in out.err  # read: 1.25 mm, then refused
    code, out = _cli(["identify", "--out", tmp_path / "o3", "--decimal", ","], capsys)
    assert code == 2 and "--decimal and --thousands go with --from-file" in out.err


# --------------------------------------------------------------------- any locale: exact or refused
try:
    from hypothesis import HealthCheck, event, given, settings
    from hypothesis import strategies as st
except ImportError:  # hypothesis comes with the test extra
    st = None


def _printed(x: float, places: int, decimal: str, thousands: str | None) -> str:
    """``x`` with ``places`` decimals, the decimal mark and the thousands separator of a locale."""
    return f"{x:,.{places}f}".replace(",", "\0").replace(".", decimal).replace("\0", thousands or "")


if st is None:
    def test_any_locale_reads_exactly_or_is_refused_naming_the_column():
        pytest.skip("hypothesis is not installed")
else:
    #: (values, decimals printed): any; thousands with one group (21,988); three decimals (21.988).
    VALUES = {"any": (st.floats(-1e7, 1e7, allow_nan=False), st.integers(0, 6)),
              "one_group": (st.integers(1000, 999_999).map(float), st.just(0)),
              "three_places": (st.floats(1.0, 999.0), st.just(3))}

    @st.composite
    def locale_files(draw):
        """(text, the channel's values as printed, the time in s as printed) of a two-column file."""
        decimal = draw(st.sampled_from(DECIMALS))
        delimiter = draw(st.sampled_from([",", ";", "\t", " "]))
        thousands = draw(st.sampled_from([None, ",", ".", "'", " ", NBSP, NNBSP]).filter(
            lambda t: t != decimal and not (delimiter == " " and t == " ")))
        quote_all = delimiter != " " and draw(st.booleans())
        values, decimals = VALUES[draw(st.sampled_from(sorted(VALUES)))]
        places, n = draw(decimals), draw(st.integers(2, 30))
        xs = draw(st.lists(values, min_size=n, max_size=n))
        step, in_ms = draw(st.sampled_from([1, 2, 250, 1000])), draw(st.booleans())

        def field(x, p):
            s = _printed(x, p, decimal, thousands)
            return f'"{s}"' if quote_all or delimiter in s else s

        times = [float(i * step) if in_ms else float(f"{i * step / 1000:.3f}") for i in range(n)]
        rows = [delimiter.join([field(t, 0 if in_ms else 3), field(x, places)]) for t, x in zip(times, xs)]
        head = delimiter.join(["time_ms" if in_ms else "time", "F"])
        expected = [float(f"{x:.{places}f}") for x in xs]
        return head + "\n" + "\n".join(rows) + "\n", expected, np.array(times) * (1e-3 if in_ms else 1.0)

    @settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(case=locale_files(), small=st.booleans())
    def test_any_locale_reads_exactly_or_is_refused_naming_the_column(tmp_path_factory, case, small):
        text, expected, times = case
        p = tmp_path_factory.mktemp("locale") / "l.csv"
        p.write_text(text, encoding="utf-8")
        with pytest.MonkeyPatch.context() as mp:
            if small:
                mp.setattr(measured_csv, "SAMPLE_LINES", 3)
                mp.setattr(measured_stream, "BLOCK_CHARS", 40)
            try:
                mc = read_channels(p)
            except MeasuredDataError as exc:
                msg = str(exc)
                assert "\n" not in msg and ("column 'F'" in msg or "column 'time" in msg), msg
                event("refused")
                return
        event("read")
        np.testing.assert_array_equal(mc.data["F"], expected)
        np.testing.assert_allclose(mc.time_s, times - times[0], rtol=0, atol=1e-12)
