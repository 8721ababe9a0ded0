"""What a rerun recording costs end to end: ``rigsim run`` with and without ``--rrd``.

::

    python benchmarks/recording_e2e.py [--durations 30 120] [--pairs 3] [--mode rig]

For each simulated duration, ``--pairs`` alternating pairs of whole commands (a fresh process
each: imports, the run, the files, and with ``--rrd`` the poses, rerun's import, the blueprint
and the .rrd file), in the order without/with, then with/without, so that a drift of the machine
does not favour one side. The smallest wall time of each side is kept (the least disturbed on a
shared machine). Prints one JSON line per duration: both times (s), the overhead (%) and the
extra seconds, the smallest CPU time (user + system) of each side with the processes the command
waited for (the recording process of ``--rrd``) and of the command's own process alone (what lies
on the critical path when the second core is free; a busy machine also charges the recording
process's CPU to the wall time: the load average before and after is printed with the number of
cores), and at the end the fixed part and the part per simulated minute (a line through the
durations' extra seconds). The command runs as ``python -m rigsim.scenarios.cli.main`` does, through
``-c`` so that it can report its own CPU time at exit. Goal: an overhead of at most 5 %.
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

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENARIO = "scenarios/data/paper/high_72kmh_3640kg.toml"


# ``rigsim run`` as ``python -m rigsim.scenarios.cli.main`` runs it, writing the CPU time of its own process
# (not of the processes it started) at exit to the file named by $E2E_OWN_CPU.
_COMMAND = """import atexit, os, resource, sys
def _own_cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    with open(os.environ["E2E_OWN_CPU"], "w") as fh:
        fh.write(repr(r.ru_utime + r.ru_stime))
atexit.register(_own_cpu)
from rigsim.scenarios.cli.main import main
sys.exit(main(sys.argv[1:]))
"""


def once(mode: str, duration_s: float, rrd: bool, tmp: pathlib.Path) -> tuple[float, float, float]:
    """Wall time, CPU time of the command and every process it waited for (the recording
    process of ``--rrd`` too) and CPU time of the command's own process (user + system), s."""
    out = tmp / "run"
    shutil.rmtree(out, ignore_errors=True)
    (tmp / "r.rrd").unlink(missing_ok=True)
    argv = [sys.executable, "-c", _COMMAND, "run", SCENARIO, "--mode", mode,
            "--duration-s", f"{duration_s:g}", "--out", str(out), "--quiet"]
    if rrd:
        argv += ["--rrd", str(tmp / "r.rrd")]
    env = {**os.environ, "E2E_OWN_CPU": str(tmp / "own_cpu")}
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(argv, cwd=ROOT, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"rigsim run failed: {proc.stderr.strip()[-400:]}")
    own = float((tmp / "own_cpu").read_text())
    return wall, (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime), own


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--durations", type=float, nargs="+", default=[30.0, 120.0], help="simulated s")
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--mode", choices=("road", "rig"), default="rig")
    args = ap.parse_args(argv)
    extra = {}
    with tempfile.TemporaryDirectory(prefix="recording_e2e_") as d:
        tmp = pathlib.Path(d)
        once(args.mode, 1.0, True, tmp)  # warm the file cache and the compiled callbacks' cache
        for dur in args.durations:
            load = os.getloadavg()[0]
            plain, rec = [], []
            for i in range(args.pairs):
                for with_rrd in ((False, True) if i % 2 == 0 else (True, False)):
                    (rec if with_rrd else plain).append(once(args.mode, dur, with_rrd, tmp))
            a, b = min(r[0] for r in plain), min(r[0] for r in rec)
            extra[dur] = b - a
            print(json.dumps({"duration_s": dur, "mode": args.mode, "without_s": round(a, 2), "with_rrd_s": round(b, 2),
                              "overhead_pct": round(100.0 * (b / a - 1.0), 1), "extra_s": round(b - a, 2),
                              "cpu_without_s": round(min(r[1] for r in plain), 2),
                              "cpu_with_rrd_s": round(min(r[1] for r in rec), 2),
                              "own_cpu_without_s": round(min(r[2] for r in plain), 2),
                              "own_cpu_with_rrd_s": round(min(r[2] for r in rec), 2),
                              "load_1min": [round(load, 1), round(os.getloadavg()[0], 1)], "cores": os.cpu_count(),
                              "goal_pct": 5.0}), flush=True)
    if len(extra) > 1:
        ds = sorted(extra)
        per_min = (extra[ds[-1]] - extra[ds[0]]) / ((ds[-1] - ds[0]) / 60.0)
        fixed = extra[ds[0]] - per_min * ds[0] / 60.0
        print(json.dumps({"fixed_s": round(fixed, 2), "per_simulated_min_s": round(per_min, 3)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
