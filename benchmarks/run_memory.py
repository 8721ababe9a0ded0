"""Peak memory of ``rigsim run`` against the simulated duration: what grows with the record.

::

    python benchmarks/run_memory.py [--durations 10 120 600] [--mode rig]

Runs ``rigsim run scenarios/data/paper/high_72kmh_3640kg.toml --mode MODE --duration-s D`` in a
fresh process per duration and reads its peak resident memory (``getrusage`` of the finished
child, ``ru_maxrss``). Prints one JSON line: the peak per duration (MB), the fixed part (the
shortest run: interpreter, MuJoCo, numpy, scipy, numba, the model), the slope (MB per simulated
minute: the record; the drive is made chunk by chunk and not held) and the size of the output
(``timeseries.csv``, MB) for comparison. Goal: a 600 s run under 400 MB
(``goal_met``, when 600 s is among the durations).

What the peak is made of: the imports (numpy, scipy.signal with scipy.stats, MuJoCo, numba),
the model and the hydraulic callbacks (numba's code generator loading the cached machine code),
the road profile read during the run, and the record (25 float64 columns at 1 kHz: 12 MB per
simulated minute). The statistics and ``timeseries.csv`` work block by block after the run,
within what the profile freed.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import resource
import shutil
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENARIO = "scenarios/data/paper/high_72kmh_3640kg.toml"
#: Peak of a 600 s run to stay under, MB (1e6 bytes).
GOAL_MB = 400.0


def peak_mb(mode: str, duration_s: float) -> tuple[float, float]:
    """(peak resident memory of the run, MB; size of its timeseries.csv, MB)."""
    out = pathlib.Path(tempfile.mkdtemp(prefix="run_memory_")) / "run"
    argv = [sys.executable, "-c",
            "import resource, sys; from rigsim.scenarios.cli.main import main; rc = main(sys.argv[1:]); "
            "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr); sys.exit(rc)",
            "run", SCENARIO, "--mode", mode, "--duration-s", f"{duration_s:g}", "--out", str(out), "--quiet"]
    proc = subprocess.run(argv, cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"rigsim run failed: {proc.stderr.strip()[-400:]}")
    kb = int(proc.stderr.strip().splitlines()[-1])  # ru_maxrss is in KiB on Linux
    size = (out / "timeseries.csv").stat().st_size / 1e6
    shutil.rmtree(out.parent, ignore_errors=True)
    return kb * 1024 / 1e6, size


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--durations", type=float, nargs="+", default=[10.0, 120.0, 600.0], help="simulated s")
    ap.add_argument("--mode", choices=("road", "rig"), default="rig")
    args = ap.parse_args(argv)
    if resource.getrlimit(resource.RLIMIT_AS)[0] not in (resource.RLIM_INFINITY,):
        print("note: an address-space limit is set; peaks above it fail", file=sys.stderr)
    rows = {d: peak_mb(args.mode, d) for d in sorted(args.durations)}
    ds = sorted(rows)
    slope = (rows[ds[-1]][0] - rows[ds[0]][0]) / ((ds[-1] - ds[0]) / 60.0) if len(ds) > 1 else float("nan")
    report = {"mode": args.mode, "peak_mb": {f"{d:g}": round(rows[d][0], 1) for d in ds},
              "csv_mb": {f"{d:g}": round(rows[d][1], 1) for d in ds},
              "fixed_mb": round(rows[ds[0]][0], 1), "mb_per_simulated_min": round(slope, 1),
              "goal": f"600 s under {GOAL_MB:g} MB"}
    if 600.0 in rows:
        report["goal_met"] = rows[600.0][0] < GOAL_MB
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
