"""``rigsim identify --from-file``: T_a per corner from a recorded file of a real rig, and refusals.

Reference: eq. 4 (rigsim.correction.output.eq4) with a known parameter set simulated by scipy from independent
random drives stands in for the recorded rig; the command's actuators file must hold T_a whose
frequency response matches eq. 4's (the fit's own tests pin the fit more tightly).
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from scipy import signal

from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.scenarios.cli.main import main

EQ4 = dict(ksv=1.0, kq_m3_s=0.0111, kc_m3_s_Pa=2.0e-12, kp_per_m=50.0, kdp_per_Pa=2.0e-8, piston_area_m2=7.43e-3,
           fluid_volume_m3=2.13e-3, bulk_modulus_Pa=1.0e9, mass_kg=500.0, damping_N_s_m=5.0e3,
           tire_N_per_m=1.2e6, ti_s=1.0)
FS = 1000.0


def _signals(seconds=120.0, seed=3, corners=("fl", "fr", "rl", "rr")):
    """t (s) and per corner (drive, lvdt) in m: each its own random drive through eq. 4."""
    num, den = eq4_coefficients_from(**EQ4)
    bd, ad, _ = signal.cont2discrete((num, den), 1.0 / FS, method="foh")
    rng = np.random.default_rng(seed)
    n = int(seconds * FS)
    out = {}
    for c in corners:
        u = signal.sosfilt(signal.butter(4, 40.0, fs=FS, output="sos"), rng.standard_normal(n)) * 5e-3
        out[c] = (u, signal.lfilter(np.ravel(bd), ad, u))
    return np.arange(n) / FS, out, (num, den)


def _recording(path, seconds=120.0, seed=3):
    """time_s, drive_<c>_m, lvdt_<c>_m for four corners, and a force (N) the pairs must not name."""
    t, sig, (num, den) = _signals(seconds, seed)
    cols, names = [t], ["time_s"]
    for c, (u, x) in sig.items():
        cols += [u, x]
        names += [f"drive_{c}_m", f"lvdt_{c}_m"]
    cols.append(np.full(t.size, 30e3))
    names.append("force_fr_N")
    np.savetxt(path, np.column_stack(cols), delimiter=",", header=",".join(names), comments="", fmt="%.10g")
    return num, den


def _matches_eq4(doc, corners, num, den):
    f = np.geomspace(0.3, 30.0, 60)
    s = 2j * np.pi * f
    truth = np.polyval(num, s) / np.polyval(den, s)
    for c in corners:
        fit = np.polyval(doc[c]["num"], s) / np.polyval(doc[c]["den"], s)
        assert np.max(np.abs(20 * np.log10(np.abs(fit / truth)))) < 0.3, c
        assert np.max(np.abs(np.degrees(np.angle(fit / truth)))) < 3.0, c
        assert doc[c]["num"][-1] == pytest.approx(doc[c]["den"][-1], rel=1e-12)  # T_a(0) = 1


def test_from_file_writes_actuators_that_match_the_recorded_rig(tmp_path):
    rec = tmp_path / "rec.csv"
    num, den = _recording(rec)
    pairs = ",".join(f"{c}=drive_{c}_m:lvdt_{c}_m" for c in ("fl", "fr", "rl", "rr"))
    out = tmp_path / "ident"
    assert main(["identify", "--from-file", str(rec), "--pairs", pairs, "--out", str(out), "--quiet"]) == 0
    doc = tomllib.loads((out / "actuators.toml").read_text())
    assert (out / "bode.png").stat().st_size > 10_000 and (out / "identification.json").exists()
    _matches_eq4(doc, ("fl", "fr", "rl", "rr"), num, den)


def test_from_file_reads_a_daq_export_with_the_lvdt_in_mm(tmp_path):
    """Semicolon, decimal comma, 'Stamp [s]' (not a time name: --time-col), the drive in m and the
    LVDT in mm, a status text: the reader converts the LVDT to m. Unconverted, H would be 1000
    where the fit pins T_a(0) = 1, and the fit could not match eq. 4."""
    t, sig, (num, den) = _signals(seconds=120.0, seed=4, corners=("fl", "rr"))
    lines = ["# export: DAQ", "Stamp [s];Soll_FL [m];Weg_FL [mm];Soll_RR [m];Weg_RR [mm];Fz_FL [kN];Status"]
    for i in range(t.size):
        row = [t[i], sig["fl"][0][i], 1e3 * sig["fl"][1][i], sig["rr"][0][i], 1e3 * sig["rr"][1][i], 30.0]
        lines.append(";".join(f"{v:.10g}".replace(".", ",") for v in row) + ";OK")
    rec = tmp_path / "rec.csv"
    rec.write_text("\n".join(lines) + "\n")
    out = tmp_path / "ident"
    pairs = "fl=Soll_FL:Weg_FL,rr=soll_rr:weg_rr"  # names as read, without [unit]; a CSV header by case too
    base = ["identify", "--from-file", str(rec), "--pairs", pairs, "--out", str(out), "--quiet"]
    assert main(base) == 2  # 'Stamp' is no time name
    assert main(base + ["--time-col", "Stamp"]) == 0
    doc = tomllib.loads((out / "actuators.toml").read_text())
    assert sorted(k for k in doc if k != "meta") == ["fl", "rr"]
    assert doc["meta"]["pairs"] == {"fl": "Soll_FL:Weg_FL", "rr": "Soll_RR:Weg_RR"}
    _matches_eq4(doc, ("fl", "rr"), num, den)


@pytest.mark.parametrize("argv, message", [
    (["identify", "--out", "{out}"], "either a SCENARIO.toml"),
    (["identify", "{rec}", "--from-file", "{rec}", "--pairs", "fl=a:b", "--out", "{out}"], "exactly one"),
    (["identify", "--from-file", "{rec}", "--out", "{out}"], "--from-file needs --pairs"),
    (["identify", "--from-file", "{rec}", "--pairs", "fl=drive_fl_m", "--out", "{out}"], "CORNER=DRIVE_COL:LVDT_COL"),
    (["identify", "--from-file", "{rec}", "--pairs", "fl=drive_fl_m:nope", "--out", "{out}"],
     "channel 'nope' is not a column of"),
    (["identify", "--from-file", "{rec}", "--pairs", "fl=drive_fl_m:lvdt_fl_m", "--time-col", "drive_fr_m",
      "--out", "{out}"], "is in 'm', not a unit of time"),
    (["identify", "{rec}", "--time-col", "time_s", "--out", "{out}"], "--time-col goes with --from-file"),
    (["identify", "--from-file", "{rec}", "--pairs", "fl=drive_fl_m:lvdt_fl_m,fr=drive_fr_m:force_fr_N",
      "--out", "{out}"], "--pairs fr: channel 'force_fr_N' is in N, not a length"),
    (["identify", "--from-file", "{rec}", "--pairs", "fl=drive_fl_m:lvdt_fl_m,fl=drive_fr_m:lvdt_fr_m",
      "--out", "{out}"], "twice"),
])
def test_bad_input_is_refused_in_one_sentence_and_nothing_is_written(tmp_path, capsys, argv, message):
    rec = tmp_path / "rec.csv"
    _recording(rec, seconds=20.0)
    out = tmp_path / "ident"
    args = [a.format(rec=rec, out=out) for a in argv]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not out.exists()
