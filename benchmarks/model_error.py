"""The model correction's fallback measure against its outcome, from a ``model_correction.py`` run.

::

    python benchmarks/model_correction.py --suite generalization > run.txt
    python benchmarks/model_error.py run.txt [more runs...] [--results docs/results]

For every calibrated row of the runs' JSON lines (the last line of each file): the fit NRMSE per
wheel (the calibrated model, pans following x_a, against the measured F_rig on the calibration
windows), the load cells' share of it (their noise over the force's std on the windows: the
calibration's own ``noise_nrmse`` where the run recorded it; where it did not, the plant's rig
test is run again (:func:`scenarios.studies.model_suite.plants.plant_job`), the same seed so the
same noise, and read as the calibration reads it, :func:`correction.identification.noise.noise_rms`) and the model error beyond it, sqrt(fit^2 - noise^2)
(:func:`~scenarios.records.model.result.model_error`, what the fallback,
``differential.HYBRID_LIMIT``, reads); beside them the outcome against the road: the
model correction's NRMSE over the linear floor and over the linear correction's NRMSE.

Prints one line per wheel sorted by model error; writes per plant the range of the model error,
and where it exceeds :data:`LARGE` the ratio of the corrected NRMSE to it (how far the model error
on the record predicts the correction's error against the road), to ``docs/results/model_error.md``
(``--results``: its folder), ending in the line that says how and where it was measured
(:mod:`scenarios.studies.results_page`), and prints that file.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

import numpy as np

from correction.identification.noise import noise_rms
from mjcf.names import CORNERS
from scenarios.core.pool import run_jobs
from scenarios.records.model.result import model_error
from scenarios.studies import scoring
from scenarios.studies.model_suite.plants import plant_job, plant_scenario
from scenarios.studies.results_page import script_command, write_results_page
from scenarios.studies.suites import case_name, pick_cases

#: A model error above this (1) is large enough for the corrected NRMSE to follow it.
LARGE = 0.06
#: Where the results file goes by default: docs/results of this repository.
RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"
HEADER = ("plant", "wheels", "model error", f"wheels above {LARGE:g}", "corrected NRMSE / model error there",
          "median")


def measured(case, duration_s: float, plant: str, tire_ratio: float, noise_N: float):
    """The plant's rig test again: (time, s; the measured force with the load cells' noise, N)."""
    sc = plant_scenario(case, duration_s, plant, tire_ratio)
    rig = plant_job(case, duration_s, plant, "rig", tire_ratio)
    return rig.t_s, scoring.measured_force(rig, noise_N, sc.seed)


def read_noise(cal: dict, t, force) -> np.ndarray:
    """The load cells' noise over the force's std on the calibration's windows, per wheel (1)."""
    scored = np.zeros(t.size, bool)
    for a, b in cal["windows_s"]:
        scored |= (t >= a - 1e-9) & (t < b - 1e-9)
    return noise_rms(force, 1.0 / (t[1] - t[0])) / force[scored].std(axis=0)


def wheels(run: dict) -> list[dict]:
    """Per wheel of every calibrated row of one run's JSON: fit, noise and model error (1), outcome."""
    dur, ratio = run["duration_s"], run["tire_ratio"]
    cases = {case_name(c): c for c in pick_cases(run["suite"], None, dur)}
    rows = [r for r in run["rows"] if r["calibration"]]
    rerun = [r for r in rows if not r["calibration"].get("noise_nrmse")]  # a run that did not record it
    forces = run_jobs([(measured, (cases[r["case"]], dur, r["plant_key"], ratio, run["noise_N"])) for r in rerun])
    noises = {id(r): read_noise(r["calibration"], t, force) for r, (t, force) in zip(rerun, forces)}
    out = []
    for r in rows:
        cal = r["calibration"]
        noise = noises.get(id(r), cal.get("noise_nrmse"))
        fit = cal["fit_nrmse"]
        error = model_error(fit, noise)
        w = r["wheels"]
        for i, c in enumerate(CORNERS):
            model = w["model"][c] if "model" in w else float("nan")
            out.append({"case": r["case"], "plant": r["plant_key"], "wheel": c, "fit": float(fit[i]),
                        "noise": float(noise[i]), "error": float(error[i]), "model": model,
                        "over_floor": model / w["floor"][c], "over_linear": model / w["linear"][c]})
    return out


def table_rows(rows: list[dict]) -> list[list[str]]:
    """Per plant (in the rows' order): its wheels, the range of their model error, and on the wheels
    whose model error exceeds :data:`LARGE` the range and median of the corrected NRMSE over it."""
    out = []
    for plant in dict.fromkeys(o["plant"] for o in rows):
        mine = [o for o in rows if o["plant"] == plant]
        err = np.array([o["error"] for o in mine])
        big = [o["model"] / o["error"] for o in mine if o["error"] > LARGE and np.isfinite(o["model"])]
        out.append([plant, str(len(mine)), f"{err.min():.3f}-{err.max():.3f}", str(len(big)),
                    f"{min(big):.2f}-{max(big):.2f}" if big else "-", f"{np.median(big):.2f}" if big else "-"])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=pathlib.Path,
                    help="output files of benchmarks/model_correction.py (their last line: the JSON)")
    ap.add_argument("--results", type=pathlib.Path, default=RESULTS,
                    help="folder of the results file model_error.md (default docs/results)")
    args = ap.parse_args(argv)
    rows, runs = [], []
    for p in args.runs:
        runs.append(json.loads(pathlib.Path(p).read_text().strip().splitlines()[-1]))
        rows += wheels(runs[-1])
    for o in sorted(rows, key=lambda o: o["error"]):
        print(f"{o['case'][:30]:30s} {o['plant']:5s} {o['wheel']}  fit {o['fit']:.3f}  noise {o['noise']:.3f}  "
              f"model error {o['error']:.3f}  corrected / floor {o['over_floor']:.2f}  / linear {o['over_linear']:.2f}")
    what = "; ".join(f"{r['suite']} suite, {r['duration_s']:g} s, tire ratio {r['tire_ratio']:g}" for r in runs)
    note = ("Model error: the calibrated model's fit NRMSE beyond the load cells' noise, sqrt(fit^2 - noise^2), "
            "per wheel, what the fallback reads; corrected NRMSE: the model correction's against the band-limited "
            f"road force. Runs of benchmarks/model_correction.py read: {what}.")
    page = write_results_page(args.results, "model_error", "The model correction's error against the model's error "
                              "on the record", HEADER, table_rows(rows), script_command(__file__, argv), note=note)
    print(page.read_text(encoding="utf-8"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
