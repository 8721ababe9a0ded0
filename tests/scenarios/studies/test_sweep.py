"""rigsim sweep: grid validation, one code path for the process pool and Dask, nothing lost.

The simulated sweeps are short (5 cases of 5 s records, one of them failing at its start; the
default scoring identifies T_a from each rig run, which needs a few seconds of record) and share
a warm 2-process pool for the module.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import csv
import json
import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import time

import pytest

import numpy as np

from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.pool import local_executor
from rigsim.scenarios.studies import scoring
from rigsim.scenarios.studies.sweep import command as sweep
from rigsim.scenarios.studies.sweep import run as sweep_run
from rigsim.scenarios.studies.sweep.case import METRIC_COLUMNS
from rigsim.scenarios.studies.sweep.executors import dask_executor
from rigsim.scenarios.studies.sweep.grid import GRID_FORMAT, load_grid, parse_grid
from rigsim.scenarios.studies.sweep.run import run_sweep
from rigsim.scenarios.studies.sweep.settings import EvalSettings

ROOT = pathlib.Path(__file__).resolve().parents[3]

BASE = """
[sweep]
name = "t"

[base]
name = "t"
speed_kmh = 72.0
duration_s = 5.0
lead_in_s = 0.5
seed = 3
road = { roughness = "high" }
"""

# Four real cases and one refused at its start (road class H leaves the stroke).
GRID = BASE + """
[[cases]]
speed_kmh = 48
vehicle.payload_kg = 3640
[[cases]]
speed_kmh = 48
vehicle.payload_kg = 6360
[[cases]]
speed_kmh = 72
vehicle.payload_kg = 3640
[[cases]]
speed_kmh = 72
vehicle.payload_kg = 6360
[[cases]]
speed_kmh = 72
road.roughness = "H"
"""


def _grid_file(tmp_path: pathlib.Path, text: str, name: str = "grid.toml") -> pathlib.Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def _rows(path: pathlib.Path, drop=("wall_time_s",)) -> list[dict]:
    with open(path, newline="") as fh:
        return [{k: v for k, v in row.items() if k not in drop} for row in csv.DictReader(fh)]


# ----------------------------------------------------------------------------- validation
@pytest.mark.parametrize("axes, message", [
    ('vehicle.paylod_kg = [3640, 6360]', "axis vehicle.paylod_kg is not a scenario key; did you mean 'vehicle.payload_kg'?"),
    ('speed = [48, 72]', "axis speed is not a scenario key; did you mean 'speed_kmh'?"),
    ('speed_kmh = [48, 0]', "speed_kmh = 0 is refused: speed_kmh must be > 0"),
    ('road.roughness = ["high", "bumpy"]', 'road.roughness = "bumpy" is refused'),
    ('actuator.bulk_modulus_Pa = [1.4e9, -1.0]', "actuator.bulk_modulus_Pa = -1 is refused"),
    ('speed_kmh = []', "axis speed_kmh must be a non-empty list"),
    ('seed = [1, 1]', "axis seed lists the value 1 twice"),
])
def test_invalid_axis_is_refused_before_anything_starts(tmp_path, axes, message):
    grid = _grid_file(tmp_path, BASE + "\n[axes]\n" + axes + "\n")
    parser = argparse.ArgumentParser()
    sweep.add_parser(parser.add_subparsers())
    args = parser.parse_args(["sweep", str(grid), "--out", str(tmp_path / "out")])
    with pytest.raises(ScenarioError) as err:
        args.func(args)
    assert message in str(err.value)
    assert "\n" not in str(err.value)
    assert not (tmp_path / "out").exists()


def test_grid_expansion_ids_and_explicit_cases(tmp_path):
    g = load_grid(_grid_file(tmp_path, BASE + """
        [axes]
        road.roughness = ["medium", "high"]
        speed_kmh = [48, 72.0, 90.5]
        [[cases]]
        vehicle.payload_kg = 3640
        [[cases]]
        vehicle.payload_kg = 6360
        actuator.bulk_modulus_Pa = 1.2e9
    """))
    assert len(g.cases) == 2 * 3 * 2
    ids = [c.case_id for c in g.cases]
    assert len(set(ids)) == len(ids)
    assert "road.roughness=medium__speed_kmh=72__vehicle.payload_kg=3640" in ids
    assert "actuator.bulk_modulus_Pa=1200000000__road.roughness=high__speed_kmh=90.5__vehicle.payload_kg=6360" in ids
    assert g.keys == ("road.roughness", "speed_kmh", "vehicle.payload_kg", "actuator.bulk_modulus_Pa")
    # the id does not depend on the order of the axes in the file; the fingerprint on the base
    doc = {"base": {"name": "b", "speed_kmh": 60.0, "duration_s": 2.0, "road": {"roughness": "high"}},
           "axes": {"seed": [1, 2], "speed_kmh": [48, 72]}}
    a = parse_grid(doc)
    b = parse_grid({**doc, "axes": {"speed_kmh": [48, 72], "seed": [1, 2]}})
    assert sorted(c.case_id for c in a.cases) == sorted(c.case_id for c in b.cases)
    assert {c.fingerprint for c in a.cases} == {c.fingerprint for c in b.cases}
    c = parse_grid({**doc, "base": {**doc["base"], "duration_s": 3.0}})
    assert not {x.fingerprint for x in a.cases} & {x.fingerprint for x in c.cases}
    with pytest.raises(ScenarioError, match="both an axis and a key of case 1"):
        parse_grid({**doc, "cases": [{"seed": 4}]})


def test_example_grid_has_twelve_valid_cases():
    g = load_grid(ROOT / "scenarios" / "data" / "sweeps" / "example.toml")
    assert len(g.cases) == 12
    assert {c.scenario.road.roughness for c in g.cases} == {"medium", "high"}


@pytest.mark.parametrize("line, message", [
    ('actuator = "eq5"', "sweep.actuator must be 'identified' or 'eq4', got 'eq5'"),
    ('lowpass = "butter"', "sweep.lowpass must be 'regularized' or 'paper', got 'butter'"),
    ("noise_N = -1.0", "sweep.noise_N must be >= 0, got -1.0"),
    ('noise_N = "100 N"', "sweep.noise_N must be a number"),
    ("settling_tolerance = 0", "sweep.settling_tolerance must be > 0"),
    ("settling_tolerance = 1", "sweep.settling_tolerance must be < 1"),
    ('lowpas = "paper"', "unknown key sweep.lowpas; did you mean 'lowpass'?"),
])
def test_invalid_sweep_setting_is_refused(tmp_path, line, message):
    path = _grid_file(tmp_path, BASE.replace('name = "t"\n', f'name = "t"\n{line}\n', 1))
    with pytest.raises(ScenarioError) as err:
        load_grid(path)
    assert str(err.value).startswith("grid.toml: ") and message in str(err.value)


def test_default_settings_are_the_paper_studys_best_method_and_noise(tmp_path):
    g = load_grid(_grid_file(tmp_path, BASE))
    assert g.settings == EvalSettings()
    assert g.settings.method == scoring.BEST and g.settings.noise_N == scoring.NOISE_N == 100.0
    assert g.settings.settling_tolerance == scoring.SETTLING_TOLERANCE
    causal = load_grid(_grid_file(tmp_path, BASE.replace('name = "t"\n', 'name = "t"\nactuator = "eq4"\n'
                                                         'lowpass = "paper"\ncorrection_mode = "causal"\n', 1)))
    assert causal.settings.method == scoring.PAPER
    # the evaluation settings and the format are part of the fingerprint: no stale case is reused
    quiet = load_grid(_grid_file(tmp_path, BASE.replace('name = "t"\n', 'name = "t"\nnoise_N = 0\n', 1)))
    assert quiet.cases[0].fingerprint != g.cases[0].fingerprint
    assert GRID_FORMAT == 3


def test_bad_workers_is_refused_before_anything_starts(tmp_path):
    parser = argparse.ArgumentParser()
    sweep.add_parser(parser.add_subparsers())
    args = parser.parse_args(["sweep", str(_grid_file(tmp_path, BASE)), "--out", str(tmp_path / "out"),
                              "--workers", "0"])
    with pytest.raises(ScenarioError, match=r"^--jobs must be a whole number >= 1, got 0$"):
        args.func(args)
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------- resume logic (no MuJoCo)
def _fake_payload(case_id, doc, source, settings):
    """Stand-in for evaluate_payload: instant, deterministic, fails on seed 13."""
    if doc.get("seed") == 13:
        return {"case_id": case_id, "status": "failed", "error": "unlucky seed", "retry": False,
                "result": None, "wall_time_s": 0.0}
    v = float(doc["speed_kmh"]) / 1000 + doc.get("seed", 0) / 1e5
    result = {k: v for k in METRIC_COLUMNS}
    return {"case_id": case_id, "status": "ok", "error": None, "retry": False, "result": result,
            "wall_time_s": 0.0}


def test_interrupt_and_resume_with_an_instant_executor(tmp_path, monkeypatch):
    monkeypatch.setattr(sweep_run, "evaluate_payload", _fake_payload)
    g = load_grid(_grid_file(tmp_path, BASE + "\n[axes]\nseed = [11, 12, 13, 14]\nspeed_kmh = [48, 72]\n"))
    with cf.ThreadPoolExecutor(1) as ex:
        full = run_sweep(g, tmp_path / "full", ex, progress=False, plot=False)
    assert (full.ok, full.failed) == (6, 2)

    def stop_after_three(case_id, record, seen=[]):  # noqa: B006 - a counter local to this test
        seen.append(case_id)
        if len(seen) == 3:
            raise KeyboardInterrupt

    with cf.ThreadPoolExecutor(1) as ex, pytest.raises(KeyboardInterrupt):
        run_sweep(g, tmp_path / "cut", ex, progress=False, plot=False, on_record=stop_after_three)
    assert len(list((tmp_path / "cut" / "cases").glob("*.json"))) == 3
    assert len(_rows(tmp_path / "cut" / "results.csv")) == 3
    assert not json.loads((tmp_path / "cut" / "sweep.json").read_text())["complete"]
    with cf.ThreadPoolExecutor(1) as ex:
        resumed = run_sweep(g, tmp_path / "cut", ex, progress=False, plot=False)
    assert (resumed.skipped, resumed.ok + resumed.failed) == (3, 5)
    assert (tmp_path / "cut" / "results.csv").read_bytes() == (tmp_path / "full" / "results.csv").read_bytes()
    failed = [r for r in _rows(tmp_path / "full" / "results.csv") if r["status"] == "failed"]
    assert [r["error"] for r in failed] == ["unlucky seed"] * 2 and failed[0]["dlc_rig"] == ""

    # resume skips everything now; --no-resume runs everything; a worker lost is retried
    with cf.ThreadPoolExecutor(1) as ex:
        assert run_sweep(g, tmp_path / "cut", ex, progress=False, plot=False).skipped == 8
        assert run_sweep(g, tmp_path / "cut", ex, resume=False, progress=False, plot=False).ok == 6
    lost = tmp_path / "cut" / "cases" / f"{g.cases[0].case_id}.json"
    rec = json.loads(lost.read_text())
    rec.update(status="failed", retry=True, result=None, error="the worker running it failed")
    lost.write_text(json.dumps(rec))
    with cf.ThreadPoolExecutor(1) as ex:
        again = run_sweep(g, tmp_path / "cut", ex, progress=False, plot=False)
    assert (again.skipped, again.ok) == (7, 1)


# ---------------------------------------------------------------------- real sweeps (MuJoCo)
def test_a_sweep_case_scores_like_the_paper_study(tmp_path):
    """The sweep's case (default settings) and the paper study's scoring (scenarios/studies/paper/
    compute.py: identify_rig, then score_pair with both methods) agree on the same case and seed."""
    from rigsim.scenarios.core.rig import Rig
    from rigsim.scenarios.core.run import run
    from rigsim.scenarios.studies.identify.compute import identify_rig

    g = load_grid(_grid_file(tmp_path, BASE))
    (case,) = g.cases
    with cf.ThreadPoolExecutor(1) as ex:
        assert run_sweep(g, tmp_path / "out", ex, progress=False, plot=False).ok == 1
    got = json.loads((tmp_path / "out" / "cases" / "base.json").read_text())["result"]
    row = _rows(tmp_path / "out" / "results.csv")[0]

    s = case.scenario
    road, rig, model = run(s, "road"), run(s, "rig"), Rig(s)
    ta = identify_rig(s, rig=model).actuators()
    best = scoring.score_pair(road, rig, model, methods=(scoring.BEST,), identified=ta, noise_N=scoring.NOISE_N,
                              seed=s.seed)
    both = scoring.score_pair(road, rig, model, methods=(scoring.PAPER, scoring.BEST), identified=ta,
                              noise_N=scoring.NOISE_N, seed=s.seed)
    # each method is scored on its own settled samples: BEST's figures do not depend on PAPER's
    for k, v in best.methods["best"].figures.items():
        np.testing.assert_array_equal(both.methods["best"].figures[k], v, err_msg=k)
    assert both.methods["best"].scored_s == best.methods["best"].scored_s

    want = best.mean
    assert abs(got["dlc_corrected"] - want["dlc_corrected_best"]) <= 1e-12
    assert abs(float(row["dlc_corrected"]) - want["dlc_corrected_best"]) <= 1e-12
    assert abs(got["dlc_rig"] - want["dlc_rig"]) <= 1e-12  # with the same measurement noise
    assert abs(got["nrmse_corrected"] - want["nrmse_corrected_best"]) <= 1e-12
    assert got["scored_s"] == best.methods["best"].scored_s
    # the comparison tells the methods and the noise apart
    assert abs(want["dlc_corrected_best"] - both.mean["dlc_corrected_paper"]) > 1e-3
    quiet = scoring.score_pair(road, rig, model, methods=(scoring.BEST,), identified=ta, noise_N=0.0, seed=s.seed)
    assert abs(got["dlc_rig"] - quiet.mean["dlc_rig"]) > 1e-6


@pytest.fixture(scope="module")
def grid_path(tmp_path_factory):
    return _grid_file(tmp_path_factory.mktemp("grid"), GRID)


@pytest.fixture(scope="module")
def pool():
    with local_executor(2) as ex:
        yield ex


@pytest.fixture(scope="module")
def reference(grid_path, pool, tmp_path_factory):
    out = tmp_path_factory.mktemp("pool")
    outcome = run_sweep(load_grid(grid_path), out, pool, progress=False)
    return out, outcome


def test_pool_sweep_records_every_case(reference):
    out, outcome = reference
    assert (outcome.total, outcome.ok, outcome.failed) == (5, 4, 1)
    rows = _rows(out / "results.csv", drop=())
    assert [r["case_id"] for r in rows] == sorted(r["case_id"] for r in rows)
    bad = [r for r in rows if r["status"] == "failed"]
    assert len(bad) == 1 and "stroke" in bad[0]["error"] and bad[0]["road.roughness"] == "H"
    good = [r for r in rows if r["status"] == "ok"]
    for r in good:
        road, rig, corr = float(r["dlc_road"]), float(r["dlc_rig"]), float(r["dlc_corrected"])
        assert 0.02 < rig < road  # the rig attenuates the dynamic load
        assert corr > rig  # the correction restores some of it
        assert float(r["nrmse_corrected"]) < float(r["nrmse_rig"])  # the correction helps
    assert "wall_time_s" not in rows[0]  # timings apart, in timings.csv: results.csv is reproducible
    timings = _rows(out / "timings.csv", drop=())
    assert [t["case_id"] for t in timings] == [r["case_id"] for r in rows]
    assert all(float(t["wall_time_s"]) > 0 for t in timings)
    assert (out / "summary.png").stat().st_size > 10_000
    assert len(list((out / "cases").glob("*.json"))) == 5


def test_dask_local_cluster_gives_the_same_results(grid_path, reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None,
                                  silence_logs=50) as cluster:
        with dask_executor(cluster.scheduler_address) as ex:
            outcome = run_sweep(load_grid(grid_path), tmp_path, ex, progress=False, plot=False)
    assert (outcome.ok, outcome.failed) == (4, 1)
    assert _rows(tmp_path / "results.csv") == _rows(reference[0] / "results.csv")


def test_killed_sweep_resumes_to_the_same_results(grid_path, reference, pool, tmp_path):
    # One worker: when the first case file appears, at least two cases of seconds each are left,
    # so Ctrl-C (sent within ~10 ms) always arrives before the sweep could finish.
    out = tmp_path / "out"
    # SIGINT's default handler restored first: a process started in the background by a
    # non-interactive shell (nohup, CI runners) inherits SIGINT ignored, and Python then never
    # raises KeyboardInterrupt.
    code = ("import argparse, signal, sys\nsignal.signal(signal.SIGINT, signal.default_int_handler)\n"
            "from rigsim.scenarios.studies.sweep import command as sweep\np = argparse.ArgumentParser()\n"
            "sweep.add_parser(p.add_subparsers())\na = p.parse_args(sys.argv[1:])\n"
            "try:\n    sys.exit(a.func(a))\nexcept KeyboardInterrupt:\n    sys.exit(130)\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen([sys.executable, "-c", code, "sweep", str(grid_path), "--out", str(out),
                             "--workers", "1", "--quiet"], env=env, cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not list((out / "cases").glob("*.json")):
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.01)
        proc.send_signal(signal.SIGINT)  # Ctrl-C
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    kept = sorted(p.name for p in (out / "cases").glob("*.json"))
    assert 1 <= len(kept) < 4, "the sweep was not interrupted after its first case"
    assert "interrupted" in err and "resume" in err
    assert not [p for p in (out / "cases").iterdir() if p.name.startswith(".")]  # no partial file
    assert len(_rows(out / "results.csv")) == len(kept)
    assert not json.loads((out / "sweep.json").read_text())["complete"]

    outcome = run_sweep(load_grid(grid_path), out, pool, progress=False)
    assert outcome.skipped == len(kept) and outcome.ok + outcome.failed == 5 - len(kept)
    assert _rows(out / "results.csv") == _rows(reference[0] / "results.csv")
