"""``rigsim correct`` (scenarios/cli/correct.py): round trips and refusals.

The command is driven through an argparse parser built with its own ``add_parser`` and
``ScenarioError`` is turned into exit code 2 as the CLI does. Expected values: the rig force is
the road force through a known T_a simulated with ``scipy.signal.lsim``; the corrected output is
compared with the road force through the low-pass (the library's ``band_limit``, itself checked
against scipy in test_correction.py) and with the library called directly.

Corrected columns are written as ``<name>_corrected`` (``fl_N_corrected``), so they cannot be
mistaken for raw ones.

One reader: the input is read by ``rigsim.correction.io.measured.read_channels`` (any
CSV dialect, RPC III, MDF4; units to SI) and the output written by ``write_channels`` in the
format of its extension (CSV: a ``# key: value`` preamble, ``time [s]``, ``name [N]`` headers);
``read_csv`` below parses that CSV by hand, independently of the reader.
"""

from __future__ import annotations

import argparse
import hashlib
import math
import re
from importlib.metadata import version

import numpy as np
import pytest
from scipy import signal

from rigsim.correction.output.apply import band_limit, correct
from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.correction.output.filters import design_correction
from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.cli.correct import add_parser, cmd_correct

EQ4_VALUES = dict(ksv=1.0, kq_m3_s=0.0109, kc_m3_s_Pa=1.26e-11, kp_per_m=50.0, kdp_per_Pa=2.0e-8,
                  piston_area_m2=7.43e-3, fluid_volume_m3=2.13e-3, bulk_modulus_Pa=1.0e9, mass_kg=500.0,
                  damping_N_s_m=5.0e3, tire_N_per_m=1.0e6)
FS = 1000.0


def run(argv) -> int:
    p = argparse.ArgumentParser()
    add_parser(p.add_subparsers(dest="command", required=True))
    args = p.parse_args(["correct", *map(str, argv)])
    assert args.func is cmd_correct
    try:
        return args.func(args)
    except ScenarioError as exc:
        msg = str(exc)
        assert msg and "\n" not in msg
        run.last_error = msg
        return 2


run.last_error = ""


def write_csv(path, names, columns, time_fmt="{:.6f}"):
    lines = [",".join(names)]
    for row in zip(*columns):
        lines.append(",".join(time_fmt.format(row[0]) if i == 0 else repr(float(v)) for i, v in enumerate(row)))
    path.write_text("\n".join(lines) + "\n")


def read_csv(path):
    """The output CSV parsed by hand: '#' preamble skipped, '[unit]' taken off the header names."""
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    names = [re.sub(r"\s*\[[^\]]*\]$", "", h) for h in lines[0].split(",")]
    return np.rec.fromarrays(np.loadtxt(lines[1:], delimiter=",", ndmin=2).T, names=names)


def read_metadata(path):
    """The output CSV's '# key: value' preamble, parsed by hand."""
    return dict(ln[2:].split(": ", 1) for ln in path.read_text().splitlines() if ln.startswith("# "))


def header(path):
    return next(ln for ln in path.read_text().splitlines() if not ln.startswith("#"))


@pytest.fixture(scope="module")
def rig_data():
    """Two wheels: road forces, the rig forces (T_a = eq. 4 applied with scipy), drive and pan."""
    rng = np.random.default_rng(42)
    n = int(20 * FS)
    t = np.arange(n) / FS
    num, den = eq4_coefficients_from(**EQ4_VALUES)
    bp = signal.butter(4, [0.5, 20.0], "bandpass", fs=FS, output="sos")
    fade = np.clip(t / 2, 0, 1)
    road = np.stack([30e3 + 4e3 * fade * signal.sosfilt(bp, rng.standard_normal(n)) / 0.3,
                     28e3 + 5e3 * fade * signal.sosfilt(bp, rng.standard_normal(n)) / 0.3], axis=1)
    rig = np.stack([signal.lsim((num, den), road[:, i] - road[0, i], t)[1] + road[0, i] for i in range(2)], axis=1)
    drive = 0.01 * signal.sosfilt(signal.butter(4, [0.3, 40.0], "bandpass", fs=FS, output="sos"),
                                  rng.standard_normal(n))
    pan = signal.lsim((num, den), drive, t)[1]
    return dict(t=t, road=road, rig=rig, drive=drive, pan=pan, num=num, den=den)


