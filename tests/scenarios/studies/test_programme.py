"""rigsim programme: many records of one truck, one calibration, corrected side by side, resumable.

Expected values: the records are 10.5 s of the paper's high-roughness 72 km/h case on the
hydraulic rig, each on its own road section (seed) and with its own load-cell noise, as a lab's CSV
(tests/scenarios/records/test_saved_calibration.py's ``lab``), calibrated on one window with the
cab held. The programme's corrected forces are, record by record, those of ``rigsim correct
--model --calibration`` run on that record alone with the programme's calibration (the same
records API call; on the record calibrated on, whose file is the calibration's own, that call
refits the tire's progressive stiffening from its optimum, within 1e-3 of the forces' spread); a run resumed after a kill, and the same programme on a Dask cluster, write the
same bytes as one run through on the pool (nothing in the outputs depends on the run but the inputs).
"""

from __future__ import annotations

import dataclasses
import json
import shutil
import sys
from types import SimpleNamespace

import numpy as np
import pytest

from rigsim.correction.io.measured import read_channels
from rigsim.scenarios.cli.main import main

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1] / "records"))

PAIRS = "fl=Soll_FL:Weg_FL,fr=Soll_FR:Weg_FR,rl=Soll_RL:Weg_RL,rr=Soll_RR:Weg_RR"
NAMES = ("run1", "run2", "run3")
FAST = ["--calibration-windows", "1", "--cab", "held", "--quiet"]


