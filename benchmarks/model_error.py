"""The model correction's fallback measure against its outcome, from a ``model_correction.py`` run.

::

    python benchmarks/model_correction.py --suite generalization > run.txt
    python benchmarks/model_error.py run.txt [more runs...] [--results docs/results]

For every calibrated row of the runs' JSON lines (the last line of each file): the model error per
wheel as the fallback (``fallback.HYBRID_LIMIT``) reads it,
:attr:`~rigsim.scenarios.records.model.result.Calibration.excess_nrmse`: the calibrated model's residual
against the measured F_rig on the calibration windows in the correction's band (its mean per window
taken out), beyond the load cells' noise there, sqrt(band^2 - noise^2); beside it the outcome
against the road: the model correction's NRMSE over the linear floor and over the linear
correction's NRMSE.

Prints one line per wheel sorted by model error; writes per plant the range of the model error,
and where it exceeds :data:`LARGE` the ratio of the corrected NRMSE to it (how far the model error
on the record predicts the correction's error against the road), to ``docs/results/model_error.md``
(``--results``: its folder), ending in the line that says how and where it was measured
(:mod:`rigsim.scenarios.studies.results_page`), and prints that file.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import pathlib
import sys

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.records.model.fallback import HYBRID_LIMIT
from rigsim.scenarios.records.model.result import Calibration
from rigsim.scenarios.studies.results_page import script_command, write_results_page

#: A model error above this (1) is large enough for the corrected NRMSE to follow it.
LARGE = 0.06
#: Where the results file goes by default: docs/results of this repository.
RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"
HEADER = ("plant", "wheels", "model error", f"wheels above {LARGE:g}", "corrected NRMSE / model error there",
          "median")


def calibration(cal: dict) -> Calibration:
    """The run's calibration (its JSON object) as the correction holds it; a run that did not record
    the band figures cannot be read as the fallback reads it."""
    if not cal.get("band_nrmse"):
        raise SystemExit("a run without the calibration's band figures (band_nrmse): run "
                         "benchmarks/model_correction.py again")
    fields = {f.name for f in dataclasses.fields(Calibration)}
    return Calibration(**{k: tuple(v) if isinstance(v, list) else v for k, v in cal.items() if k in fields})


def wheels(run: dict) -> list[dict]:
    """Per wheel of every calibrated row of one run's JSON: band fit, noise and model error (1), outcome."""
    out = []
    for r in (r for r in run["rows"] if r["calibration"]):
        cal = calibration(r["calibration"])
        _, fit, noise = cal.error_figures()
        error = cal.excess_nrmse
        w = r["wheels"]
        for i, c in enumerate(CORNERS):
            # a wheel past the limit is corrected linearly: no model NRMSE to set beside its error
            model = w["model"][c] if "model" in w and error[i] <= HYBRID_LIMIT else float("nan")
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
        print(f"{o['case'][:30]:30s} {o['plant']:5s} {o['wheel']}  band {o['fit']:.3f}  noise {o['noise']:.3f}  "
              f"model error {o['error']:.3f}  corrected / floor {o['over_floor']:.2f}  / linear {o['over_linear']:.2f}")
    what = "; ".join(f"{r['suite']} suite, {r['duration_s']:g} s, tire ratio {r['tire_ratio']:g}" for r in runs)
    note = ("Model error: the calibrated model's residual on the calibration windows in the correction's band beyond "
            "the load cells' noise there, sqrt(band^2 - noise^2), per wheel, what the fallback reads; corrected NRMSE: the model correction's against the band-limited "
            f"road force, on the wheels the model corrects (model error up to {HYBRID_LIMIT:g}). Runs of benchmarks/model_correction.py read: {what}.")
    page = write_results_page(args.results, "model_error", "The model correction's error against the model's error "
                              "on the record", HEADER, table_rows(rows), script_command(__file__, argv), note=note)
    print(page.read_text(encoding="utf-8"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
