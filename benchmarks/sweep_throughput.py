"""Sweep throughput: cases per minute on 1 and 2 workers, and the speed-up (target >= 1.9x on 2 cores).

::

    python benchmarks/sweep_throughput.py [--cases 6] [--duration-s 8] [--executor local|dask]

Every case is the same scenario with another road seed (equal cost), run in road and rig mode
and corrected (:func:`rigsim.scenarios.studies.sweep.case.evaluate_case`). The workers are warmed up first
(imports and the hydraulic kernels' compilation, a few seconds per process), so the figure is
the steady throughput of a long sweep. Prints one JSON line with, for judging the speed-up on a
shared machine, its load average and ``machine_speedup``: the speed-up of pure-Python CPU work on
2 processes against 1 at the same time (2.0 on two idle cores).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import pathlib
import sys
import tempfile
import time

from rigsim.scenarios.core.pool import local_executor
from rigsim.scenarios.studies.sweep.executors import dask_executor
from rigsim.scenarios.studies.sweep.grid import parse_grid
from rigsim.scenarios.studies.sweep.run import run_sweep

TARGET_SPEEDUP = 1.9


def _grid(cases: int, duration_s: float, source: pathlib.Path):
    doc = {
        "sweep": {"name": "throughput"},
        "base": {"name": "throughput", "speed_kmh": 72.0, "duration_s": duration_s, "lead_in_s": 1.0,
                 "road": {"roughness": "high"}, "vehicle": {"payload_kg": 3640.0}},
        "axes": {"seed": list(range(1, cases + 1))},
    }
    return parse_grid(doc, source=source)


@contextlib.contextmanager
def _executor(kind: str, workers: int):
    if kind == "local":
        with local_executor(workers) as ex:
            yield ex
        return
    import distributed

    with distributed.LocalCluster(n_workers=workers, processes=True, threads_per_worker=1,
                                  dashboard_address=None, silence_logs=50) as cluster:
        with dask_executor(cluster.scheduler_address) as ex:
            yield ex


def _burn(n: int) -> float:
    """Pure-Python CPU work (no MuJoCo, no I/O); returns its own duration in s."""
    t0 = time.perf_counter()
    acc = 0
    for i in range(n):
        acc += i * i
    return time.perf_counter() - t0


def machine_speedup(n: int = 4_000_000) -> float:
    """What the machine gives two processes now: 1-process over 2-process time for 4 equal jobs.

    2.0 on two idle cores; lower when other work shares them. The sweep's speed-up can only be
    judged against this.
    """
    import concurrent.futures as cf

    times = []
    for workers in (1, 2):
        with cf.ProcessPoolExecutor(workers) as pool:
            list(pool.map(_burn, [1000] * workers))  # start the processes
            t0 = time.perf_counter()
            list(pool.map(_burn, [n] * 4))
            times.append(time.perf_counter() - t0)
    return times[0] / times[1]


def measure(kind: str, workers: int, cases: int, duration_s: float, tmp: pathlib.Path) -> dict:
    """Warm ``workers`` workers, then run ``cases`` cases; returns wall time and cases per minute."""
    with _executor(kind, workers) as ex:
        warm = _grid(workers, 1.0, tmp / "warm.toml")
        warm = type(warm)(name=warm.name, source=warm.source, axes=warm.axes, cases=warm.cases,
                          settings=type(warm.settings)(actuator="eq4", lowpass="paper", correction_mode="causal",
                                                        settling_tolerance=0.2))  # warm-up: imports, compilation
        run_sweep(warm, tmp / f"warm-{kind}-{workers}", ex, progress=False, plot=False)
        grid = _grid(cases, duration_s, tmp / "grid.toml")
        t0 = time.perf_counter()
        outcome = run_sweep(grid, tmp / f"run-{kind}-{workers}", ex, progress=False, plot=False)
        wall = time.perf_counter() - t0
    if outcome.failed:
        raise SystemExit(f"{outcome.failed} benchmark cases failed; see {tmp}")
    return {"wall_time_s": round(wall, 2), "cases_per_min": round(60.0 * cases / wall, 2)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=6, help="cases per measurement (default 6; even for 2 workers)")
    ap.add_argument("--duration-s", type=float, default=8.0,
                    help="record length of each case in s (default 8: the identified T_a needs ~8 s)")
    ap.add_argument("--executor", choices=("local", "dask"), default="local")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="rigsim-sweep-bench-") as d:
        tmp = pathlib.Path(d)
        one = measure(args.executor, 1, args.cases, args.duration_s, tmp)
        two = measure(args.executor, 2, args.cases, args.duration_s, tmp)
    speedup = two["cases_per_min"] / one["cases_per_min"]
    print(json.dumps({
        "executor": args.executor, "cases": args.cases, "duration_s": args.duration_s,
        "workers_1": one, "workers_2": two, "speedup": round(speedup, 3), "target": TARGET_SPEEDUP,
        "meets_target": speedup >= TARGET_SPEEDUP, "cpu_count": os.cpu_count(),
        "machine_speedup": round(machine_speedup(), 3),
        "load_average_1min": round(os.getloadavg()[0], 2),
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
