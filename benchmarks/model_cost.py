"""What the truck-model correction costs a user: ``rigsim correct --model`` timed on a lab's file.

::

    python benchmarks/model_cost.py [--duration-s 60] [--case high_72kmh_3640kg] [--cab held auto]
                                    [--plant-cab rigid 2] [--workers 2] [--repeat 3] [--results docs/results]

The rig test of a paper case (``scenarios/data/paper``, the design rig) is written as a lab's CSV
(forces in kN with 100 N rms of load-cell noise, seeded; each post's drive and LVDT in mm), once
per plant truck (``--plant-cab``: the catalogue truck's rigid cab, and the cab on its own mounts of
that frequency in Hz, which ``--cab auto`` fits in a second calibration), then corrected as a user
would, each command a fresh process, timed from start to exit (wall and the children's CPU), each
``--repeat`` times in turn, the median kept (a shared machine's speed drifts by 10-25 % within
minutes; the linear baseline, repeated alike, shows it):

* the baseline, ``rigsim correct --actuators`` after ``rigsim identify --from-file`` (the linear
  correction, T_a identified from the same file), measured in the same run;
* ``rigsim correct --model SCENARIO --pairs ...`` with each ``--cab`` asked for: the calibration of
  the truck model on the file and its correction.

The goal (the model correction's cost): a record calibrated and corrected with the defaults
(``--cab auto``) in at most half its own duration on 2 cores, i.e. wall / record length <= 0.5
(:data:`GOAL`: 30 s for a 60 s record); ``--cab held`` is timed beside it. Prints one row per command (wall s, CPU
s, wall over the record's length, over the linear correction's) and writes them to
``docs/results/model_cost.md`` (``--results``: its folder).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import pathlib
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.config import load_scenario, paper_scenarios
from rigsim.scenarios.studies.lab_record import write_lab_record
from rigsim.scenarios.studies.results_page import script_command, write_results_page

RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"
#: The goal: the default model correction's (``--cab auto``) wall time over the record's length, 1.
GOAL = 0.5
PAIRS = ",".join(f"{c}=Soll_{c.upper()}:Weg_{c.upper()}" for c in CORNERS)
FORCES = ",".join(f"{c}=Fz_{c.upper()}" for c in CORNERS)


def write_record(path: pathlib.Path, scenario_path: pathlib.Path, duration_s: float, noise_N: float = 100.0,
                 cab_hz: float | None = None) -> None:
    """The rig test of ``scenario_path`` (``duration_s``, s; the truck's cab on ``cab_hz`` mounts, Hz,
    None: rigid) as a lab's CSV at ``path``."""
    sc = load_scenario(scenario_path)
    sc = dataclasses.replace(sc, duration_s=duration_s, vehicle=dataclasses.replace(sc.vehicle, cab_mount_hz=cab_hz))
    write_lab_record(path, sc, noise_N)


