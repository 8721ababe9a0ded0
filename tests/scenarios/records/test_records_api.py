"""The records API (scenarios/records/api.py): a lab's script corrects a record in three lines.

    record = read_record(path); result = correct_record(record, LinearOptions(...)); result.write(out)

Expected values:

* ``rigsim correct`` on the same input and options: the API's file must be the command's, byte for
  byte (linear), and the model correction's values and metadata the command's (the truck model's
  calibration, deterministic and ~20 s, is run once: the second run's calibration must receive
  exactly the first's inputs, and gets its result);
* the 6th-order Butterworth's magnitude from ``scipy.signal.butter``/``freqs`` and T_a's from its
  coefficients, against the corrected force's frequency response estimated from the data (H1):
  ``lowpass_hz`` must move the -3 dB point of ``|corrected / measured| |T_a|`` to itself;
* the per-corner identification against ``rigsim identify --from-file``'s ``actuators.toml``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re

import numpy as np
import pytest
from scipy import signal

from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.correction.output.lowpass import BAND_HZ
from rigsim.scenarios.cli.main import main
from rigsim.scenarios.core.config import ScenarioError
from rigsim import LinearOptions, ModelOptions, correct_record, identify_record, read_record

EQ4_VALUES = dict(ksv=1.0, kq_m3_s=0.0109, kc_m3_s_Pa=1.26e-11, kp_per_m=50.0, kdp_per_Pa=2.0e-8,
                  piston_area_m2=7.43e-3, fluid_volume_m3=2.13e-3, bulk_modulus_Pa=1.0e9, mass_kg=500.0,
                  damping_N_s_m=5.0e3, tire_N_per_m=1.0e6)
FS = 1000.0
NAMES = ("time", "tire_force_fl_N", "Fz_FR", "rl-load", "force_RR_N", "drive_m", "pan_m")


def _write_csv(path, names, columns) -> None:
    rows = [",".join(names)] + [",".join(repr(float(v)) for v in row) for row in zip(*columns)]
    path.write_text("\n".join(rows) + "\n")



@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """Four wheels, each rig force the road force through its own eq. 4 (scipy), a random drive and
    the pan through the first T_a; the per-corner and the one-T_a actuator files."""
    from rigsim.correction.io.actuator_file import write_actuators_file

    d = tmp_path_factory.mktemp("rig")
    rng = np.random.default_rng(42)
    n = int(12 * FS)
    t = np.arange(n) / FS
    tas = [eq4_coefficients_from(**dict(EQ4_VALUES, tire_N_per_m=kt)) for kt in (1.0e6, 1.3e6, 0.7e6, 1.6e6)]
    bp = signal.butter(4, [0.5, 20.0], "bandpass", fs=FS, output="sos")
    road = np.stack([29e3 + 4e3 * signal.sosfilt(bp, rng.standard_normal(n)) / 0.3 for _ in range(4)], axis=1)
    forces = [signal.lsim(ta, road[:, i] - road[0, i], t)[1] + road[0, i] for i, ta in enumerate(tas)]
    drive = 0.01 * signal.sosfilt(signal.butter(4, [0.3, 40.0], "bandpass", fs=FS, output="sos"),
                                  rng.standard_normal(n))
    _write_csv(d / "rig.csv", NAMES, [t, *forces, drive, signal.lsim(tas[0], drive, t)[1]])
    write_actuators_file(d / "acts.toml", dict(zip(("fl", "fr", "rl", "rr"), tas)), meta={"source": "test"})
    num, den = tas[0]
    (d / "act.toml").write_text("[transfer_function]\nnum = [%s]\nden = [%s]\n" % (
        ", ".join(map(repr, map(float, num))), ", ".join(map(repr, map(float, den)))))
    return d


CASES = {  # CLI flags -> the same as LinearOptions' fields and correct_record's keywords
    "per_corner": (["--actuators", "{d}/acts.toml"], dict(actuators="{d}/acts.toml"), {}),
    "one_ta_paper_causal_mark": (["--actuator", "{d}/act.toml", "--columns", "Fz_FR,rl-load", "--lowpass", "paper",
                                  "--mode", "causal", "--transient", "mark"],
                                 dict(actuator="{d}/act.toml", lowpass="paper", mode="causal"),
                                 dict(columns=["Fz_FR", "rl-load"], transient="mark")),
    "identified_keep_25hz": (["--identify", "drive_m,PAN_M", "--columns", "Fz_FR", "--transient", "keep",
                              "--lowpass-hz", "25"],
                             dict(identify=("drive_m", "PAN_M"), lowpass_hz=25.0), dict(columns="Fz_FR", transient="keep")),
    "map": (["--actuators", "{d}/acts.toml", "--map", "fl=Fz_FR,rr=RL-LOAD"],
            dict(actuators="{d}/acts.toml"), dict(corner_map={"fl": "Fz_FR", "rr": "RL-LOAD"})),
}


def _fill(value, d):
    return value.replace("{d}", str(d)) if isinstance(value, str) else value


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_three_lines_write_the_file_rigsim_correct_writes(rig, case, tmp_path, capsys):
    flags, fields, keywords = CASES[case]
    src = str(rig / "rig.csv")
    assert main(["correct", src, *[_fill(f, rig) for f in flags], "-o", str(tmp_path / "cli.csv")]) == 0
    printed = capsys.readouterr().out

    record = read_record(src)
    options = LinearOptions(**{k: _fill(v, rig) for k, v in fields.items()})
    result = correct_record(record, options, **{k: _fill(v, rig) for k, v in keywords.items()})
    result.write(tmp_path / "api.csv")

    assert (tmp_path / "api.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    assert result.table() in printed and result.description in printed
    assert result.method == "linear" and result.reason == "" and result.corrected_N.shape == (12000, len(result.channels))
    # the comparison can fail: another corner gives another file
    change = {"lowpass_hz": 24.0} if options.lowpass == "regularized" else {"mode": "zerophase"}
    other = correct_record(record, dataclasses.replace(options, **change),
                           **{k: _fill(v, rig) for k, v in keywords.items()})
    other.write(tmp_path / "other.csv")
    assert (tmp_path / "other.csv").read_bytes() != (tmp_path / "cli.csv").read_bytes()


def test_the_result_holds_the_loads_as_data_and_refuses_to_overwrite(rig, tmp_path):
    result = correct_record(read_record(rig / "rig.csv"), LinearOptions(actuators=str(rig / "acts.toml")))
    assert result.channels == ("tire_force_fl_N", "Fz_FR", "rl-load", "force_RR_N")
    assert result.corners == ("fl", "fr", "rl", "rr") and result.fs_hz == FS
    s = result.settled
    for j, row in enumerate(result.loads):  # DLC = std / mean on the settled samples, worked here directly
        before, after = result.measured_N[s, j], result.corrected_N[s, j]
        assert row.dlc_before == pytest.approx(before.std() / before.mean(), rel=1e-12)
        assert row.dlc_after == pytest.approx(after.std() / after.mean(), rel=1e-12)
        assert row.change == pytest.approx(row.dlc_after / row.dlc_before - 1.0)
    result.write(tmp_path / "o.csv")
    with pytest.raises(ScenarioError, match="exists; pass --force .overwrite=True. to replace it"):
        result.write(tmp_path / "o.csv")
    result.write(tmp_path / "o.csv", overwrite=True)
    with pytest.raises(ScenarioError, match="is the input file"):
        result.write(rig / "rig.csv", overwrite=True)


def test_messages_name_the_keywords(rig):
    record = read_record(rig / "rig.csv")
    with pytest.raises(ScenarioError, match=r"^give exactly one of actuator='ACT.toml', actuators='ACTS.toml' and "):
        correct_record(record, LinearOptions())
    with pytest.raises(ScenarioError, match=r"^corner_map maps corners of a per-corner file: use it with actuators="):
        correct_record(record, LinearOptions(actuator=str(rig / "act.toml")), corner_map={"fl": "Fz_FR"})
    with pytest.raises(ScenarioError, match=r"^lowpass_hz must be a finite number of Hz > 0, got nan$"):
        correct_record(record, LinearOptions(actuator=str(rig / "act.toml"), lowpass_hz=math.nan))
    with pytest.raises(ScenarioError, match=r"fix: corner_map='xx=COLUMN'"):
        correct_record(record, LinearOptions(actuators={"fl": ([1.0], [1.0]), "xx": ([1.0], [1.0])}))
    with pytest.raises(ScenarioError, match=r"^options must be rigsim.LinearOptions\(actuators=...\) .*got 'acts.toml'"):
        correct_record(record, "acts.toml")
    with pytest.raises(ScenarioError, match=r"^linear must be a rigsim.LinearOptions .*got 'acts.toml'"):
        correct_record(record, ModelOptions("truck.toml", pairs="fl=a:b", linear="acts.toml"))


@pytest.fixture(scope="module")
def white(tmp_path_factory):
    """40 s of a force with a white dynamic part (2 kN rms on 30 kN), and eq. 4's T_a."""
    d = tmp_path_factory.mktemp("white")
    n = int(40 * FS)
    force = 30e3 + 2e3 * np.random.default_rng(5).standard_normal(n)
    _write_csv(d / "white.csv", ("time", "Fz_FL"), [np.arange(n) / FS, force])
    return read_record(d / "white.csv"), eq4_coefficients_from(**EQ4_VALUES)


