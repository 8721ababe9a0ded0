"""A test programme's cost: ``rigsim programme`` on N records of one mismatched truck, on the pool and on Dask.

::

    python benchmarks/programme.py [--records 20] [--duration-s 60] [--jobs 2] [--seed 0] [--dask]
                                   [--alone N] [--cab auto|held|fitted] [--calibration-windows N]
                                   [--calibrate-on N] [--results docs/results]

One plant truck is drawn as the mismatch suite draws them (``scenarios/data/suites/mismatch_plants.toml``,
:func:`rigsim.scenarios.studies.model_suite.mismatch.mismatch_plants`) for the paper's high-roughness
3640 kg case; each record is that truck on the rig on its own road section (seed) at its own speed
(48-80 km/h), written as a lab's CSV (:func:`rigsim.scenarios.studies.lab_record.write_lab_record`,
100 N rms of load-cell noise), and corrected with the catalogue truck's scenario as TRUCK.toml.
Measured: the wall time of ``rigsim programme --jobs N`` (a fresh process), and for the first
``--alone`` records the DLC of each wheel against the same record corrected by ``rigsim correct
--model`` calibrated on it alone (the goal: within 0.2 %), and both against the road: the
truck's road test on the same road (the wheel forces the rig is to reproduce), its DLC over the
corrected file's samples; with ``--dask`` the same
programme on a local Dask cluster of ``--jobs`` single-threaded workers, into the same folder (the
metadata names it), its files compared byte for byte and its throughput against the pool's.
Prints each figure and writes them to ``docs/results/programme.md`` (``--results``: its folder):
one row per record corrected alone too, the wall times and the goals below the table.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

from rigsim.correction.io.measured import read_channels
from rigsim.correction.metrics.dlc import dlc
from rigsim.scenarios.core.config import load_scenario, paper_scenarios
from rigsim.scenarios.studies.lab_record import PAIRS, write_lab_record
from rigsim.scenarios.studies.model_suite.mismatch import mismatch_plants, mismatch_scenario
from rigsim.scenarios.studies.programme.settings import CALIBRATE_ON
from rigsim.scenarios.studies.results_page import script_command, write_results_page

RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"
CASE = "high_72kmh_3640kg"
SPEEDS_KMH = (48.0, 60.0, 72.0, 80.0)
#: The goal, %: each record's DLC within this of its own correction calibrated alone.
GOAL_PCT = 0.2


def _dlcs(path) -> dict:
    got = read_channels(path)
    return {c: float(dlc(got.data[c])) for c in got.names if c.endswith("_corrected")}


def _road_dlcs(scenario, path) -> dict:
    """The road test's DLC per wheel over the samples the corrected file ``path`` holds."""
    from rigsim.mjcf.names import CORNERS
    from rigsim.scenarios.core.run import run

    road = run(scenario, "road")
    got = read_channels(path)
    keep = np.isin(np.round(np.asarray(road.t_s) * 1e3).astype(int), np.round(got.time_s * 1e3).astype(int))
    force = np.asarray(road.signals["tire_force_N"])[keep]
    return {f"Fz_{c.upper()}_corrected": float(dlc(force[:, i])) for i, c in enumerate(CORNERS)}


def _files(folder: pathlib.Path) -> dict:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name != "timings.csv" and not p.name.startswith(".")}


