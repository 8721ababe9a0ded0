"""``rigsim correct`` (scenarios/cli/correct.py): round trips and refusals.

The command is driven through an argparse parser built with its own ``add_parser`` and
``ScenarioError`` is turned into exit code 2 as the CLI does. Expected values: the rig force is
the road force through a known T_a simulated with ``scipy.signal.lsim``; the corrected output is
compared with the road force through the low-pass (the library's ``band_limit``, itself checked
against scipy in test_correction.py) and with the library called directly.

Deliberate change (one correction, issue of the four corners): corrected columns are written as
``<name>_corrected`` (``fl_N_corrected``), so they cannot be mistaken for raw ones.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest
from scipy import signal

from correction.apply import band_limit, correct
from correction.eq4 import eq4_coefficients_from
from correction.filters import design_correction
from scenarios.core.config import ScenarioError
from scenarios.cli.correct import add_parser, cmd_correct

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
    return np.genfromtxt(path, delimiter=",", names=True)


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
        text[0] = "t,fl_N"
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
    ("no_time", [], r"has no 'time' column"),
    ("lowrate", [], r"sampling rate 50 Hz is too low"),
    ("short_record", [], r"not longer than the correction's transients"),
    ("good", ["--columns", "fl_N,rl_N"], r"column 'rl_N' is not in"),
    ("good", ["--columns", "time"], r"column 'time' is the time column"),
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
    from correction.actuator_file import write_actuators_file

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
    assert out.read_text().splitlines()[0] == ",".join(("time",) + tuple(f"{c}_corrected" for c in FOUR[1:]))
    got = dict(zip(("time",) + tuple(f"{c}_corrected" for c in FOUR[1:]), np.loadtxt(out, delimiter=",", skiprows=1).T))
    n = d["t"].size
    filts = [design_correction(ta, FS, "regularized") for ta in d["tas"]]
    from correction.filters import reference_filter

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
        # stress factor E[(F/F_static)^4] with F_static the mean (correction.damage), worked here directly
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
    assert out.read_text().splitlines()[0] == "time,Fz_FR_corrected,rl-load_corrected"
    got = read_csv(out)
    np.testing.assert_allclose(got["Fz_FR_corrected"],
                               correct(d["rig"][:, 1], design_correction(d["tas"][0], FS, "regularized"), "zerophase"),
                               rtol=1e-9)
    # --columns restricts the automatic mapping
    csv, acts = _four_files(tmp_path, d)
    assert run([csv, "--actuators", acts, "--columns", "force_RR_N", "-o", out, "--transient", "keep"]) == 0
    got = read_csv(out)
    assert got.dtype.names == ("time", "force_RR_N_corrected")
    np.testing.assert_allclose(got["force_RR_N_corrected"],
                               correct(d["rig"][:, 3], design_correction(d["tas"][3], FS, "regularized"), "zerophase"),
                               rtol=1e-9)


@pytest.mark.parametrize("corners, extra, message", [
    (("fl", "fr", "rl", "xx"), [], r"corner 'xx' of the actuator file matches no column of the input; fix: --map xx=COLUMN"),
    (("fl", "fr", "rl", "force"), [], r"corner 'force' .* matches several columns \(tire_force_fl_N, force_RR_N\)"),
    (("fl", "fr", "rl", "rr"), ["--columns", "time"], "is the time column"),
    (("fl", "fr", "rl", "rr"), ["--map", "fl=nope"], "--map names column 'nope', which is not in the input"),
    (("fl", "fr", "rl", "rr"), ["--map", "xx=Fz_FR"], "--map names corner 'xx', which is not in the actuator file"),
    (("fl", "fr", "rl", "rr"), ["--map", "fl=Fz_FR,fr=Fz_FR"], "column 'Fz_FR' is mapped to several corners"),
    (("fl", "fr", "rl", "rr"), ["--map", "fl"], "must be CORNER=COLUMN"),
    (("fl", "fr", "rl", "rr"), ["--map", "fl=Fz_FR", "--columns", "RR"], "column 'RR' is not in"),
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
    from correction.actuator_file import write_actuators_file

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
    before = csv.read_bytes()
    for out in (csv, tmp / "." / csv.name, act):
        assert run([csv, "--actuator", act, "-o", out]) == 2
        assert "is the input file" in run.last_error, run.last_error
    link = tmp / "link.csv"
    os.link(csv, link)  # the same file under another name
    assert run([csv, "--actuator", act, "-o", link]) == 2
    assert run([tmp / "missing.csv", "--actuator", act, "-o", tmp / "missing.csv"]) == 2
    assert "is the input file" in run.last_error  # before the input is even read
    assert csv.read_bytes() == before and act.exists()


def test_identify_accepts_an_actuator_whose_data_are_not_minimum_phase(tmp_path, rig_data):
    """Drive -> pan through eq. 4 times an all-pass (a right-half-plane zero at 20 Hz): the former fit
    (orders 1/4, no clean-up) came back with its zero in the right half-plane and the command refused
    it ("non-minimum-phase ... refit"). Now the fit is the minimum-phase counterpart (eq. 4 itself)."""
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