def timed(argv: list[str], env: dict) -> tuple[float, float]:
    """Run ``argv`` to its end: (wall s, CPU s of it and its children). Exits on a failed command."""
    cpu0 = sum(resource.getrusage(resource.RUSAGE_CHILDREN)[:2])
    t0 = time.perf_counter()
    done = subprocess.run(argv, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        sys.exit(f"{' '.join(argv)} failed ({done.returncode}): {done.stderr.strip() or done.stdout.strip()}")
    return wall, sum(resource.getrusage(resource.RUSAGE_CHILDREN)[:2]) - cpu0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration-s", type=float, default=60.0, help="the record's length, s")
    ap.add_argument("--case", default="high_72kmh_3640kg", help="the paper case (a file stem of scenarios/data/paper)")
    ap.add_argument("--cab", nargs="+", default=["held", "auto"], choices=("held", "fitted", "auto"),
                    help="the --cab of each model correction timed")
    ap.add_argument("--plant-cab", nargs="+", default=["rigid", "2"],
                    help="the plant truck's cab: rigid, or on mounts of this frequency (Hz); one record each")
    ap.add_argument("--workers", type=int, default=2, help="worker processes of the model correction (--jobs)")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each command, the median kept")
    ap.add_argument("--results", default=str(RESULTS), help="folder of model_cost.md")
    args = ap.parse_args(argv)
    if args.repeat < 1:
        ap.error(f"--repeat must be at least 1, got {args.repeat}")
    paths = {p.stem: p for p in paper_scenarios()}
    if args.case not in paths:
        ap.error(f"--case must be one of {', '.join(paths)}")
    try:
        plants = [None if c == "rigid" else float(c) for c in args.plant_cab]
    except ValueError:
        ap.error(f"--plant-cab takes rigid or a mount frequency in Hz, got {' '.join(args.plant_cab)}")
    rigsim = str(pathlib.Path(sys.executable).with_name("rigsim"))
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    rows, model_walls = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k, cab_hz in enumerate(plants):
            truck = "rigid cab" if cab_hz is None else f"cab on {cab_hz:g} Hz mounts"
            folder = pathlib.Path(tmp) / str(k)
            folder.mkdir()
            rec = folder / "messung.csv"
            write_record(rec, paths[args.case], args.duration_s, cab_hz=cab_hz)
            times = {key: [] for key in ["linear", *args.cab]}
            for r in range(args.repeat):  # in turn, so that a drift of the machine's speed reaches every command
                ident = folder / f"ident{r}"  # each run its own outputs: the commands refuse to replace one
                i = timed([rigsim, "identify", "--from-file", str(rec), "--pairs", PAIRS, "--out", str(ident)], env)
                c = timed([rigsim, "correct", str(rec), "--actuators", str(ident / "actuators.toml"), "--map", FORCES,
                           "-o", str(folder / f"linear{r}.csv"), "--quiet"], env)
                times["linear"].append((i[0] + c[0], i[1] + c[1]))
                for cab in args.cab:
                    times[cab].append(timed([rigsim, "correct", str(rec), "--model", str(paths[args.case]), "--pairs",
                                             PAIRS, "-o", str(folder / f"model_{cab}{r}.csv"), "--quiet", "--cab", cab,
                                             "--jobs", str(args.workers)], env))
            median = {key: tuple(float(v) for v in np.median(np.asarray(t), axis=0)) for key, t in times.items()}
            base = median["linear"]
            rows.append([truck, "linear: identify --from-file + correct --actuators", base, base[0]])
            for cab in args.cab:
                rows.append([truck, f"model: correct --model --cab {cab}", median[cab], base[0]])
                if cab == "auto":
                    model_walls.append(median[cab][0])
    table = [[truck, what, f"{wall:.1f}", f"{cpu:.1f}", f"{wall / args.duration_s:.2f}", f"{wall / base:.1f}"]
             for truck, what, (wall, cpu), base in rows]
    head = ("plant truck", "command", "wall s", "CPU s", "wall / record length", "wall / linear")
    print(" | ".join(head))
    for r in table:
        print(" | ".join(r))
    worst = max(model_walls, default=float("nan")) / args.duration_s
    goal = (f"goal: the default model correction (--cab auto) in at most half the record's length (wall / record "
            f"length <= {GOAL:g}): {'met' if worst <= GOAL else 'not met'} (worst {worst:.2f})" if model_walls
            else "the default (--cab auto) not timed")
    note = (f"A {args.duration_s:g} s record of `scenarios/data/paper/{args.case}.toml` (design rig, 100 N load-cell "
            f"noise) per plant truck, on {args.workers} cores, the median of {args.repeat} runs of each command "
            f"(wall and CPU each); {goal}.")
    print(note)
    write_results_page(args.results, "model_cost", "What the truck-model correction costs: one record, each command "
                       "a fresh process", head, table, script_command(__file__, argv), note=note)
    return 0


if __name__ == "__main__":
    sys.exit(main())
