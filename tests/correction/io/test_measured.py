"""rigsim.correction.io.measured on delimited text: layouts written by hand the way DAQ software writes them,
read back to hand-computed SI numbers; every refusal one sentence naming what is wrong."""

from __future__ import annotations

import os

import numpy as np
import pytest

from rigsim.correction.io.measured import MeasuredDataError, read_channels, write_channels

T = [0.0, 0.001, 0.002, 0.003]
FZ_N = [12500.0, 12750.0, 13000.0, 12250.0]  # 12.5, 12.75, 13.0, 12.25 kN
X_M = [0.0015, 0.00125, 0.001, 0.00075]  # 1.5, 1.25, 1.0, 0.75 mm


def _write(tmp_path, name, content, encoding="utf-8"):
    p = tmp_path / name
    p.write_bytes(content if isinstance(content, bytes) else content.encode(encoding))
    return p


# (file name, content, expected {channel: SI values}, time column name, source units)
LAYOUTS = {
    "comma_point_suffix_N": ("a.csv", "time,Fz_FL_N\n0.000,12500\n0.001,12750\n0.002,13000\n0.003,12250\n",
                             {"Fz_FL_N": FZ_N}, "time", {"Fz_FL_N": "N"}),
    "semicolon_decimal_comma_units_row": (
        "b.csv", "Zeit;Fz_FL;x_FL\ns;kN;mm\n0,000;12,5;1,5\n0,001;12,75;1,25\n0,002;13,0;1,0\n0,003;12,25;0,75\n",
        {"Fz_FL": FZ_N, "x_FL": X_M}, "Zeit", {"Fz_FL": "kN", "x_FL": "mm"}),
    "tab_units_in_brackets": (
        "c.txt", "Time [s]\tFz_FL [kN]\tx_FL [mm]\n0.000\t12.5\t1.5\n0.001\t12.75\t1.25\n0.002\t13.0\t1.0\n"
                 "0.003\t12.25\t0.75\n", {"Fz_FL": FZ_N, "x_FL": X_M}, "Time", {"Fz_FL": "kN", "x_FL": "mm"}),
    "bom_crlf_no_space_brackets": (
        "d.csv", "\ufefftime,Fz_FL[kN]\r\n0.000,12.5\r\n0.001,12.75\r\n0.002,13.0\r\n0.003,12.25\r\n",
        {"Fz_FL": FZ_N}, "time", {"Fz_FL": "kN"}),
    "hash_preamble_parentheses": (
        "e.csv", "# DAQ export\n# rig: DYNTRAC 4-post\n# sample rate: 1000 Hz\n#\n\ntime (s),Fz_FL (kN)\n"
                 "0.000,12.5\n0.001,12.75\n0.002,13.0\n0.003,12.25\n", {"Fz_FL": FZ_N}, "time", {"Fz_FL": "kN"}),
    "time_ms_column": ("f.csv", "time_ms,Fz_FL [N]\n0,12500\n1,12750\n2,13000\n3,12250\n",
                       {"Fz_FL": FZ_N}, "time_ms", {"Fz_FL": "N"}),
    "time_us_column": ("g.csv", "time_us;x_FL [mm]\n0;1,5\n1000;1,25\n2000;1\n3000;0,75\n",
                       {"x_FL": X_M}, "time_us", {"x_FL": "mm"}),
    "mm_displacement_t": ("h.csv", "t,x_FL [mm]\n0,1.5\n0.001,1.25\n0.002,1\n0.003,0.75\n",
                          {"x_FL": X_M}, "t", {"x_FL": "mm"}),
    "status_text_column": (
        "i.csv", "time,Fz_FL [kN],status\n0.000,12.5,OK\n0.001,12.75,OK\n0.002,13.0,OVERLOAD\n0.003,12.25,OK\n",
        {"Fz_FL": FZ_N}, "time", {"Fz_FL": "kN"}),
    "quoted_fields": ("j.csv", '"time","Fz_FL [kN]"\n"0.000","12.5"\n"0.001","12.75"\n"0.002","13.0"\n'
                               '"0.003","12.25"\n', {"Fz_FL": FZ_N}, "time", {"Fz_FL": "kN"}),
    "quoted_decimal_comma_in_comma_file": (
        "k.csv", '"time","Fz_FL [kN]"\n"0,000","12,5"\n"0,001","12,75"\n"0,002","13,0"\n"0,003","12,25"\n',
        {"Fz_FL": FZ_N}, "time", {"Fz_FL": "kN"}),
    "trailing_delimiter": ("l.csv", "time;Fz_FL [kN];\n0,000;12,5;\n0,001;12,75;\n0,002;13,0;\n0,003;12,25;\n",
                           {"Fz_FL": FZ_N}, "time", {"Fz_FL": "kN"}),
    "blank_separated_dat": ("m.dat", "Time [s]    Fz_FL [kN]   x_FL [mm]\n0.000  12.5   1.5\n0.001  12.75  1.25\n"
                                     "0.002  13.0   1.0\n0.003  12.25  0.75\n",
                            {"Fz_FL": FZ_N, "x_FL": X_M}, "Time", {"Fz_FL": "kN", "x_FL": "mm"}),
    "din_slash_and_in": ("n.csv", "Zeit/s;Kraft/kN;Weg in mm\n0,000;12,5;1,5\n0,001;12,75;1,25\n0,002;13;1\n"
                                  "0,003;12,25;0,75\n", {"Kraft": FZ_N, "Weg": X_M}, "Zeit",
                         {"Kraft": "kN", "Weg": "mm"}),
    "units_row_in_brackets": ("o.csv", "t,Fz_FL,x_FL\n[s],[kN],(mm)\n0,12.5,1.5\n0.001,12.75,1.25\n0.002,13,1\n"
                                       "0.003,12.25,0.75\n", {"Fz_FL": FZ_N, "x_FL": X_M}, "t",
                              {"Fz_FL": "kN", "x_FL": "mm"}),
    "thousands_separator_decimal_comma": (
        "p.csv", "Zeit;Fz_FL [N]\n0,000;12.500,0\n0,001;12.750\n0,002;13.000,00\n0,003;12.250,0\n",
        {"Fz_FL": FZ_N}, "Zeit", {"Fz_FL": "N"}),
    "hash_preamble_then_units_row": (
        "r.csv", "# Test: 4-post road simulation\n# Operator: lab 2\nTime;Fz_FL;x_FL\n[s];[kN];[mm]\n"
                 "0,000;12,5;1,5\n0,001;12,75;1,25\n0,002;13,0;1,0\n0,003;12,25;0,75\n",
        {"Fz_FL": FZ_N, "x_FL": X_M}, "Time", {"Fz_FL": "kN", "x_FL": "mm"}),
    "capital_Time_without_unit": ("s.csv", "Time,Fz_FL [N]\n0,12500\n0.001,12750\n0.002,13000\n0.003,12250\n",
                                  {"Fz_FL": FZ_N}, "Time", {"Fz_FL": "N"}),
    "semicolon_comment_preamble_blank_lines": (
        "q.csv", "; catman export\n; channel count = 1\n\ntime;Fz_FL [daN]\n\n0,000;1250\n0,001;1275\n\n0,002;1300\n"
                 "0,003;1225\n\n", {"Fz_FL": FZ_N}, "time", {"Fz_FL": "daN"}),
}


