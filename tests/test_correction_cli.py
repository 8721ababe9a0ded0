"""``rigsim correct`` (scenarios/cli/correct.py): round trips and refusals.

The command is driven through an argparse parser built with its own ``add_parser`` and
``ScenarioError`` is turned into exit code 2 as the CLI does. Expected values: the rig force is
the road force through a known T_a simulated with ``scipy.signal.lsim``; the corrected output is
compared with the road force through the low-pass (the library's ``band_limit``, itself checked
against scipy in test_correction.py) and with the library called directly.
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
    assert got.dtype.names == ("time", "fl_N", "fr_N")
    filt = design_correction((rig_data["num"], rig_data["den"]), FS, lowpass)
    mask = filt.transient_mask(rig_data["t"].size, mode)
    np.testing.assert_allclose(got["time"], rig_data["t"][mask], atol=1e-9)
    ref = band_limit(rig_data["road"], FS, lowpass, mode)[mask]
    direct = correct(rig_data["rig"], filt, mode)[mask]
    for i, col in enumerate(("fl_N", "fr_N")):
        np.testing.assert_allclose(got[col], direct[:, i], rtol=1e-9)  # written to 10 digits
        dyn = ref[:, i] - ref[:, i].mean()
        assert np.sqrt(np.mean((got[col] - ref[:, i]) ** 2)) / dyn.std() < 5e-3  # fs 1 kHz: warping ~1e-3


def test_parameters_file_mark_option_and_selected_columns(files, rig_data):
    csv, _, tmp = files
    act = tmp / "par.toml"
    act.write_text("[parameters]\n" + "".join(f"{k} = {v!r}\n" for k, v in EQ4_VALUES.items()))
    out = tmp / "o.csv"
    assert run([csv, "--actuator", act, "-o", out, "--columns", "fr_N", "--transient", "mark",
                "--mode", "causal"]) == 0
    got = read_csv(out)
    assert got.dtype.names == ("time", "fr_N", "settled")
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
    assert got.dtype.names == ("time", "fl_N", "settled")
    filt = design_correction((d["num"], d["den"]), FS, "regularized")
    both = filt.transient_mask(d["t"].size, "zerophase") & got["settled"].astype(bool)
    assert both.sum() > 0.5 * both.size
    known = correct(d["rig"][:, 0], filt, "zerophase")[both]
    dyn = known - known.mean()
    assert np.sqrt(np.mean((got["fl_N"][both] - known) ** 2)) / dyn.std() < 0.02  # identified vs known T_a


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