def _files(folder) -> dict:
    """Every file's bytes below ``folder`` but the run's timings and the folder's marker."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name != "timings.csv" and not p.name.startswith(".")}


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """Three records (seeds 11, 12, 13; noise seeds 7, 8, 9), the truck file, and the programme run
    through on the pool into ``out`` (its files kept in ``reference``)."""
    from test_correct_model import _write_csv as write_lab_csv

    from rigsim.scenarios.core.config import load_scenario, paper_scenarios
    from rigsim.scenarios.core.run import run

    truck = paper_scenarios()[2]
    base = dataclasses.replace(load_scenario(truck), duration_s=10.5)
    d = tmp_path_factory.mktemp("programme")
    (d / "records").mkdir()
    for i, name in enumerate(NAMES):
        res = run(dataclasses.replace(base, seed=11 + i), "rig")
        force = res.signals["tire_force_N"] + np.random.default_rng(7 + i).normal(0.0, 100.0,
                                                                                  res.signals["tire_force_N"].shape)
        write_lab_csv(d / "records" / f"{name}.csv", res.t_s, force, res.signals["profile_m"], res.signals["pan_m"])
    records = [str(d / "records" / f"{n}.csv") for n in NAMES]
    argv = ["programme", *records, "--model", str(truck), "--pairs", PAIRS, *FAST]
    assert main([*argv, "--jobs", "2", "--out", str(d / "out")]) == 0
    shutil.copytree(d / "out", d / "reference")
    return SimpleNamespace(dir=d, records=records, truck=truck, argv=argv)


def test_one_calibration_and_the_forces_of_correct_alone(lab, tmp_path):
    out = lab.dir / "out"
    cals = sorted(p.name for p in out.glob("*.calibration.json"))
    assert cals == ["high_72kmh_3640kg.calibration.json"]
    report = json.loads((out / "programme.json").read_text())
    assert [r["calibration"] for r in report["records"]] == ["made", "held", "held"]
    assert report["corrected"] == 3 and report["failed"] == 0
    assert report["trucks"][0]["calibrated_on"] == "run1 (and run2, run3)"  # settings.CALIBRATE_ON
    for r in report["records"]:
        assert r["method"] == "model" and len(r["wheels"]) == 4
        assert all(w["model_error"] < 0.25 and w["dlc_after"] > 0 and w["del5_after_N"] > 0 for w in r["wheels"])
    md = (out / "programme.md").read_text()
    assert "| run2 | high_72kmh_3640kg | model | held |" in md and (out / "programme.png").stat().st_size > 1000
    for name, record in zip(NAMES, lab.records):
        alone = tmp_path / f"{name}.csv"
        argv = ["correct", record, "--model", str(lab.truck), "--pairs", PAIRS, *FAST, "--jobs", "1",
                "--calibration", str(out / cals[0]), "-o", str(alone)]
        assert main(argv) == 0
        got, ref = read_channels(out / f"{name}_corrected.csv"), read_channels(alone)
        assert got.names == ref.names
        np.testing.assert_array_equal(got.time_s, ref.time_s)
        for c in got.names:
            if name == NAMES[0]:  # the record calibrated on: the file refines the tire's stiffening once more
                spread = ref.data[c].std()
                assert np.abs(got.data[c] - ref.data[c]).max() <= 1e-3 * spread
            else:
                np.testing.assert_array_equal(got.data[c], ref.data[c])


def test_a_run_killed_mid_way_resumes_to_the_same_bytes(lab):
    """Killed after run2's file was written but before its report, and before run3: run2 and run3 are
    corrected again, run1 and the calibration are kept."""
    out = lab.dir / "out"
    (out / "records" / "run2.json").unlink()
    for p in (out / "run3_corrected.csv", out / "records" / "run3.json", out / "programme.json"):
        p.unlink()
    seen = []
    from rigsim.scenarios.core.pool import local_executor
    from rigsim.scenarios.studies.programme.run import run_programme
    from rigsim.scenarios.studies.programme.settings import from_flags

    programme = from_flags(lab.records, model=str(lab.truck), pairs=PAIRS, calibration_windows=1, cab="held")
    with local_executor(2) as ex:
        outcome = run_programme(programme, out, ex, progress=False, on_record=seen.append)
    assert outcome.skipped == 1 and sorted(r.name for r in seen) == ["run2", "run3"]
    assert _files(out) == _files(lab.dir / "reference")


def test_ctrl_c_leaves_a_report_and_the_same_command_finishes(lab, tmp_path):
    """Ctrl-C (KeyboardInterrupt) once run2 is reported: it reaches the caller, the report of what
    was done is written (run1 and run2), nothing half-written; the same call then corrects run3
    alone, and the folder holds the bytes of one run through."""
    from rigsim.scenarios.core.pool import local_executor
    from rigsim.scenarios.studies.programme.run import run_programme
    from rigsim.scenarios.studies.programme.settings import from_flags

    programme = from_flags(lab.records, model=str(lab.truck), pairs=PAIRS, calibration_windows=1, cab="held")
    out = tmp_path / "out"

    def interrupt(report):
        if report.name == "run2":
            raise KeyboardInterrupt

    with local_executor(1) as ex, pytest.raises(KeyboardInterrupt):
        run_programme(programme, out, ex, progress=False, on_record=interrupt)
    done = json.loads((out / "programme.json").read_text())
    assert [r["name"] for r in done["records"]] == ["run1", "run2"]
    assert not [p.name for p in out.rglob("*") if p.name.startswith(".") or p.suffix == ".tmp"]
    seen = []
    with local_executor(1) as ex:
        outcome = run_programme(programme, out, ex, progress=False, on_record=seen.append)
    assert outcome.skipped == 2 and [r.name for r in seen] == ["run3"]
    here = {k: v.replace(str(out).encode(), str(lab.dir / "out").encode()) for k, v in _files(out).items()}
    assert here == _files(lab.dir / "reference")  # the files name their folder: the reference's written in


def test_a_corrupt_record_is_reported_and_the_others_are_whole(lab, capsys):
    bad = lab.dir / "records" / "broken.csv"
    bad.write_text("time [s],Fz_FL [kN]\n0.0,1.0\n0.001,oops\n")
    argv = ["programme", lab.records[0], str(bad), *lab.records[1:], "--model", str(lab.truck), "--pairs", PAIRS,
            *FAST, "--jobs", "2", "--out", str(lab.dir / "out")]
    capsys.readouterr()
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "record broken (" in err and "1 of 4 records failed: broken" in err
    report = json.loads((lab.dir / "out" / "programme.json").read_text())
    assert [r["status"] for r in report["records"]] == ["corrected", "failed", "corrected", "corrected"]
    assert report["records"][1]["error"]
    ref = _files(lab.dir / "reference")
    now = _files(lab.dir / "out")
    for name in NAMES:
        assert now[f"{name}_corrected.csv"] == ref[f"{name}_corrected.csv"]
    assert not (lab.dir / "out" / "broken_corrected.csv").exists()
    bad.unlink()


@pytest.mark.parametrize("extra, named", [
    (["--jobs", "0"], "--jobs"),
    (["--scheduler", "http://127.0.0.1:8787"], "--scheduler"),
    (["--pairs", "fl=Soll_FL"], "--pairs"),
    (["--model", "/nonexistent/truck.toml"], "truck.toml"),
    (["--calibration-windows", "0"], "--calibration-windows"),
    (["--calibrate-on", "0"], "--calibrate-on"),
])
def test_bad_options_are_one_sentence_and_nothing_is_written(lab, tmp_path, capsys, extra, named):
    argv = ["programme", *lab.records, "--model", str(lab.truck), "--pairs", PAIRS, *FAST, "--out",
            str(tmp_path / "new"), *extra]
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and named in err, err
    assert not (tmp_path / "new").exists()


def test_no_records_or_a_missing_one_is_refused(lab, tmp_path, capsys):
    for argv in (["programme", "--model", str(lab.truck), "--pairs", PAIRS],
                 ["programme", str(tmp_path / "absent.csv"), "--model", str(lab.truck), "--pairs", PAIRS],
                 ["programme", lab.records[0], str(tmp_path / "x" / "run1.csv"), "--model", str(lab.truck),
                  "--pairs", PAIRS, "--programme", "p.toml"]):
        assert main([*argv, "--out", str(tmp_path / "new")]) == 2
        assert "\n" not in capsys.readouterr().err.strip()
    assert not (tmp_path / "new").exists()


def test_a_programme_file_names_records_and_trucks(lab, tmp_path):
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.studies.programme.settings import read_programme

    f = tmp_path / "p.toml"
    f.write_text(f'[trucks.loaded]\nmodel = "{lab.truck}"\npairs = "{PAIRS}"\ncab = "held"\n'
                 f'calibration_windows = 1\n\n[[records]]\npath = "{lab.dir / "records"}/run*.csv"\n')
    p = read_programme(f, "rsp")
    assert [e.output for e in p.records] == ["run1_corrected.rsp", "run2_corrected.rsp", "run3_corrected.rsp"]
    assert p.trucks[0].options().calibration_windows == 1 and p.trucks[0].options().workers == 1
    f.write_text(f.read_text().replace("cab =", "cabin ="))
    with pytest.raises(ScenarioError, match=r"\[trucks.loaded\].*cabin"):
        read_programme(f)


def test_the_truck_is_calibrated_on_its_first_records(lab, tmp_path):
    """--calibrate-on 2: one window of run1 and one of run2 fitted (the calibration names run2, each
    window's record numbered), run1 corrected with it as calibrated, run2 and run3 with it as saved."""
    from rigsim.scenarios.records.model.saved import read_calibration

    out = tmp_path / "two"
    assert main([*lab.argv, "--calibrate-on", "2", "--jobs", "2", "--out", str(out)]) == 0
    saved = read_calibration(out / "high_72kmh_3640kg.calibration.json")
    assert saved.record == lab.records[0] and saved.also == (lab.records[1],)
    assert saved.calibration.window_records == (0, 1)
    report = json.loads((out / "programme.json").read_text())
    assert [r["calibration"] for r in report["records"]] == ["made", "held", "held"]
    assert report["trucks"][0]["calibrated_on"] == "run1 (and run2)"
    one = read_calibration(lab.dir / "reference" / "high_72kmh_3640kg.calibration.json")
    assert saved.calibration.fitted != one.calibration.fitted  # another fit: windows of two records


def test_the_parser_formats_are_the_settings(lab):
    from rigsim.scenarios.studies.programme import command, settings

    assert command.FORMATS == settings.FORMATS
    parser = __import__("argparse").ArgumentParser()
    command.add_parser(parser.add_subparsers())
    sub = parser._subparsers._group_actions[0].choices["programme"]  # noqa: SLF001 - argparse's own
    help_of = {a.dest: a.help for a in sub._actions}  # noqa: SLF001
    assert f"(default {settings.CALIBRATE_ON})" in help_of["calibrate_on"]


def test_a_dask_cluster_writes_the_same_bytes(lab):
    """On a local Dask cluster, calibrated afresh, then killed after run2 (run3's files removed) and
    run again: the same files as on the pool, byte for byte (a correction's linear algebra runs on
    one BLAS thread wherever it runs)."""
    distributed = pytest.importorskip("distributed")
    out = lab.dir / "out"
    shutil.rmtree(out)
    argv = ["programme", *lab.records, "--model", str(lab.truck), "--pairs", PAIRS, *FAST, "--out", str(out)]
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, host="127.0.0.1",
                                  dashboard_address=None, silence_logs=50) as cluster:
        assert main([*argv, "--scheduler", cluster.scheduler_address]) == 0
        for p in (out / "run3_corrected.csv", out / "records" / "run3.json", out / "programme.json"):
            p.unlink()
        assert main([*argv, "--scheduler", cluster.scheduler_address]) == 0
    got, ref = _files(out), _files(lab.dir / "reference")
    assert sorted(got) == sorted(ref)
    assert got == ref