def _corner_of(result, ta) -> tuple[np.ndarray, np.ndarray]:
    """(f, |corrected/measured| |T_a|) by H1 on the settled samples: the low-pass's magnitude."""
    s = result.settled
    f, pxy = signal.csd(result.measured_N[s, 0], result.corrected_N[s, 0], fs=FS, nperseg=4096)
    _, pxx = signal.welch(result.measured_N[s, 0], fs=FS, nperseg=4096)
    num, den = ta
    jw = 2j * np.pi * f
    return f, np.abs(pxy / pxx) * np.abs(np.polyval(num, jw) / np.polyval(den, jw))


@pytest.mark.parametrize("corner_hz", [None, 18.0, 40.0])
def test_lowpass_hz_is_the_butterworth_corner_of_the_correction(white, corner_hz):
    record, ta = white
    result = correct_record(record, LinearOptions(actuator=ta, lowpass_hz=corner_hz), transient="keep")
    f, got = _corner_of(result, ta)
    fc = BAND_HZ if corner_hz is None else corner_hz
    _, butter = signal.freqs(*signal.butter(6, 2 * np.pi * fc, analog=True), worN=2 * np.pi * f)
    band = (f > 1.0) & (f < 2.0 * fc)
    np.testing.assert_allclose(got[band], np.abs(butter[band]), atol=0.01)
    below = np.flatnonzero(got < 1 / math.sqrt(2))  # the -3 dB point, interpolated
    k = below[below > 10][0]
    f3 = np.interp(1 / math.sqrt(2), [got[k], got[k - 1]], [f[k], f[k - 1]])
    assert f3 == pytest.approx(fc, abs=0.3)
    assert result.metadata["lowpass"] == f"regularized: Butterworth order 6, {fc:g} Hz"


