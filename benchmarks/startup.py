"""Fixed cost of a ``rigsim`` process: start-up of the help and of a short rig run.

Each command runs as its own process (``python -m rigsim.scenarios.cli.main ...`` from this tree, the
same code as the ``rigsim`` console script), ``--repeats`` times (default 5); the median wall
time (``time.perf_counter`` around ``subprocess.run``) is kept:

* ``help_s``: ``rigsim --help``; ``correct_help_s``: ``rigsim correct --help``;
* ``python_s``: ``python -c pass`` (the interpreter alone, for reference);
* ``rig_warm_s``: ``rigsim run high_72kmh_3640kg.toml --mode rig --duration-s 0.5`` with a warm
  numba cache (a private ``RIGSIM_CACHE_DIR``, filled by one untimed run first);
* ``rig_nocache_s``: the same run with ``RIGSIM_NO_CACHE=1`` (callbacks compiled in the process).

The simulated steps' share of a rig run is ``steps / rig_steps_per_s``: ``steps`` is the run's
own count (``info.simulated_steps`` in its ``result.json``, lead-in included), the rate is
measured here on the very model the run builds (:class:`rigsim.scenarios.core.rig.Rig` of the same
scenario), with the hydraulic callbacks installed and ``mujoco.rollout`` stepping the drive
from rest (fastest of 3). ``fixed_warm_s`` / ``fixed_nocache_s`` = run time minus that share:
imports, compilation (or cache load), model building, linearization, writing the files.

Printed as one JSON line with the times (s; each also as ``*_cpu_s``, the process's user +
system CPU time, steadier than the wall time when other work shares the machine), the rate, and
the ratios ``nocache_over_warm`` (rig run) and ``help_over_python``.

Usage::

    python benchmarks/startup.py [--repeats 5] [--duration-s 0.5]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "data" / "paper" / "high_72kmh_3640kg.toml"


def _cpu_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _timed(argv: list[str], env: dict, repeats: int) -> tuple[float, float]:
    """Median wall time and median CPU time (user + system), s, of ``repeats`` runs of ``argv``
    (each must exit 0). The CPU time is the steadier figure on a shared machine."""
    times, cpu = [], []
    for _ in range(repeats):
        c0 = _cpu_children()
        t0 = time.perf_counter()
        proc = subprocess.run(argv, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        times.append(time.perf_counter() - t0)
        cpu.append(_cpu_children() - c0)
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(argv)} failed: {proc.stderr.decode()[-2000:]}")
    return statistics.median(times), statistics.median(cpu)


def rig_step_rate(duration_s: float, repeats: int = 3) -> tuple[float, int]:
    """(steps/s, steps): the rig model of the benchmark's scenario stepped from rest through its
    road drive with ``mujoco.rollout`` and the compiled hydraulic callbacks (fastest of ``repeats``)."""
    import mujoco
    import numpy as np
    from mujoco import rollout

    from rigsim.hydraulics.bridge import hydraulic_callbacks
    from rigsim.scenarios.core.config import load_scenario
    from rigsim.scenarios.core.rig import Rig

    scenario = dataclasses.replace(load_scenario(SCENARIO), duration_s=duration_s)
    rig = Rig(scenario, hydraulic=True)
    drive = rig.road_drive()
    model = rig.model
    ctrl = np.zeros((drive.t_s.size, model.nu))
    ctrl[:, rig.actuators] = drive.z_m
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    best = np.inf
    for _ in range(repeats):
        data = rig.rest_state()
        state = np.empty(mujoco.mj_stateSize(model, kind))
        mujoco.mj_getState(model, data, state, kind)
        with hydraulic_callbacks(model):
            t0 = time.perf_counter()
            rollout.rollout(model, data, state, ctrl, initial_warmstart=data.qacc_warmstart.copy())
            best = min(best, time.perf_counter() - t0)
    return drive.t_s.size / best, int(drive.t_s.size)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--duration-s", type=float, default=0.5)
    args = ap.parse_args(argv)

    py = sys.executable
    cli = [py, "-m", "rigsim.scenarios.cli.main"]
    base = {k: v for k, v in os.environ.items() if k not in ("RIGSIM_NO_CACHE", "RIGSIM_CACHE_DIR")}
    with tempfile.TemporaryDirectory() as tmp:
        warm_env = dict(base, RIGSIM_CACHE_DIR=str(pathlib.Path(tmp) / "cache"))
        cold_env = dict(base, RIGSIM_NO_CACHE="1")
        out = pathlib.Path(tmp) / "run"
        run = cli + ["run", str(SCENARIO), "--mode", "rig", "--out", str(out),
                     "--duration-s", f"{args.duration_s:g}", "--quiet", "--force"]
        result = {}
        for name, argv, env in (("python", [py, "-c", "pass"], base), ("help", cli + ["--help"], base),
                                ("correct_help", cli + ["correct", "--help"], base)):
            result[f"{name}_s"], result[f"{name}_cpu_s"] = _timed(argv, env, args.repeats)
        _timed(run, warm_env, 1)  # fills the cache
        result["rig_warm_s"], result["rig_warm_cpu_s"] = _timed(run, warm_env, args.repeats)
        result["rig_nocache_s"], result["rig_nocache_cpu_s"] = _timed(run, cold_env, args.repeats)
        info = json.loads((out / "result.json").read_text())["info"]
        os.environ["RIGSIM_CACHE_DIR"] = warm_env["RIGSIM_CACHE_DIR"]  # not the user's cache
        os.environ.pop("RIGSIM_NO_CACHE", None)
        rate, steps_here = rig_step_rate(args.duration_s)
    steps = int(info["simulated_steps"])
    if steps_here != steps:
        raise RuntimeError(f"the rate was measured on {steps_here} steps, the run took {steps}")
    step_share = steps / rate
    result.update({
        "duration_s": args.duration_s,
        "repeats": args.repeats,
        "simulated_steps": steps,
        "rig_steps_per_s": round(rate, 1),
        "step_share_s": step_share,
        "fixed_warm_s": result["rig_warm_s"] - step_share,
        "fixed_nocache_s": result["rig_nocache_s"] - step_share,
        "fixed_warm_cpu_s": result["rig_warm_cpu_s"] - step_share,
        "fixed_nocache_cpu_s": result["rig_nocache_cpu_s"] - step_share,
    })
    result["nocache_over_warm"] = result["rig_nocache_s"] / result["rig_warm_s"]
    result["help_over_python"] = result["help_s"] / result["python_s"]
    result = {k: round(v, 3) if isinstance(v, float) else v for k, v in result.items()}
    print(json.dumps(result))
    return result


if __name__ == "__main__":
    main()
