"""Where ``rigsim paper``'s CPU goes: the physics against everything around it, stage by stage.

::

    python benchmarks/paper_breakdown.py [--duration-s 60]

``benchmarks/paper_overhead.py`` compares the command's wall time with bare MuJoCo's for the same
steps (goal: at most 1.5x). This script says what the rest is. It runs the jobs of
``rigsim paper`` one after the other in this process, exactly as its workers do
(:mod:`rigsim.scenarios.studies.paper.compute`'s job functions ``identify_job``, ``run_job`` and
``case_job``, with the files the command's ``finish_run`` and ``finish`` write, then the report
the parent renders), and charges the CPU time (``time.process_time``,
s; this process only, so a busy machine disturbs it little) to stages:

* ``physics``: inside ``mujoco.rollout.rollout`` (every run's and identification's stepping, the
  hydraulic callbacks included: ``benchmarks/step_rate.py`` measures their share of it);
* ``identification``, ``road run``, ``rig run``: the rest of each job (drives, poses of the
  record, statistics, the frequency-response estimate and fits);
* ``run files``: each run's ``result.json`` and ``timeseries.csv`` (``write_case_run``);
* ``scoring``: the corrections and metrics of a case (``score_pair``);
* ``figures``: the case's Figure 8 analogue and damage figure (``write_case``); the first case
  pays matplotlib's first draw (fonts, text layout), as each worker of the command does once;
* ``report``: Table 2's bars, ``report.md``, ``paper.json``;
* ``imports``: a fresh interpreter importing what the command's parent imports before its pool
  starts (measured in a subprocess, CPU of that process).

Prints one JSON line: the seconds per stage, the non-physics total, its ratio to the physics, and
the share the goal leaves: on J cores with perfect packing, wall <= 1.5 x bare needs the
non-physics CPU within 0.5 x the physics' CPU (the parent's serial imports count J times).
Goal: ``non_physics_over_physics`` at most 0.5.
"""

from __future__ import annotations

import argparse
import functools
import gc
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
#: What ``rigsim paper``'s parent imports before it starts its pool (scenarios/studies/paper/command.py).
PARENT_IMPORTS = ("import rigsim.scenarios.cli.main, rigsim.scenarios.studies.paper.compute, rigsim.scenarios.studies.paper.report, "
                  "rigsim.scenarios.studies.scoring, rigsim.scenarios.core.files, rigsim.scenarios.core.outputs")


def import_cpu_s() -> float:
    """CPU time (s) of a fresh interpreter importing :data:`PARENT_IMPORTS` with the collector off,
    as the command imports them (best of three)."""
    code = f"import gc, resource; gc.disable(); {PARENT_IMPORTS}; r = resource.getrusage(resource.RUSAGE_SELF); " \
           "print(r.ru_utime + r.ru_stime)"
    env = {**os.environ, "MUJOCO_GL": "disable"}
    runs = [float(subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True, text=True,
                                 check=True).stdout) for _ in range(3)]
    return min(runs)


class _Clock:
    """CPU seconds per stage; time inside ``mujoco.rollout.rollout`` goes to ``physics``."""

    def __init__(self) -> None:
        self.s: dict[str, float] = {}
        self._in_rollout = 0.0

    def add(self, stage: str, seconds: float) -> None:
        self.s[stage] = self.s.get(stage, 0.0) + seconds

    def wrap_rollout(self):
        from mujoco import rollout

        original = rollout.rollout

        @functools.wraps(original)
        def timed(*args, **kwargs):
            t = time.process_time()
            try:
                return original(*args, **kwargs)
            finally:
                dt = time.process_time() - t
                self._in_rollout += dt
                self.add("physics", dt)

        rollout.rollout = timed
        return original

    def stage(self, name: str, fn, *args):
        """Run ``fn(*args)``, charging its CPU to ``name`` less what it spent stepping."""
        stepped, t = self._in_rollout, time.process_time()
        result = fn(*args)
        self.add(name, time.process_time() - t - (self._in_rollout - stepped))
        return result


def breakdown(duration_s: float | None) -> dict:
    """CPU seconds per stage of the paper's jobs run serially (see the module's description)."""
    from mujoco import rollout

    from rigsim.scenarios.core.config import paper_scenarios
    from rigsim.scenarios.core.files import to_json
    from rigsim.scenarios.studies.paper import compute
    from rigsim.scenarios.studies.paper.report import render_report, write_case, write_case_run
    from rigsim.scenarios.studies.scoring import NOISE_N

    gc.freeze()  # as the command does with its imports' objects before its pool starts
    clock = _Clock()
    original = clock.wrap_rollout()
    out = pathlib.Path(tempfile.mkdtemp(prefix="paper_breakdown_"))
    cases = []
    try:
        for p in paper_scenarios():
            sc = compute.case_scenario(p, duration_s)
            ident = clock.stage("identification", compute.identify_job, str(p), duration_s)
            road = clock.stage("road run", compute.run_job, str(p), "road", duration_s)
            rig = clock.stage("rig run", compute.run_job, str(p), "rig", duration_s)
            for r in (road, rig):
                clock.stage("run files", write_case_run, r, out)
            score = clock.stage("scoring", compute.case_job, str(p), duration_s, NOISE_N, road, rig, ident, None)
            case = compute.PaperCase(scenario=sc, road=road, rig=rig, identification=ident, score=score)
            clock.stage("figures", write_case, case, out)
            cases.append(case)
        result = compute.PaperResult(cases=tuple(cases), noise_N=NOISE_N)
        clock.stage("report", lambda: (render_report(result, case_files=False), to_json(result)))
    finally:
        rollout.rollout = original
        shutil.rmtree(out, ignore_errors=True)
    return clock.s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration-s", type=float, default=None, help="the paper's --duration-s (default: its 60 s)")
    ap.add_argument("--jobs", type=int, default=2, help="cores of the command (for the goal's share; default 2)")
    args = ap.parse_args(argv)
    stages = breakdown(args.duration_s)
    stages["imports"] = import_cpu_s()
    physics = stages["physics"]
    rest = {k: v for k, v in stages.items() if k != "physics"}
    other = sum(rest.values()) + (args.jobs - 1) * stages["imports"]  # serial imports: J cores idle meanwhile
    print(json.dumps({
        "duration_s": args.duration_s or 60.0, "jobs": args.jobs,
        "cpu_s": {k: round(v, 2) for k, v in sorted(stages.items(), key=lambda kv: -kv[1])},
        "physics_cpu_s": round(physics, 2), "non_physics_cpu_s": round(other, 2),
        "non_physics_over_physics": round(other / physics, 3),
        "goal_non_physics_over_physics": 0.5,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