@pytest.mark.parametrize("layout", sorted(LAYOUTS))
def test_daq_layouts_read_to_the_same_si_numbers(tmp_path, layout):
    name, text, expected, time_name, source = LAYOUTS[layout]
    mc = read_channels(_write(tmp_path, name, text))
    assert mc.format == "csv"
    assert mc.time_name == time_name
    assert list(mc.data) == list(expected)
    np.testing.assert_allclose(mc.time_s, T, rtol=0, atol=1e-15)
    assert mc.fs_hz == pytest.approx(1000.0, rel=1e-12)
    for ch, values in expected.items():
        np.testing.assert_allclose(mc.data[ch], values, rtol=1e-14, atol=0)
        assert mc.units[ch] == ("N" if values is FZ_N else "m")
    assert dict(mc.source_units) == source


def test_other_encodings(tmp_path):
    # Excel "Unicode text": UTF-16 with BOM, tab, German decimal comma
    p = _write(tmp_path, "u16.txt", "time\tFz_FL [kN]\n0\t12,5\n0,001\t12,75\n0,002\t13\n0,003\t12,25\n", "utf-16")
    np.testing.assert_allclose(read_channels(p).data["Fz_FL"], FZ_N, rtol=1e-14)
    # an older Windows export: cp1252 with a micro sign
    p = _write(tmp_path, "w.csv", "time;x_FL [µm]\n0;1500\n0,001;1250\n0,002;1000\n0,003;750\n", "cp1252")
    mc = read_channels(p)
    np.testing.assert_allclose(mc.data["x_FL"], X_M, rtol=1e-14)
    assert mc.source_units["x_FL"] == "µm"