@pytest.fixture()
def files(tmp_path, rig_data):
    d = rig_data
    csv = tmp_path / "rig.csv"
    write_csv(csv, ["time", "fl_N", "fr_N"], [d["t"], d["rig"][:, 0], d["rig"][:, 1]])
    act = tmp_path / "act.toml"
    act.write_text("[transfer_function]\nnum = [%s]\nden = [%s]\n" % (
        ", ".join(repr(float(v)) for v in d["num"]), ", ".join(repr(float(v)) for v in d["den"])))
    return csv, act, tmp_path


def nothing_written(folder, out):
    return not out.exists() and not [p for p in folder.iterdir() if p.name.startswith(".")]


# ---------------------------------------------------------------- good files


@pytest.mark.parametrize("mode", ["causal", "zerophase"])
@pytest.mark.parametrize("lowpass", ["paper", "regularized"])
def test_round_trip_recovers_the_band_limited_road_force(files, rig_data, mode, lowpass):
    csv, act, tmp = files
    out = tmp / "out" / "corrected.csv"
    assert run([csv, "--actuator", act, "-o", out, "--lowpass", lowpass, "--mode", mode]) == 0
    got = read_csv(out)
    assert got.dtype.names == ("time", "fl_N_corrected", "fr_N_corrected")
    filt = design_correction((rig_data["num"], rig_data["den"]), FS, lowpass)
    mask = filt.transient_mask(rig_data["t"].size, mode)
    np.testing.assert_allclose(got["time"], rig_data["t"][mask], atol=1e-9)
    ref = band_limit(rig_data["road"], FS, lowpass, mode)[mask]
    direct = correct(rig_data["rig"], filt, mode)[mask]
    for i, col in enumerate(("fl_N", "fr_N")):
        np.testing.assert_allclose(got[col + "_corrected"], direct[:, i], rtol=1e-9)  # written to 10 digits
        dyn = ref[:, i] - ref[:, i].mean()
        assert np.sqrt(np.mean((got[col + "_corrected"] - ref[:, i]) ** 2)) / dyn.std() < 5e-3  # fs 1 kHz: warping ~1e-3


def test_parameters_file_mark_option_and_selected_columns(files, rig_data):
    csv, _, tmp = files
    act = tmp / "par.toml"
    act.write_text("[parameters]\n" + "".join(f"{k} = {v!r}\n" for k, v in EQ4_VALUES.items()))
    out = tmp / "o.csv"
    assert run([csv, "--actuator", act, "-o", out, "--columns", "fr_N", "--transient", "mark",
                "--mode", "causal"]) == 0
    got = read_csv(out)
    assert got.dtype.names == ("time", "fr_N_corrected", "settled")
    assert got.size == rig_data["t"].size
    filt = design_correction((rig_data["num"], rig_data["den"]), FS, "regularized")
    np.testing.assert_array_equal(got["settled"].astype(bool), filt.transient_mask(got.size, "causal"))


def test_identify_from_drive_and_pan_columns(tmp_path, rig_data):
    d = rig_data
    csv = tmp_path / "rig.csv"
    write_csv(csv, ["time", "drive_m", "pan_m", "fl_N"], [d["t"], d["drive"], d["pan"], d["rig"][:, 0]])
    out = tmp_path / "o.csv"
    assert run([csv, "--identify", "drive_m,pan_m", "-o", out, "--transient", "mark"]) == 0
    got = read_csv(out)
    assert got.dtype.names == ("time", "fl_N_corrected", "settled")
    assert read_metadata(out)["ta_source"] == "identified from drive_m,pan_m"
    filt = design_correction((d["num"], d["den"]), FS, "regularized")
    both = filt.transient_mask(d["t"].size, "zerophase") & got["settled"].astype(bool)
    assert both.sum() > 0.5 * both.size
    known = correct(d["rig"][:, 0], filt, "zerophase")[both]
    dyn = known - known.mean()
    assert np.sqrt(np.mean((got["fl_N_corrected"][both] - known) ** 2)) / dyn.std() < 0.02  # identified vs known


# ---------------------------------------------------------------- refusals: exit 2, one sentence, nothing written


