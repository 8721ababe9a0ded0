"""The model correction's integration step: its truck runs' error and cost against a fine step.

::

    python benchmarks/model_step.py [--duration-s 12] [--steps-ms 1 2 3 4] [--results docs/results]

For each truck below, the rig test of its scenario (the design rig, its actuators lagging) gives
the pans' measured motion x_a at 1 kHz; the model truck (:func:`rigsim.scenarios.records.model.model_runs.model_forces`,
RK4, the pans following x_a, the forces splined from the steps onto the samples) is then run with
the same values at each step of ``--steps-ms`` and at a reference step of 0.25 ms (the second
method: the same equations integrated 4-16 times finer). Per truck and step: the forces' rms
difference from the reference over the std of the rig's force (the worst wheel, the first 2 s left
out: the model's start from rest), the rms of 100 N of load-cell noise on the same scale (what a
calibration cannot see below), and the run's wall time over the 1 ms run's (the median of three).

* the catalogue truck on the paper's high case (rigid cab), and on 2 Hz cab mounts;
* the shipped trucks ``scenarios/data/trucks/tractor_air.toml`` and ``rigid_long_leaf.toml``;
* ``rigid_long_leaf.toml`` with a frame that twists and bends at 6/9 Hz and an engine of 1 t on
  10 Hz mounts (what a fleet truck's model may fit, ``docs/fleet.md``);
* the generalization suite's gen15 (the catalogue truck empty on a class D road at 100 km/h), whose
  wheels leave their pans: the tire's kink at zero load, for which the model correction keeps the
  rig's step (:func:`rigsim.scenarios.records.model.model_runs.model_step`).

Writes ``docs/results/model_step.md`` (``--results``: its folder).
"""

from __future__ import annotations

import argparse
import dataclasses
import pathlib
import sys
import time

import numpy as np

from rigsim.scenarios.core.config import load_scenario, parse_scenario
from rigsim.scenarios.core.rig import MAX_KINEMATIC_STEP_S
from rigsim.scenarios.core.run import run
from rigsim.scenarios.records.model import model_runs
from rigsim.scenarios.studies.results_page import script_command, write_results_page
from rigsim.scenarios.studies.suites import generalization_cases

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"
#: The reference step, s.
REFERENCE_S = 2.5e-4
#: The load cells' noise the page compares with, N rms.
NOISE_N = 100.0
#: Left out of the comparison: the model's start from rest, s.
START_S = 2.0


def trucks(duration_s: float) -> list[tuple[str, object]]:
    """(label, scenario) of each truck of the page, each ``duration_s`` (s) long."""
    paper = load_scenario(ROOT / "scenarios" / "data" / "paper" / "high_72kmh_3640kg.toml")
    leaf = load_scenario(ROOT / "scenarios" / "data" / "trucks" / "rigid_long_leaf.toml")
    out = [("catalogue, rigid cab (paper high 72 km/h)", paper),
           ("catalogue, cab on 2 Hz mounts", dataclasses.replace(
               paper, vehicle=dataclasses.replace(paper.vehicle, cab_mount_hz=2.0))),
           ("tractor_air.toml", load_scenario(ROOT / "scenarios" / "data" / "trucks" / "tractor_air.toml")),
           ("rigid_long_leaf.toml", leaf),
           ("rigid_long_leaf.toml, frame 6/9 Hz, engine 1 t on 10 Hz", dataclasses.replace(
               leaf, vehicle=dataclasses.replace(leaf.vehicle, frame_torsion_hz=6.0, frame_bending_hz=9.0,
                                                 engine_mass_kg=1000.0, engine_mount_hz=10.0))),
           ("gen15: empty, class D, 100 km/h (wheels lift)", parse_scenario(generalization_cases(16)[15]))]
    return [(label, dataclasses.replace(sc, duration_s=duration_s)) for label, sc in out]


def forces(scenario, t_s, x_a_m, step_s: float) -> tuple[np.ndarray, float]:
    """The model truck's forces (N) at ``step_s`` (s) and the wall time (s) of the run, the median of three."""
    saved = model_runs.MODEL_STEP_S
    model_runs.MODEL_STEP_S = step_s
    try:
        walls, out = [], None
        for _ in range(3):
            t0 = time.perf_counter()
            out = model_runs.model_forces(scenario.vehicle, t_s, x_a_m, base_scenario=scenario)
            walls.append(time.perf_counter() - t0)
    finally:
        model_runs.MODEL_STEP_S = saved
    return out, float(np.median(walls))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration-s", type=float, default=12.0, help="each rig test's length, s")
    ap.add_argument("--steps-ms", type=float, nargs="+", default=[1.0, 2.0, 3.0, 4.0], help="the steps compared, ms")
    ap.add_argument("--results", default=str(RESULTS), help="folder of model_step.md")
    args = ap.parse_args(argv)
    if args.duration_s <= START_S + 1.0:
        ap.error(f"--duration-s must exceed {START_S + 1.0:g} s (the start left out and a second scored)")
    if any(not 0.25 < s <= 1e3 * MAX_KINEMATIC_STEP_S for s in args.steps_ms):
        ap.error(f"--steps-ms must lie in (0.25, {1e3 * MAX_KINEMATIC_STEP_S:g}] ms, got {args.steps_ms}")
    rows = []
    for label, sc in trucks(args.duration_s):
        rig = run(sc, "rig")
        t, x_a, f_rig = np.asarray(rig.t_s), rig.signals["pan_m"], rig.signals["tire_force_N"]
        scored = t - t[0] >= START_S
        norm = f_rig[scored].std(axis=0)
        ref, _ = forces(sc, t, x_a, REFERENCE_S)
        _, wall_1ms = forces(sc, t, x_a, 1e-3)
        for step_ms in args.steps_ms:
            f, wall = forces(sc, t, x_a, step_ms * 1e-3)
            err = np.sqrt(np.mean((f - ref)[scored] ** 2, axis=0)) / norm
            worst = np.abs(f - ref)[scored].max()
            rows.append([label, f"{step_ms:g}", f"{err.max():.5f}", f"{worst:.0f}", f"{(NOISE_N / norm).min():.4f}",
                         f"{wall / wall_1ms:.2f}"])
            print(" | ".join(rows[-1]), flush=True)
    head = ("truck", "step ms", "force error / std (worst wheel)", "largest error N", f"{NOISE_N:g} N noise / std (least)",
            "wall / 1 ms run")
    note = (f"Each truck's model run on its rig test's measured pan motion ({args.duration_s:g} s, 1 kHz, the first "
            f"{START_S:g} s left out), RK4 at each step against the same run at {REFERENCE_S * 1e3:g} ms. The model "
            f"correction runs at {model_runs.MODEL_STEP_S * 1e3:g} ms "
            "(`rigsim.scenarios.records.model.model_runs.MODEL_STEP_S`), or at the rig's step where a record's "
            "wheels lift (`model_step`).")
    write_results_page(args.results, "model_step", "The model correction's integration step: error and cost of "
                       "its truck runs", head, rows, script_command(__file__, argv), note=note)
    return 0


if __name__ == "__main__":
    sys.exit(main())