@pytest.mark.parametrize("value, extra, expected", [
    ("nan", [], "--lowpass-hz must be a finite number of Hz > 0, got nan"),
    ("inf", [], "--lowpass-hz must be a finite number of Hz > 0, got inf"),
    ("0", [], "--lowpass-hz must be a finite number of Hz > 0, got 0.0"),
    ("-5", [], "--lowpass-hz must be a finite number of Hz > 0, got -5.0"),
    ("500", [], "--lowpass-hz 500 Hz is not below the Nyquist frequency of"),
    ("490", [], "fix: lower --lowpass-hz (490 Hz), or record or resample"),
    ("20", ["--lowpass", "paper"], "--lowpass-hz sets the corner of the regularized low-pass; the paper's"),
])
def test_bad_lowpass_hz_exits_2_inone_line(one_line, rig, tmp_path, capsys, value, extra, expected):
    out = tmp_path / "o.csv"
    argv = ["correct", str(rig / "rig.csv"), "--actuator", str(rig / "act.toml"), "-o", str(out), *extra]
    assert main(argv + [f"--lowpass-hz={value}"]) == 2
    line = one_line(capsys.readouterr().err)
    assert line.startswith("rigsim: error: ") and expected in line, line
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == []


def test_the_default_corner_given_writes_the_default_file(rig, tmp_path):
    base = ["correct", str(rig / "rig.csv"), "--actuator", str(rig / "act.toml")]
    assert main(base + ["-o", str(tmp_path / "a.csv")]) == 0
    assert main(base + ["-o", str(tmp_path / "b.csv"), "--lowpass-hz", f"{BAND_HZ:g}"]) == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_quiet_is_accepted_by_the_linear_correction(rig, tmp_path, capsys):
    base = ["correct", str(rig / "rig.csv"), "--actuators", str(rig / "acts.toml")]
    assert main(base + ["-o", str(tmp_path / "a.csv")]) == 0
    loud = capsys.readouterr()
    assert main(base + ["-o", str(tmp_path / "b.csv"), "--quiet"]) == 0
    quiet = capsys.readouterr()
    assert quiet.err == "" and quiet.out == loud.out.replace("a.csv", "b.csv")  # the result is printed
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_identify_record_gives_the_actuators_file_of_rigsim_identify(rig, tmp_path):
    from rigsim.correction.io.actuator_file import write_actuators_file

    src = str(rig / "rig.csv")
    assert main(["identify", "--from-file", src, "--pairs", "fl=drive_m:pan_m", "--out", str(tmp_path / "id"),
                 "--quiet"]) == 0
    ident = identify_record(read_record(src), pairs={"fl": ("drive_m", "pan_m")})
    write_actuators_file(tmp_path / "api.toml", ident.fits, meta=ident.meta())
    assert (tmp_path / "api.toml").read_bytes() == (tmp_path / "id" / "actuators.toml").read_bytes()
    with pytest.raises(ScenarioError, match=r"^pairs fl: channel 'tire_force_fl_N' is in N, not a length"):
        identify_record(read_record(src), pairs="fl=drive_m:tire_force_fl_N")