def _bad_csv(tmp, rig_data, kind):
    t = rig_data["t"].copy()
    f = rig_data["rig"][:, 0].copy()
    names, time_fmt = ["time", "fl_N"], "{:.6f}"
    if kind == "nonuniform":
        t[5000:] += 0.0004
    elif kind == "backwards":
        t[100] = t[98]
    elif kind == "lowrate":
        t = t * 20.0  # 50 Hz
    p = tmp / f"{kind}.csv"
    write_csv(p, names, [t, f], time_fmt)
    text = p.read_text().splitlines()
    if kind == "nan":
        text[1201] = text[1201].split(",")[0] + ",nan"
    elif kind == "text":
        text[7] = text[7].split(",")[0] + ",12kN"
    elif kind == "short_row":
        text[9] = text[9].split(",")[0]
    elif kind == "no_time":
        text[0] = "tick,fl_N"
    elif kind == "short_record":
        text = text[:1500]
    p.write_text("\n".join(text) + "\n")
    return p


@pytest.mark.parametrize("kind, extra, message", [
    ("nonuniform", [], r"column 'time' is not uniform at line 5002"),
    ("backwards", [], r"column 'time' does not increase at line 102"),
    ("nan", [], r"column 'fl_N' has 'nan' at line 1202"),
    ("text", [], r"column 'fl_N' is not numeric at line 8 \('12kN'\)"),
    ("short_row", [], r"line 10 .* has 1 fields but the header has 2"),
    ("no_time", [], r"has no time column \(named time, t, zeit"),
    ("lowrate", [], r"sampling rate 50 Hz is too low"),
    ("short_record", [], r"not longer than the correction's transients"),
    ("good", ["--columns", "fl_N,rl_N"], r"channel 'rl_N' is not a column of .*; its columns are time, fl_N, fr_N"),
    ("good", ["--columns", "time"], r"channel 'time' is the time column"),
    ("good", ["--time-col", "fl_N", "--columns", "fr_N"], r"time column 'fl_N' .* is in 'N', not a unit of time"),
    ("good", ["--time-col", "zeit"], r"time column 'zeit' is not a column of"),
])
def test_bad_input_exits_2_and_writes_nothing(files, rig_data, kind, extra, message):
    csv, act, tmp = files
    if kind != "good":
        csv = _bad_csv(tmp, rig_data, kind)
    out = tmp / "out.csv"
    assert run([csv, "--actuator", act, "-o", out, *extra]) == 2
    assert __import__("re").search(message, run.last_error), run.last_error
    assert nothing_written(tmp, out)


@pytest.mark.parametrize("actuator, message", [
    ("[transfer_function]\nnum = [1.0]\nden = [1.0, -1.0]\n", "T_a is unstable"),
    ("[transfer_function]\nnum = [-1.0, 1.0]\nden = [0.001, 0.1, 1.0]\n", "T_a is non-minimum-phase"),
    ("[transfer_function]\nnum = [2.0]\nden = [0.001, 0.1, 1.0]\n", r"T_a\(0\) = 2.*pass --normalize-dc"),
    ("[transfer_funtion]\nnum = [1.0]\nden = [1.0, 1.0]\n", "did you mean 'transfer_function'"),
    ("[transfer_function\n", "is not valid TOML"),
])
def test_bad_actuator_exits_2_and_writes_nothing(files, actuator, message):
    csv, _, tmp = files
    act = tmp / "bad.toml"
    act.write_text(actuator)
    out = tmp / "out.csv"
    assert run([csv, "--actuator", act, "-o", out]) == 2
    assert __import__("re").search(message, run.last_error), run.last_error
    assert nothing_written(tmp, out)


def test_option_errors_exit_2(files):
    csv, act, tmp = files
    out = tmp / "out.csv"
    cases = [([csv, "-o", out], "exactly one of --actuator"),
             ([csv, "--actuator", act, "--identify", "fl_N,fr_N", "-o", out], "exactly one of --actuator"),
             ([csv, "--actuator", act, "--actuators", act, "-o", out], "exactly one of --actuator"),
             ([csv, "--actuator", act, "--map", "fl=fl_N", "-o", out], "use it with --actuators"),
             ([csv, "--identify", "fl_N", "-o", out], "needs two columns"),
             ([csv, "--identify", "fl_N,pan", "-o", out], "column 'pan' is not in"),
             ([tmp / "missing.csv", "--actuator", act, "-o", out], "does not exist"),
             ([csv, "--actuator", tmp / "missing.toml", "-o", out], "does not exist")]
    for argv, message in cases:
        assert run(argv) == 2, argv
        assert message in run.last_error, run.last_error
        assert nothing_written(tmp, out)


