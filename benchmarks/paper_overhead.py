"""``rigsim paper`` against the physics' own cost: its wall time over bare MuJoCo's for the same steps.

::

    python benchmarks/paper_overhead.py [--jobs 2] [--duration-s 60] [--repeats 1]

1. Counts the MuJoCo steps ``rigsim paper`` takes on its default rig
   (:data:`rigsim.scenarios.studies.paper.command.RIG`): per case the road run, the rig run (both RK4 at
   1e-3 s, the lead-in plus the duration) and the rig's identification
   (:func:`rigsim.scenarios.studies.identify.compute.identify_rig`'s drive, RK4).
2. Times ``rigsim paper --out TMP --jobs J --quiet`` end to end (a subprocess: imports, compiling
   or loading the hydraulic callbacks, the runs, the scoring, each run's ``result.json``, the
   report and its figures; no time series, which only ``--series`` writes). The
   packages are byte-compiled first, as ``pip install`` leaves an installed package (a checkout
   run with ``PYTHONDONTWRITEBYTECODE`` set would otherwise compile every module's source in
   every run).
3. Times bare MuJoCo stepping the same number of steps on the same J cores: J worker processes,
   each stepping its share of the steps with ``mujoco.rollout`` on the truck on the pans with a
   stiff built-in position servo per pan instead of the hydraulics, replaying the pan motion of
   the hydraulic rig (:func:`rigsim.scenarios.studies.bare_twin.bare_controls`), under the same integration and step,
   after a warm-up; the bare wall time is the slowest worker's. This is the cost of the
   multibody physics alone, with no callback, no I/O, no Python between steps.

Prints one JSON line: steps, paper wall and CPU time (s), the bare wall time (s), their ratio
(goal: at most 1.5) and the paper's CPU seconds per bare CPU second. With
``--repeats R`` the two are timed alternately R times and the smallest of each is used (the
least disturbed by other processes on a shared machine).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import resource
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
#: Steps each bare rollout call takes (the forces of one recorded chunk, replayed), 1.
CHUNK_STEPS = 20_000


def paper_steps(duration_s: float | None) -> dict:
    """MuJoCo steps of ``rigsim paper`` (its default rig) by integration: ``{"rk4": the road runs', the rig runs' and
    the identifications'}``, each at its test's time step (RK4 at 1e-3 s, :mod:`rigsim.scenarios.core.rig`)."""
    import dataclasses

    from rigsim.scenarios.core.config import load_scenario, paper_scenarios
    from rigsim.scenarios.core.rig import Rig
    from rigsim.scenarios.core.drive import IDENT_MIN_S, IDENT_SKIP_S
    from rigsim.scenarios.studies.paper.command import RIG

    total = 0
    for p in paper_scenarios(RIG):
        sc = load_scenario(p)
        if duration_s is not None:
            sc = dataclasses.replace(sc, duration_s=float(duration_s))
        road, rig = Rig(sc, hydraulic=False), Rig(sc)
        total += road.road_source().n_steps
        record_s = max(sc.duration_s, IDENT_MIN_S) + IDENT_SKIP_S
        total += rig.road_source().n_steps + int(round(record_s / rig.dt_s)) + 1
    return {"rk4": total}


def bare_worker(steps: int, integration: str) -> dict:
    """Step the bare truck ``steps`` times (rollouts of :data:`CHUNK_STEPS`) under ``integration``
    (a key of :data:`rigsim.scenarios.studies.bare_twin.INTEGRATIONS`); wall and CPU time, s."""
    import mujoco
    from mujoco import rollout

    from rigsim.hydraulics.bridge import hydraulic_callbacks
    from rigsim.scenarios.studies.bare_twin import bare_controls, build_models, drive_signal, initial_state, static_loads

    rig, bare, corners = build_models("truck", integration=integration)
    loads = static_loads(bare, corners)
    hyd = [mujoco.mj_name2id(rig, mujoco.mjtObj.mjOBJ_ACTUATOR, f"hyd_{c}") for c in corners]
    n = min(CHUNK_STEPS, steps)
    x_ref = np.zeros((n, rig.nu))
    x_ref[:, hyd] = drive_signal(n, rig.opt.timestep, corners)
    with hydraulic_callbacks(rig, fast=True):
        state, sensordata = rollout.rollout(rig, mujoco.MjData(rig), initial_state(rig, corners, loads, True), x_ref)
    forces = bare_controls(rig, bare, corners, state, sensordata)
    data, s0 = mujoco.MjData(bare), initial_state(bare, corners, loads, False)
    rollout.rollout(bare, data, s0, forces[:10])  # warm-up
    left = steps
    c0, t0 = time.process_time(), time.perf_counter()
    while left > 0:
        k = min(n, left)
        rollout.rollout(bare, data, s0, forces[:k])
        left -= k
    return {"wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}


def time_bare(steps: dict, jobs: int) -> dict:
    """Bare stepping of ``steps`` (per integration) on ``jobs`` workers: each worker steps its
    share of every integration's steps; the wall time is the slowest worker's, s."""
    from rigsim.scenarios.core.pool import run_jobs

    def shares(n):
        return [n // jobs + (1 if i < n % jobs else 0) for i in range(jobs)]

    res = run_jobs([(bare_worker, (s, kind)) for kind, n in steps.items() for s in shares(n)], workers=jobs)
    per_worker = [sum(r["wall_s"] for r in res[i::jobs]) for i in range(jobs)]
    return {"wall_s": max(per_worker), "cpu_s": sum(r["cpu_s"] for r in res)}


def byte_compile() -> None:
    """Byte-compile the four packages (``__pycache__``, as ``pip install`` does for an installed one)."""
    import compileall

    for package in ("mjcf", "hydraulics", "correction", "scenarios"):
        compileall.compile_dir(str(ROOT / package), quiet=1)


def time_paper(jobs: int, duration_s: float | None) -> dict:
    out = pathlib.Path(tempfile.mkdtemp(prefix="paper_overhead_")) / "paper"
    argv = [sys.executable, "-m", "rigsim.scenarios.cli.main", "paper", "--out", str(out), "--jobs", str(jobs), "--quiet"]
    if duration_s is not None:
        argv += ["--duration-s", f"{duration_s:g}"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(argv, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    shutil.rmtree(out.parent, ignore_errors=True)
    if proc.returncode != 0:
        raise SystemExit(f"rigsim paper failed ({proc.returncode}): {proc.stderr.strip()[-500:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2, help="worker processes for both (default 2)")
    ap.add_argument("--duration-s", type=float, default=None, help="the paper's --duration-s (default: its 60 s)")
    ap.add_argument("--repeats", type=int, default=1, help="alternate the two timings R times, keep the smallest")
    args = ap.parse_args(argv)
    if args.jobs < 1 or args.repeats < 1:
        raise SystemExit("--jobs and --repeats must be at least 1")
    steps = paper_steps(args.duration_s)
    byte_compile()
    papers, bares = [], []
    for _ in range(args.repeats):
        papers.append(time_paper(args.jobs, args.duration_s))
        bares.append(time_bare(steps, args.jobs))
    paper = min(papers, key=lambda r: r["wall_s"])
    bare = min(bares, key=lambda r: r["wall_s"])
    print(json.dumps({
        "steps": steps, "jobs": args.jobs, "cpu_count": os.cpu_count(), "duration_s": args.duration_s or 60.0,
        "paper_wall_s": round(paper["wall_s"], 2), "paper_cpu_s": round(paper["cpu_s"], 2),
        "bare_wall_s": round(bare["wall_s"], 2), "bare_cpu_s": round(bare["cpu_s"], 2),
        "bare_steps_per_s_per_worker": round(sum(steps.values()) / bare["cpu_s"], 0),
        "ratio_wall": round(paper["wall_s"] / bare["wall_s"], 3),
        "ratio_cpu": round(paper["cpu_s"] / bare["cpu_s"], 3),
        "goal_ratio_wall": 1.5,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