def test_kN_and_N_files_give_the_same_numbers_in_N(tmp_path):
    kn = read_channels(_write(tmp_path, "kn.csv", "time;Fz [kN]\n0;12,5\n0,001;12,75\n0,002;13\n0,003;12,25\n"))
    n = read_channels(_write(tmp_path, "n.csv", "time,Fz [N]\n0,12500\n0.001,12750\n0.002,13000\n0.003,12250\n"))
    np.testing.assert_array_equal(kn.data["Fz"], n.data["Fz"])
    np.testing.assert_array_equal(n.data["Fz"], FZ_N)
    assert (kn.source_units["Fz"], n.source_units["Fz"]) == ("kN", "N")


def test_other_units_to_si(tmp_path):
    p = _write(tmp_path, "u.csv", "time,p [bar],F [lbf],v [mm/s],valve [%],ratio [-],a [g],T [°C],plain\n"
                                  "0,2,1,10,50,1,1,20,7\n0.001,3,2,20,25,2,0,25,8\n")
    mc = read_channels(p)
    np.testing.assert_allclose(mc.data["p"], [2e5, 3e5])
    np.testing.assert_allclose(mc.data["F"], [4.4482216152605, 8.896443230521])
    np.testing.assert_allclose(mc.data["v"], [0.01, 0.02])
    np.testing.assert_allclose(mc.data["valve"], [0.5, 0.25])  # % -> fraction, unit "1"
    np.testing.assert_allclose(mc.data["a"], [9.80665, 0.0])  # g is gravity, not a gram
    np.testing.assert_allclose(mc.data["T"], [293.15, 298.15])
    np.testing.assert_allclose(mc.data["plain"], [7, 8])
    assert dict(mc.units) == {"p": "Pa", "F": "N", "v": "m/s", "valve": "1", "ratio": "1", "a": "m/s^2", "T": "K",
                              "plain": ""}
    assert mc.source_units["plain"] == ""


def test_selection_time_col_and_metadata(tmp_path):
    p = _write(tmp_path, "s.csv", "# rig: DYNTRAC\n# note: first line\n# note: second line\n# free text\n"
                                  "time,t,Fz [kN],x [mm],status\n0,5,1,1,OK\n0.001,6,2,2,OK\n0.002,7,3,3,OK\n")
    mc = read_channels(p, time_col="time", channels=["x [mm]", "t"])
    assert list(mc.data) == ["x", "t"]
    np.testing.assert_allclose(mc.data["t"], [5, 6, 7])
    assert dict(mc.metadata) == {"rig": "DYNTRAC", "note": "first line\nsecond line", "comment": "free text"}
    d = mc.to_dict()
    assert d["fs_hz"] == pytest.approx(1000) and d["units"] == {"x": "m", "t": ""} and "data" not in d
    with pytest.raises(TypeError):
        mc.data["y"] = mc.data["x"]  # read-only results
    with pytest.raises(ValueError):
        mc.data["x"][0] = 1.0
    with pytest.raises(ValueError):
        mc.time_s[0] = 1.0


# ---------------------------------------------------------------- refusals: one sentence naming what is wrong