def test_an_existing_output_survives_a_failed_run(files, rig_data):
    csv, act, tmp = files
    out = tmp / "out.csv"
    out.write_text("previous\n")
    bad = _bad_csv(tmp, rig_data, "nan")
    assert run([bad, "--actuator", act, "-o", out]) == 2
    assert out.read_text() == "previous\n"
    assert math.isfinite(read_csv(csv)["fl_N"][0])


# ---------------------------------------------------------------- four corners: --actuators, --map, output names

FOUR = ("time", "tire_force_fl_N", "Fz_FR", "rl-load", "force_RR_N")


@pytest.fixture(scope="module")
def four_wheels():
    """Four wheels, each rig force through its own eq. 4 (four tire stiffnesses), simulated with scipy."""
    rng = np.random.default_rng(7)
    n = int(20 * FS)
    t = np.arange(n) / FS
    bp = signal.butter(4, [0.5, 20.0], "bandpass", fs=FS, output="sos")
    fade = np.clip(t / 2, 0, 1)
    tas = [eq4_coefficients_from(**dict(EQ4_VALUES, tire_N_per_m=kt)) for kt in (1.0e6, 1.3e6, 0.7e6, 1.6e6)]
    road = np.stack([29e3 + 4e3 * fade * signal.sosfilt(bp, rng.standard_normal(n)) / 0.3 for _ in range(4)], axis=1)
    rig = np.stack([signal.lsim(ta, road[:, i] - road[0, i], t)[1] + road[0, i] for i, ta in enumerate(tas)], axis=1)
    return dict(t=t, road=road, rig=rig, tas=tas)


def _four_files(tmp, d, corners=("fl", "fr", "rl", "rr")):
    from rigsim.correction.io.actuator_file import write_actuators_file

    csv = tmp / "rig4.csv"
    write_csv(csv, list(FOUR), [d["t"]] + [d["rig"][:, i] for i in range(4)])
    acts = tmp / "actuators.toml"
    write_actuators_file(acts, dict(zip(corners, d["tas"])), meta={"source": "test"})
    return csv, acts


def test_actuators_file_corrects_each_corner_with_its_own_t_a_and_prints_the_dlc(tmp_path, four_wheels, capsys):
    d = four_wheels
    csv, acts = _four_files(tmp_path, d)
    out = tmp_path / "o.csv"
    assert run([csv, "--actuators", acts, "-o", out]) == 0
    assert header(out) == ",".join(("time [s]",) + tuple(f"{c}_corrected [N]" for c in FOUR[1:]))
    got = read_csv(out)
    n = d["t"].size
    filts = [design_correction(ta, FS, "regularized") for ta in d["tas"]]
    from rigsim.correction.output.filters import reference_filter

    mask = reference_filter(FS, "regularized").transient_mask(n, "zerophase")
    mask &= np.logical_and.reduce([f.transient_mask(n, "zerophase") for f in filts])
    np.testing.assert_allclose(got["time"], d["t"][mask], atol=1e-9)
    ref = band_limit(d["road"], FS, "regularized", "zerophase")[mask]
    for i, (col, filt) in enumerate(zip(FOUR[1:], filts)):
        direct = correct(d["rig"][:, i], filt, "zerophase")[mask]
        np.testing.assert_allclose(got[f"{col}_corrected"], direct, rtol=1e-9)
        assert np.sqrt(np.mean((got[f"{col}_corrected"] - ref[:, i]) ** 2)) / ref[:, i].std() < 5e-3
    # the table: DLC = std / mean of the raw and of the corrected force on the settled rows
    text = capsys.readouterr().out
    for i, col in enumerate(FOUR[1:]):
        raw = d["rig"][mask, i]
        cor = got[f"{col}_corrected"]
        line = next(ln for ln in text.splitlines() if ln.startswith(col + " "))
        before, after, change, sf_before, sf_after = line.split()[1:6]
        # stress factor E[(F/F_static)^4] with F_static the mean (rigsim.correction.metrics.damage), worked here directly
        assert float(sf_before) == pytest.approx(np.mean((np.maximum(raw, 0) / raw.mean()) ** 4), abs=6e-5)
        assert float(sf_after) == pytest.approx(np.mean((np.maximum(cor, 0) / cor.mean()) ** 4), abs=6e-5)
        assert float(before) == pytest.approx(raw.std() / raw.mean(), abs=6e-5)
        assert float(after) == pytest.approx(cor.std() / cor.mean(), abs=6e-5)
        assert float(change.rstrip("%")) == pytest.approx(100 * (cor.std() / cor.mean() / (raw.std() / raw.mean()) - 1),
                                                          abs=0.06)
        assert float(after) > float(before)  # the rig attenuates; the correction restores