# ---------------------------------------------------------------- the model correction


@pytest.fixture(scope="module")
def truck_record(tmp_path_factory):
    """10.5 s of the paper's high-roughness 72 km/h case on the hydraulic rig, written as a lab's CSV
    (tests/scenarios/records/test_correct_model.py's layout), and a TRUCK.toml whose first guesses are the truck's own."""
    import dataclasses

    from test_correct_model import _write_csv as write_lab_csv

    from rigsim.scenarios.core.config import load_scenario, paper_scenarios
    from rigsim.scenarios.core.run import run

    sc = dataclasses.replace(load_scenario(paper_scenarios()[2]), duration_s=10.5)
    res = run(sc, "rig")
    force = res.signals["tire_force_N"] + np.random.default_rng(7).normal(0.0, 100.0,
                                                                         res.signals["tire_force_N"].shape)
    d = tmp_path_factory.mktemp("truck")
    write_lab_csv(d / "messung.csv", res.t_s, force, res.signals["profile_m"], res.signals["pan_m"])
    (d / "truck.toml").write_text(
        'name = "truck"\nspeed_kmh = 72.0\nduration_s = 10.0\n[road]\nroughness = "high"\n[vehicle]\n'
        "tire_stiffness_front_N_per_m = 9.0e5\ntire_stiffness_rear_N_per_m = 1.8e6\n"
        "tire_damping_front_Ns_per_m = 1500.0\ntire_damping_rear_Ns_per_m = 3000.0\n"
        "spring_friction_front_N = 1000.0\nspring_friction_rear_N = 2000.0\ntire_progressive_ratio = 0.0\n")
    return d