REFUSALS = [
    ("unknown_unit", "time,Fz [furlong]\n0,1\n0.001,2\n", {}, r"'Fz' of .* is in 'furlong', a unit this reader"),
    ("text_selected", "time,Fz [N],status\n0,1,OK\n0.001,2,OK\n", {"channels": ["status"]},
     r"column 'status' is not numeric at line 2 \('OK'\)"),
    ("text_in_numbers", "time,Fz [N]\n0,1\n0.001,12kN\n0.002,3\n", {}, r"column 'Fz' is not numeric at line 3 \('12kN'\)"),
    ("nan", "time,Fz [N]\n0,1\n0.001,2\n0.002,nan\n", {}, r"column 'Fz' has 'nan' at line 4"),
    ("inf", "time;Fz [N]\n0;1\n0,001;-inf\n", {}, r"column 'Fz' has '-inf' at line 3"),
    ("gap", "time,Fz [N]\n0,1\n0.001,\n0.002,3\n", {}, r"column 'Fz' is empty at line 3"),
    ("duplicate", "time,Fz [N],Fz [kN]\n0,1,1\n0.001,2,2\n", {}, r"column 'Fz' appears more than once"),
    ("two_times", "time,t,Fz\n0,0,1\n0.001,0.001,2\n", {}, r"several time columns \(time, t\); name the one"),
    ("no_time", "a,b\n0,1\n1,2\n", {}, r"has no time column .* its columns are a, b"),
    ("non_uniform", "time,F\n0,1\n0.001,1\n0.002,1\n0.0035,1\n0.0045,1\n", {}, r"column 'time' is not uniform at line 5"),
    ("backwards", "time,F\n0,1\n0.002,1\n0.001,1\n", {}, r"column 'time' does not increase at line 4"),
    ("time_in_mm", "time [mm],F\n0,1\n1,2\n", {}, r"time column 'time' of .* is in 'mm', not a unit of time"),
    ("units_disagree", "time,F [kN]\ns,N\n0,1\n1,2\n", {}, r"'F' of .* says 'kN' in the header but 'N' in the units row"),
    ("short_row", "time,F\n0,1\n0.001\n", {}, r"line 3 of .* has 1 fields but the header has 2"),
    ("one_row", "time,F\n0,1\n", {}, r"has 1 data rows; at least two are needed"),
    ("missing_channel", "time,F [N]\n0,1\n1,2\n", {"channels": ["G"]}, r"channel 'G' is not a column of .* columns are time, F"),
    ("time_as_channel", "time,F [N]\n0,1\n1,2\n", {"channels": ["time"]}, r"channel 'time' is the time column"),
    ("header_only", "time,F\n", {}, r"has a header \(line 1\) but no data rows"),
    ("empty", "# nothing\n", {}, r"is empty; it needs a header line"),
]


@pytest.mark.parametrize("kind, text, kwargs, message", REFUSALS, ids=[r[0] for r in REFUSALS])
def test_refusals_are_one_sentence(tmp_path, kind, text, kwargs, message):
    p = _write(tmp_path, f"{kind}.csv", text)
    with pytest.raises(MeasuredDataError, match=message) as exc:
        read_channels(p, **kwargs)
    assert "\n" not in str(exc.value)


def test_unknown_unit_or_text_only_matters_when_selected(tmp_path):
    p = _write(tmp_path, "x.csv", "time,Fz [furlong],x [mm],status\n0,1,1,OK\n0.001,2,2,OK\n")
    np.testing.assert_allclose(read_channels(p, channels=["x"]).data["x"], [0.001, 0.002])


def test_file_level_refusals(tmp_path):
    with pytest.raises(MeasuredDataError, match=r"does not exist"):
        read_channels(tmp_path / "missing.csv")
    with pytest.raises(MeasuredDataError, match=r"extension '.xlsx'; give a .csv"):
        read_channels(_write(tmp_path, "a.xlsx", "time,F\n0,1\n"))
    with pytest.raises(MeasuredDataError, match=r"is binary, not delimited text"):
        read_channels(_write(tmp_path, "bin.dat", b"\x00\x01\x02time"))


# ---------------------------------------------------------------- writing CSV

def _channels(tmp_path):
    return read_channels(_write(tmp_path, "in.csv", "# rig: DYNTRAC\ntime;Fz_FL [kN];x_FL [mm]\n"
                                                     "0,000;12,5;1,5\n0,001;12,75;1,25\n0,002;13;1\n0,003;12,25;0,75\n"))