def test_map_and_columns_choose_what_is_corrected(tmp_path, four_wheels):
    d = four_wheels
    csv, acts = _four_files(tmp_path, d, corners=("front_left", "b", "c", "d"))
    out = tmp_path / "o.csv"
    # explicit map: only the mapped columns, each with its corner's T_a
    assert run([csv, "--actuators", acts, "--map", "front_left=Fz_FR,d=rl-load", "-o", out, "--transient", "keep"]) == 0
    assert header(out) == "time [s],Fz_FR_corrected [N],rl-load_corrected [N]"
    got = read_csv(out)
    np.testing.assert_allclose(got["Fz_FR_corrected"],
                               correct(d["rig"][:, 1], design_correction(d["tas"][0], FS, "regularized"), "zerophase"),
                               rtol=1e-9)
    # --columns restricts the automatic mapping
    csv, acts = _four_files(tmp_path, d)
    assert run([csv, "--actuators", acts, "--columns", "force_RR_N", "-o", out, "--transient", "keep", "--force"]) == 0
    got = read_csv(out)
    assert got.dtype.names == ("time", "force_RR_N_corrected")
    np.testing.assert_allclose(got["force_RR_N_corrected"],
                               correct(d["rig"][:, 3], design_correction(d["tas"][3], FS, "regularized"), "zerophase"),
                               rtol=1e-9)


@pytest.mark.parametrize("corners, extra, message", [
    (("fl", "fr", "rl", "xx"), [], r"corner 'xx' of the actuator file matches no column of the input; fix: --map xx=COLUMN"),
    (("fl", "fr", "rl", "force"), [], r"corner 'force' .* matches several columns \(tire_force_fl_N, force_RR_N\)"),
    (("fl", "fr", "rl", "rr"), ["--columns", "time"], "is the time column"),
    (("fl", "fr", "rl", "rr"), ["--map", "fl=nope"], "channel 'nope' is not a column of"),
    (("fl", "fr", "rl", "rr"), ["--map", "xx=Fz_FR"], "--map names corner 'xx', which is not in the actuator file"),
    (("fl", "fr", "rl", "rr"), ["--map", "fl=Fz_FR,fr=Fz_FR"], "column 'Fz_FR' is mapped to several corners"),
    (("fl", "fr", "rl", "rr"), ["--map", "fl"], "must be CORNER=COLUMN"),
    (("fl", "fr", "rl", "rr"), ["--map", "fl=Fz_FR", "--columns", "RR"], "channel 'RR' is not a column of"),
    (("fl", "fr", "rl", "rr"), ["--map", "fl=Fz_FR", "--columns", "Fz_FR,force_RR_N"],
     "column 'force_RR_N' is not mapped to a corner; fix: add CORNER=force_RR_N to --map"),
    (("fl", "fr", "rl", "x"), ["--columns", "Fz_FR,rl-load,force_RR_N"], r"column 'force_RR_N' names no corner"),
    (("fl", "fr", "rl", "rr"), ["--columns", "Fz_FR,Fz_FR"], "names a column twice"),
])
def test_mapping_errors_name_the_corner_and_the_fix(tmp_path, four_wheels, corners, extra, message):
    csv, acts = _four_files(tmp_path, four_wheels, corners)
    out = tmp_path / "o.csv"
    assert run([csv, "--actuators", acts, "-o", out, *extra]) == 2
    assert __import__("re").search(message, run.last_error), run.last_error
    assert not out.exists()


