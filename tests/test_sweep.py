"""rigsim sweep: grid validation, one code path for the process pool and Dask, nothing lost.

The simulated sweeps are short (5 cases of 1.5 s records, one of them failing at its start) and
share two warm executors (a 2-process pool and a 2-worker Dask LocalCluster) for the module.
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

from scenarios import sweep
from scenarios.config import ScenarioError
from scenarios.sweep_grid import load_grid, parse_grid

ROOT = pathlib.Path(__file__).resolve().parents[1]

BASE = """
[sweep]
name = "t"
settling_tolerance = 0.05   # 1.5 s records: score the samples outside the 5 % transients

[base]
name = "t"
speed_kmh = 72.0
duration_s = 1.5
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
    g = load_grid(ROOT / "scenarios" / "sweeps" / "example.toml")
    assert len(g.cases) == 12
    assert {c.scenario.road.roughness for c in g.cases} == {"medium", "high"}


# ------------------------------------------------------------------- resume logic (no MuJoCo)
def _fake_payload(case_id, doc, source, settings):
    """Stand-in for evaluate_payload: instant, deterministic, fails on seed 13."""
    if doc.get("seed") == 13:
        return {"case_id": case_id, "status": "failed", "error": "unlucky seed", "retry": False,
                "result": None, "wall_time_s": 0.0}
    v = float(doc["speed_kmh"]) / 1000 + doc.get("seed", 0) / 1e5
    result = {k: v for k in sweep.METRIC_COLUMNS}
    return {"case_id": case_id, "status": "ok", "error": None, "retry": False, "result": result,
            "wall_time_s": 0.0}


def test_interrupt_and_resume_with_an_instant_executor(tmp_path, monkeypatch):
    monkeypatch.setattr(sweep, "evaluate_payload", _fake_payload)
    g = load_grid(_grid_file(tmp_path, BASE + "\n[axes]\nseed = [11, 12, 13, 14]\nspeed_kmh = [48, 72]\n"))
    with cf.ThreadPoolExecutor(1) as ex:
        full = sweep.run_sweep(g, tmp_path / "full", ex, progress=False, plot=False)
    assert (full.ok, full.failed) == (6, 2)

    def stop_after_three(case_id, record, seen=[]):  # noqa: B006 - a counter local to this test
        seen.append(case_id)
        if len(seen) == 3:
            raise KeyboardInterrupt

    with cf.ThreadPoolExecutor(1) as ex, pytest.raises(KeyboardInterrupt):
        sweep.run_sweep(g, tmp_path / "cut", ex, progress=False, plot=False, on_record=stop_after_three)
    assert len(list((tmp_path / "cut" / "cases").glob("*.json"))) == 3
    assert len(_rows(tmp_path / "cut" / "results.csv")) == 3
    assert not json.loads((tmp_path / "cut" / "sweep.json").read_text())["complete"]
    with cf.ThreadPoolExecutor(1) as ex:
        resumed = sweep.run_sweep(g, tmp_path / "cut", ex, progress=False, plot=False)
    assert (resumed.skipped, resumed.ok + resumed.failed) == (3, 5)
    assert (tmp_path / "cut" / "results.csv").read_bytes() == (tmp_path / "full" / "results.csv").read_bytes()
    failed = [r for r in _rows(tmp_path / "full" / "results.csv") if r["status"] == "failed"]
    assert [r["error"] for r in failed] == ["unlucky seed"] * 2 and failed[0]["dlc_rig"] == ""

    # resume skips everything now; --no-resume runs everything; a worker lost is retried
    with cf.ThreadPoolExecutor(1) as ex:
        assert sweep.run_sweep(g, tmp_path / "cut", ex, progress=False, plot=False).skipped == 8
        assert sweep.run_sweep(g, tmp_path / "cut", ex, resume=False, progress=False, plot=False).ok == 6
    lost = tmp_path / "cut" / "cases" / f"{g.cases[0].case_id}.json"
    rec = json.loads(lost.read_text())
    rec.update(status="failed", retry=True, result=None, error="the worker running it failed")
    lost.write_text(json.dumps(rec))
    with cf.ThreadPoolExecutor(1) as ex:
        again = sweep.run_sweep(g, tmp_path / "cut", ex, progress=False, plot=False)
    assert (again.skipped, again.ok) == (7, 1)


# ---------------------------------------------------------------------- real sweeps (MuJoCo)
@pytest.fixture(scope="module")
def grid_path(tmp_path_factory):
    return _grid_file(tmp_path_factory.mktemp("grid"), GRID)


@pytest.fixture(scope="module")
def pool():
    with sweep.local_executor(2) as ex:
        yield ex


@pytest.fixture(scope="module")
def reference(grid_path, pool, tmp_path_factory):
    out = tmp_path_factory.mktemp("pool")
    outcome = sweep.run_sweep(load_grid(grid_path), out, pool, progress=False)
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
        assert float(r["wall_time_s"]) > 0
    assert (out / "summary.png").stat().st_size > 10_000
    assert len(list((out / "cases").glob("*.json"))) == 5


def test_dask_local_cluster_gives_the_same_results(grid_path, reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None,
                                  silence_logs=50) as cluster:
        with sweep.dask_executor(cluster.scheduler_address) as ex:
            outcome = sweep.run_sweep(load_grid(grid_path), tmp_path, ex, progress=False, plot=False)
    assert (outcome.ok, outcome.failed) == (4, 1)
    assert _rows(tmp_path / "results.csv") == _rows(reference[0] / "results.csv")


def test_killed_sweep_resumes_to_the_same_results(grid_path, reference, pool, tmp_path):
    out = tmp_path / "out"
    code = ("import argparse, sys\nfrom scenarios import sweep\np = argparse.ArgumentParser()\n"
            "sweep.add_parser(p.add_subparsers())\na = p.parse_args(sys.argv[1:])\n"
            "try:\n    sys.exit(a.func(a))\nexcept KeyboardInterrupt:\n    sys.exit(130)\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen([sys.executable, "-c", code, "sweep", str(grid_path), "--out", str(out),
                             "--workers", "2", "--quiet"], env=env, cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not list((out / "cases").glob("*.json")):
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.05)
        proc.send_signal(signal.SIGINT)  # Ctrl-C
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    kept = sorted(p.name for p in (out / "cases").glob("*.json"))
    assert 1 <= len(kept) < 5, "the sweep finished before it was interrupted"
    assert "interrupted" in err and "resume" in err
    assert not [p for p in (out / "cases").iterdir() if p.name.startswith(".")]  # no partial file
    assert len(_rows(out / "results.csv")) == len(kept)

    outcome = sweep.run_sweep(load_grid(grid_path), out, pool, progress=False)
    assert outcome.skipped == len(kept) and outcome.ok + outcome.failed == 5 - len(kept)
    assert _rows(out / "results.csv") == _rows(reference[0] / "results.csv")