def test_csv_write_reads_back_exactly(tmp_path):
    mc = _channels(tmp_path)
    out = write_channels(tmp_path / "out" / "o.csv", mc, metadata={"rig": "DYNTRAC", "note": "a\nb"})
    lines = out.read_text().splitlines()
    assert lines[:3] == ["# rig: DYNTRAC", "# note: a", "# note: b"]
    assert lines[3] == "time [s],Fz_FL [N],x_FL [m]"
    back = read_channels(out)
    np.testing.assert_array_equal(back.time_s, mc.time_s)
    for n in mc.data:
        np.testing.assert_array_equal(back.data[n], mc.data[n])
    assert dict(back.units) == dict(mc.units) and dict(back.metadata) == {"rig": "DYNTRAC", "note": "a\nb"}
    assert dict(read_channels(write_channels(tmp_path / "p.csv", mc)).metadata) == {"rig": "DYNTRAC"}  # its own


def test_write_refusals_and_atomicity(tmp_path):
    mc = _channels(tmp_path)
    out = tmp_path / "o.csv"
    out.write_text("previous\n")
    with pytest.raises(MeasuredDataError, match=r"exists; pass --force"):
        write_channels(out, mc)
    with pytest.raises(MeasuredDataError, match=r"metadata key 'a:b' cannot be written"):
        write_channels(out, mc, metadata={"a:b": "x"}, overwrite=True)
    assert out.read_text() == "previous\n"
    assert sorted(os.listdir(tmp_path)) == ["in.csv", "o.csv"]  # no temporary file left
    write_channels(out, mc, overwrite=True)
    assert out.read_text().startswith("# rig: DYNTRAC\ntime [s],")
    with pytest.raises(MeasuredDataError, match=r"is the input file"):
        write_channels(tmp_path / "in.csv", mc, overwrite=True, inputs=[tmp_path / "in.csv"])
    os.symlink(tmp_path / "in.csv", tmp_path / "link.csv")
    with pytest.raises(MeasuredDataError, match=r"is the input file"):
        write_channels(tmp_path / "link.csv", mc, overwrite=True, inputs=[tmp_path / "in.csv"])


@pytest.mark.parametrize("data, message", [
    ({"Fz [kN]": [1.0, 2.0]}, r"channel name 'Fz \[kN\]' cannot be written"),
    ({"Time": [1.0, 2.0]}, r"channel name 'Time' would read back as .* a time column"),
    ({"Fz": [1.0, float("nan")]}, r"channel 'Fz' is nan at sample 1"),
    ({"Fz": [1.0]}, r"channel 'Fz' has shape \(1,\) but time_s has \(2,\)"),
])
def test_write_refuses_what_would_not_read_back(tmp_path, data, message):
    from types import SimpleNamespace

    with pytest.raises(MeasuredDataError, match=message):
        write_channels(tmp_path / "o.csv", SimpleNamespace(time_s=[0.0, 0.001], data=data, units={}))
    assert not (tmp_path / "o.csv").exists()


# ---------------------------------------------------------------- a lab's CSV: ms time, text column, uniform rate

def test_ms_time_text_column_and_uniform_rate(tmp_path):
    """read_channels on a lab's CSV: time in ms, decimal commas, a text column left out, the rate from
    a uniform time axis (the reader rigsim correct and identify use)."""
    p = _write(tmp_path, "old.csv", "time [ms];Fz_FL [kN];status\n0;12,5;OK\n1;12,75;OK\n2;13;OK\n3;12,25;OK\n")
    mc = read_channels(p)
    assert mc.names == ("Fz_FL",) and mc.time_name == "time"  # the status text is left out
    np.testing.assert_allclose(mc.time_s, T, rtol=1e-14)
    np.testing.assert_allclose(mc.data["Fz_FL"], FZ_N, rtol=1e-14)
    assert mc.fs_hz == pytest.approx(1000.0)
    assert read_channels(_write(tmp_path, "t.csv", "t,F\n0,1\n1,2\n")).fs_hz == pytest.approx(1.0)
    with pytest.raises(MeasuredDataError, match=r"'time' is not uniform at line 5 "):  # row i on line i + 2
        read_channels(_write(tmp_path, "u.csv", "time,F\n0,1\n0.001,2\n0.002,3\n0.0035,4\n0.0045,5\n"))