def test_a_refused_corner_is_named(tmp_path, four_wheels):
    from rigsim.correction.io.actuator_file import write_actuators_file

    csv, acts = _four_files(tmp_path, four_wheels)
    tas = dict(zip(("fl", "fr", "rl", "rr"), four_wheels["tas"]))
    tas["rl"] = ([-1.0, 1.0], [0.001, 0.1, 1.0])
    write_actuators_file(acts, tas)
    out = tmp_path / "o.csv"
    assert run([csv, "--actuators", acts, "-o", out]) == 2
    assert run.last_error.startswith("corner 'rl' (column 'rl-load'): T_a is non-minimum-phase"), run.last_error


def test_output_equal_to_an_input_is_refused_before_any_work(files, tmp_path):
    import os

    csv, act, tmp = files
    digest = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (csv, act)}
    for out in (csv, tmp / "." / csv.name, act):
        for force in ([], ["--force"]):  # --force never makes an input writable
            assert run([csv, "--actuator", act, "-o", out, *force]) == 2
            assert "is the input file" in run.last_error, run.last_error
    link = tmp / "link.csv"
    os.link(csv, link)  # the same file under another name
    assert run([csv, "--actuator", act, "-o", link, "--force"]) == 2
    assert run([tmp / "missing.csv", "--actuator", act, "-o", tmp / "missing.csv"]) == 2
    assert "is the input file" in run.last_error  # before the input is even read
    assert {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (csv, act)} == digest


def test_identify_accepts_an_actuator_whose_data_are_not_minimum_phase(tmp_path, rig_data):
    """Drive -> pan through eq. 4 times an all-pass (a right-half-plane zero at 20 Hz): a fit that
    keeps that zero in the right half-plane (orders 1/4, no clean-up) would be refused by the command
    ("non-minimum-phase ... refit"); the fit is the minimum-phase counterpart (eq. 4 itself)."""
    d = rig_data
    a = 2 * math.pi * 20.0
    num, den = np.polymul(d["num"], [-1.0 / a, 1.0]), np.polymul(d["den"], [1.0 / a, 1.0])
    pan = signal.lsim((num, den), d["drive"], d["t"])[1]
    csv = tmp_path / "rig.csv"
    write_csv(csv, ["time", "drive_m", "pan_m", "fl_N"], [d["t"], d["drive"], pan, d["rig"][:, 0]])
    out = tmp_path / "o.csv"
    assert run([csv, "--identify", "drive_m,pan_m", "-o", out]) == 0, run.last_error
    got = read_csv(out)
    filt = design_correction((d["num"], d["den"]), FS, "regularized")
    mask = filt.transient_mask(d["t"].size, "zerophase")
    known = correct(d["rig"][:, 0], filt, "zerophase")
    t_out = np.round(got["time"] * FS).astype(int)
    both = np.intersect1d(t_out, np.flatnonzero(mask))
    assert both.size > 0.3 * d["t"].size
    sel = np.isin(t_out, both)
    dyn = known[both] - known[both].mean()
    assert np.sqrt(np.mean((got["fl_N_corrected"][sel] - known[both]) ** 2)) / dyn.std() < 0.02


# ---------------------------------------------------------------- real rig files: any format in, any format out, SI


def _daq_csv(path, t, forces_N, disp_m):
    """A German DAQ export: '#' preamble, ';' and decimal comma, 'Zeit [s]', forces in kN, the LVDT
    in mm, a status text column."""
    lines = ["# Prüfstand: DYNTRAC", "# Messung: 2024-05-02 10:15", "",
             "Zeit [s];Fz_FL [kN];Fz_FR [kN];Weg_FL [mm];Status"]
    for i in range(t.size):
        values = (forces_N[i, 0] / 1e3, forces_N[i, 1] / 1e3, disp_m[i] * 1e3)
        row = [f"{t[i]:.4f}"] + [repr(float(v)) for v in values]
        lines.append(";".join(x.replace(".", ",") for x in row) + ";OK")
    path.write_text("\r\n".join(lines) + "\r\n", encoding="utf-8")
    return path