def _timed(argv: list[str], env: dict) -> float:
    t0 = time.perf_counter()
    done = subprocess.run(argv, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        sys.exit(f"{' '.join(argv[:3])}... failed ({done.returncode}): {done.stderr.strip()[-2000:]}")
    return wall


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=int, default=20, help="records in the programme")
    ap.add_argument("--duration-s", type=float, default=60.0, help="each record's length, s")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (and Dask workers)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the plant truck's draw")
    ap.add_argument("--alone", type=int, default=None, help="records also corrected alone (default: all)")
    ap.add_argument("--cab", choices=("auto", "held", "fitted"), default="auto", help="the calibration's --cab")
    ap.add_argument("--calibration-windows", type=int, default=None, help="the calibration's windows (default 2)")
    ap.add_argument("--calibrate-on", type=int, default=None,
                    help="the programme's --calibrate-on: the truck calibrated on its first N records (default 3)")
    ap.add_argument("--dask", action="store_true", help="also on a local Dask cluster")
    ap.add_argument("--results", default=str(RESULTS), help="folder of programme.md")
    args = ap.parse_args(argv)
    if args.records < 1 or args.jobs < 1:
        ap.error("--records and --jobs must be at least 1")
    truck = next(p for p in paper_scenarios() if p.stem == CASE)
    plant = mismatch_plants([truck], seed=args.seed)[0]
    rigsim = str(pathlib.Path(sys.executable).with_name("rigsim"))
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    options = ["--model", str(truck), "--pairs", PAIRS, "--cab", args.cab, "--quiet"]
    if args.calibration_windows is not None:
        options += ["--calibration-windows", str(args.calibration_windows)]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        (tmp / "records").mkdir()
        base, scenarios = load_scenario(truck), {}
        for i in range(args.records):
            sc = mismatch_scenario(truck, plant, args.duration_s)
            sc = dataclasses.replace(sc, seed=base.seed + 101 * i, speed_kmh=SPEEDS_KMH[i % len(SPEEDS_KMH)])
            scenarios[f"rec{i:03d}"] = sc
            write_lab_record(tmp / "records" / f"rec{i:03d}.csv", sc, noise_seed=7 + i)
        records = sorted(str(p) for p in (tmp / "records").glob("*.csv"))
        out = tmp / "out"
        on = [] if args.calibrate_on is None else ["--calibrate-on", str(args.calibrate_on)]
        wall = _timed([rigsim, "programme", *records, *options, *on, "--jobs", str(args.jobs), "--out", str(out)], env)
        notes = [f"pool: {args.records} records of {args.duration_s:g} s, --jobs {args.jobs}, --cab {args.cab}, "
                 f"--calibrate-on {args.calibrate_on or CALIBRATE_ON}: "
                 f"{wall:.1f} s wall ({wall / 60:.2f} min; {args.records / wall * 60:.2f} records/min)"]
        print(notes[-1])
        worst, to_road, rows = 0.0, {"programme": [], "alone": []}, []
        for rec in records[:args.alone]:
            name = pathlib.Path(rec).stem
            alone = tmp / f"{name}_alone.csv"
            _timed([rigsim, "correct", rec, *options, "--jobs", str(args.jobs), "-o", str(alone)], env)
            a, p = _dlcs(alone), _dlcs(out / f"{name}_corrected.csv")
            r = _road_dlcs(scenarios[name], out / f"{name}_corrected.csv")
            diff = {c: 100.0 * (p[c] / a[c] - 1.0) for c in a}
            worst = max(worst, *(abs(d) for d in diff.values()))
            to_road["programme"] += [100.0 * (p[c] / r[c] - 1.0) for c in r]
            to_road["alone"] += [100.0 * (a[c] / r[c] - 1.0) for c in r]
            rows.append([name, f"{scenarios[name].speed_kmh:g}", " ".join(f"{d:+.3f}" for d in diff.values()),
                         " ".join(f"{v:+.2f}" for v in to_road["programme"][-4:]),
                         " ".join(f"{v:+.2f}" for v in to_road["alone"][-4:])])
            print(f"  {name}: DLC programme against alone: " + ", ".join(f"{c.split('_')[1]} {d:+.3f} %"
                                                                          for c, d in diff.items())
                  + "; against the road: programme " + " ".join(f"{v:+.2f}" for v in to_road["programme"][-4:])
                  + " %, alone " + " ".join(f"{v:+.2f}" for v in to_road["alone"][-4:]) + " %")
        if records[:args.alone]:
            within = sum(max(abs(float(x)) for x in r[2].split()) <= GOAL_PCT for r in rows)
            notes.append(f"worst DLC difference against the records calibrated alone: {worst:.3f} % (goal {GOAL_PCT:g} %: "
                         f"{'met' if worst <= GOAL_PCT else 'not met'}; {within} of {len(rows)} records within it)")
            print(notes[-1])
            prog, own = np.abs(to_road["programme"]), np.abs(to_road["alone"])
            notes.append(f"DLC error against the road over {prog.size} wheels: programme mean {prog.mean():.3f} %, worst "
                         f"{prog.max():.3f} %; alone mean {own.mean():.3f} %, worst {own.max():.3f} %; the programme "
                         f"closer on {int(np.sum(prog < own))} of {prog.size}")
            print(notes[-1])
        if args.dask:
            import distributed

            reference = _files(out)
            shutil.move(out, tmp / "pool")
            with distributed.LocalCluster(n_workers=args.jobs, processes=True, threads_per_worker=1,
                                          host="127.0.0.1", dashboard_address=None, silence_logs=50) as cluster:
                dwall = _timed([rigsim, "programme", *records, *options, *on, "--scheduler", cluster.scheduler_address,
                                "--out", str(out)], env)
            same = _files(out) == reference
            notes.append(f"dask: {dwall:.1f} s wall, throughput {wall / dwall:.0%} of the pool's (goal 90 %); files "
                         f"{'byte-identical' if same else 'DIFFERENT'} to the pool's")
            print(notes[-1])
    head = ("record", "speed km/h", "DLC programme against alone, % (fl fr rl rr)",
            "DLC error against the road, programme, % (fl fr rl rr)", "alone, % (fl fr rl rr)")
    note = (f"{args.records} records of {args.duration_s:g} s of one mismatched truck (the mismatch suite's draw, "
            f"seed {args.seed}) on its own road section each, 100 N load-cell noise, corrected by `rigsim programme` "
            f"and, record by record, by `rigsim correct --model` calibrated on that record alone; DLC differences "
            f"relative (100 (DLC / DLC_reference - 1)).\n\n" + "\n".join(f"- {n}" for n in notes))
    write_results_page(args.results, "programme", "A test programme: one calibration per truck, records in parallel",
                       head, rows, script_command(__file__, argv), note=note)
    return 0



if __name__ == "__main__":
    sys.exit(main())