def test_the_model_correction_gives_the_values_of_rigsim_correct_model(truck_record, tmp_path, capsys, monkeypatch):
    from rigsim.scenarios.records.model import differential

    calls, real = [], differential.calibrate_truck

    def once(*args, **kw):  # the second calibration must get the first's inputs; it gets its result
        inputs = (args, {k: v for k, v in kw.items() if k not in ("executor", "defer")})  # callables made per call
        if calls:
            first, cal = calls[0]
            assert len(inputs[0]) == len(first[0]) and all(np.array_equal(a, b) for a, b in zip(inputs[0], first[0]))
            assert inputs[1].keys() == first[1].keys()
            for k, v in inputs[1].items():
                assert (np.array_equal(v, first[1][k]) if isinstance(v, np.ndarray) else v == first[1][k]), k
            return cal
        calls.append((inputs, real(*args, **kw)))
        return calls[0][1]

    monkeypatch.setattr(differential, "calibrate_truck", once)
    src, truck = str(truck_record / "messung.csv"), str(truck_record / "truck.toml")
    pairs = {c: (f"Soll_{c.upper()}", f"Weg_{c.upper()}") for c in ("fl", "fr", "rl", "rr")}
    assert main(["correct", src, "--model", truck, "--pairs", ",".join(f"{c}={d}:{x}" for c, (d, x) in pairs.items()),
                 "-o", str(tmp_path / "cli.csv"), "--calibration-windows", "1", "--cab", "held", "--jobs", "2",
                 "--transient", "mark"]) == 0
    printed, progress = capsys.readouterr()
    lines = []
    options = ModelOptions(truck, pairs=pairs, calibration_windows=1, cab="held", workers=2)
    result = correct_record(read_record(src), options, transient="mark", progress=lines.append)
    result.write(tmp_path / "api.csv")
    assert len(calls) == 1 and result.method == "model" and result.reason == ""
    assert (tmp_path / "api.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    got = read_record(tmp_path / "cli.csv")
    for j, c in enumerate(result.channels):
        np.testing.assert_allclose(got.data[f"{c}_corrected"], result.corrected_N[:, j], rtol=1e-9)
    assert result.table() in printed and result.calibration.table() in printed
    timeless = functools.partial(re.sub, r"in [0-9.]+ s", "in _ s")  # the lines state wall times
    assert timeless("\n".join(lines) + "\n") == timeless(progress)  # the progress lines go to stderr, the same
    assert result.metadata["cal_runs"].endswith(", converged")


def test_a_record_on_the_labs_clock_is_written_on_that_clock(rig, tmp_path):
    """A record whose time axis starts at 86 400 s (a day's clock) is read from 0 s (its start in
    ``time_start_s``); the corrected file's time is on the record's clock again: read back, its
    start is the lab's 86 400 s plus the samples the correction's transients dropped."""
    src = (rig / "rig.csv").read_text().splitlines()
    shifted = [src[0]] + [",".join([repr(float(line.split(",")[0]) + 86400.0), *line.split(",")[1:]])
                          for line in src[1:]]
    (tmp_path / "clock.csv").write_text("\n".join(shifted) + "\n")
    record = read_record(tmp_path / "clock.csv")
    assert record.time_s[0] == 0.0 and float(record.metadata["time_start_s"]) == 86400.0
    result = correct_record(record, LinearOptions(actuators=str(rig / "acts.toml")))
    assert result.time_start_s == 86400.0
    back = read_record(result.write(tmp_path / "out.csv"))
    first = result.time_s[result.settled][0]  # the file starts at the first settled sample
    assert float(back.metadata["time_start_s"]) == pytest.approx(86400.0 + first, abs=1e-9)
    plain = correct_record(read_record(rig / "rig.csv"), LinearOptions(actuators=str(rig / "acts.toml")))
    again = read_record(plain.write(tmp_path / "plain.csv"))
    assert plain.time_start_s == 0.0 and float(again.metadata["time_start_s"]) == pytest.approx(first, abs=1e-9)
    np.testing.assert_array_equal(back.array(), again.array())  # the same forces, on the other clock