def test_a_kn_file_and_an_n_file_give_the_same_corrected_forces_in_n(files, rig_data):
    """The reader converts kN to N: the German kN file and the plain N file of the same forces give
    the same corrected forces (in N); the mm channel and the text column are not taken as forces."""
    csv, act, tmp = files
    daq = _daq_csv(tmp / "daq.csv", rig_data["t"], rig_data["rig"], rig_data["pan"])
    assert run([csv, "--actuator", act, "-o", tmp / "n.csv"]) == 0
    assert run([daq, "--actuator", act, "-o", tmp / "kn.csv"]) == 0
    n, kn = read_csv(tmp / "n.csv"), read_csv(tmp / "kn.csv")
    assert header(tmp / "kn.csv") == "time [s],Fz_FL_corrected [N],Fz_FR_corrected [N]"
    np.testing.assert_allclose(kn["time"], n["time"], atol=1e-12)
    for a, b in (("Fz_FL", "fl_N"), ("Fz_FR", "fr_N")):
        np.testing.assert_allclose(kn[f"{a}_corrected"], n[f"{b}_corrected"], rtol=1e-12, atol=1e-7)
        assert 25e3 < kn[f"{a}_corrected"].mean() < 35e3  # N, not kN
    # a length named as a force is refused, before anything is written
    assert run([daq, "--actuator", act, "--columns", "Fz_FL,Weg_FL", "-o", tmp / "x.csv"]) == 2
    assert "channel 'Weg_FL' is in mm, not a force" in run.last_error, run.last_error
    assert not (tmp / "x.csv").exists()


def test_actuators_map_the_corners_of_a_daq_file_and_the_output_records_how_it_was_made(files, rig_data):
    from rigsim.correction.io.actuator_file import write_actuators_file
    from rigsim.correction.io.measured import read_channels

    csv, act, tmp = files
    daq = _daq_csv(tmp / "daq.csv", rig_data["t"], rig_data["rig"], rig_data["pan"])
    acts = tmp / "acts.toml"
    write_actuators_file(acts, {"fl": (rig_data["num"], rig_data["den"]), "fr": (rig_data["num"], rig_data["den"])})
    # automatic: only force channels are candidates, so Weg_FL does not compete with Fz_FL for corner fl
    assert run([daq, "--actuators", acts, "-o", tmp / "auto.csv"]) == 0
    assert run([daq, "--actuators", acts, "--map", "fl=Fz_FL,fr=Fz_FR", "-o", tmp / "c.rsp"]) == 0
    auto = read_csv(tmp / "auto.csv")
    back = read_channels(tmp / "c.rsp")
    assert back.names == ("Fz_FL_corrected", "Fz_FR_corrected") and set(back.units.values()) == {"N"}
    np.testing.assert_allclose(back.time_s, auto["time"] - auto["time"][0], atol=1e-9)  # read from the first sample
    assert float(back.metadata["time_start_s"]) == pytest.approx(auto["time"][0], abs=1e-9)
    for name in back.names:  # int16 RPC III: within half a step of the exact values
        step = np.abs(auto[name]).max() / 32752
        assert np.abs(back.data[name] - auto[name]).max() <= 0.5 * step * (1 + 1e-9)
    meta = back.metadata
    assert meta["made_by"] == "rigsim correct" and meta["TIME_TYPE"] == "RESPONSE"
    assert meta["rigsim_version"] == version("rigsim")
    assert meta["input"].endswith("daq.csv") and meta["ta_source"].endswith("acts.toml")
    assert meta["corners"] == "fl=Fz_FL,fr=Fz_FR"
    assert meta["lowpass"] == "regularized: Butterworth order 6, 30 Hz"
    assert meta["mode"] == "zerophase" and meta["settling_tolerance"] == "0.001" and meta["transient"] == "drop"
    assert read_metadata(tmp / "auto.csv")["input"] == str(daq)  # the CSV keeps the whole path


def test_mdf4_output_reads_back_exactly(files):
    pytest.importorskip("asammdf")
    from rigsim.correction.io.measured import read_channels

    csv, act, tmp = files
    assert run([csv, "--actuator", act, "-o", tmp / "o.csv", "--lowpass", "paper", "--transient", "mark"]) == 0
    assert run([csv, "--actuator", act, "-o", tmp / "o.mf4", "--lowpass", "paper", "--transient", "mark"]) == 0
    ref, back = read_csv(tmp / "o.csv"), read_channels(tmp / "o.mf4")
    assert back.names == ("fl_N_corrected", "fr_N_corrected", "settled")
    for name in back.names:
        np.testing.assert_array_equal(back.data[name], ref[name])
    assert back.metadata["lowpass"].startswith("paper: 2 x 2nd order, 16/24 Hz")
    assert back.metadata["ta_source"] == str(act)


def test_an_rpc3_input_corrects_like_the_same_numbers_in_a_csv(files, rig_data):
    """RPC III in (forces in kN, int16): the command reads what read_channels reads and corrects it
    exactly as the same numbers (in N) from a CSV file."""
    from types import SimpleNamespace

    from rigsim.correction.io.measured import read_channels, write_channels

    csv, act, tmp = files
    rsp = tmp / "rig.rsp"
    write_channels(rsp, SimpleNamespace(time_s=rig_data["t"], data={"Fz_FL": rig_data["rig"][:, 0] / 1e3},
                                        units={"Fz_FL": "kN"}))
    mc = read_channels(rsp)
    assert mc.units["Fz_FL"] == "N"
    write_csv(tmp / "same.csv", ["time", "Fz_FL"], [mc.time_s, mc.data["Fz_FL"]])
    assert run([rsp, "--actuator", act, "-o", tmp / "a.csv"]) == 0
    assert run([tmp / "same.csv", "--actuator", act, "-o", tmp / "b.csv"]) == 0
    a, b = read_csv(tmp / "a.csv"), read_csv(tmp / "b.csv")
    np.testing.assert_allclose(a["time"], b["time"], atol=1e-9)
    np.testing.assert_allclose(a["Fz_FL_corrected"], b["Fz_FL_corrected"], rtol=1e-12)
    assert run([rsp, "--actuator", act, "--time-col", "t", "-o", tmp / "c.csv"]) == 2
    assert "has no time column" in run.last_error


def test_time_col_names_a_time_column_without_a_time_name(files, rig_data):
    csv, act, tmp = files
    p = tmp / "stamp.csv"
    write_csv(p, ["Stamp [ms]", "fl_N"], [rig_data["t"] * 1e3, rig_data["rig"][:, 0]], time_fmt="{:.3f}")
    assert run([p, "--actuator", act, "-o", tmp / "o.csv"]) == 2
    assert "has no time column" in run.last_error and "(time_col)" in run.last_error
    assert run([p, "--actuator", act, "--time-col", "Stamp", "-o", tmp / "o.csv"]) == 0
    assert run([csv, "--actuator", act, "--columns", "fl_N", "-o", tmp / "ref.csv"]) == 0
    got, ref = read_csv(tmp / "o.csv"), read_csv(tmp / "ref.csv")
    np.testing.assert_allclose(got["time"], ref["time"], atol=1e-9)  # ms read as s
    np.testing.assert_allclose(got["fl_N_corrected"], ref["fl_N_corrected"], rtol=1e-12)


def test_an_existing_output_needs_force(files):
    csv, act, tmp = files
    out = tmp / "out.csv"
    out.write_text("previous\n")
    assert run([csv, "--actuator", act, "-o", out]) == 2
    assert re.fullmatch(r"output '.*out\.csv' exists; pass --force to replace it", run.last_error), run.last_error
    assert out.read_text() == "previous\n" and not [p for p in tmp.iterdir() if p.name.startswith(".")]
    assert run([csv, "--actuator", act, "-o", out, "--force"]) == 0
    assert read_csv(out).dtype.names == ("time", "fl_N_corrected", "fr_N_corrected")


@pytest.mark.parametrize("out, message", [
    ("o.csv", r"cannot be written: channel name 'Fz\[1\]_corrected' cannot be written to CSV"),
    ("o.xlsx", r"has extension '\.xlsx'"),
])
def test_an_output_the_writer_would_refuse_is_refused_before_the_correction(files, rig_data, monkeypatch, out,
                                                                             message):
    from types import SimpleNamespace

    import rigsim.correction.output.pipeline
    from rigsim.correction.io.measured import write_channels

    csv, act, tmp = files
    rsp = tmp / "odd.rsp"  # RPC III allows brackets in a channel name; a CSV header does not
    write_channels(rsp, SimpleNamespace(time_s=rig_data["t"], data={"Fz[1]": rig_data["rig"][:, 0]}, units={}))
    monkeypatch.setattr(rigsim.correction.output.pipeline, "correct_forces", lambda *a, **k: pytest.fail("corrected"))
    assert run([rsp, "--actuator", act, "-o", tmp / out]) == 2
    assert re.search(message, run.last_error), run.last_error
    assert not (tmp / out).exists()
