"""The model correction on real trucks: random plant trucks, several differences at once, measured as a lab measures.

::

    python benchmarks/mismatch_suite.py [--plants 24] [--duration-s 30] [--seed 0]
                                        [--lab typical|typical-no-drift|ideal] [--channels aligned|raw]
                                        [--cab auto|held|fitted] [--drift-cut-hz 0.7] [--workers N] [--noise-N 100]
                                        [--results docs/results] [--from-json RUN.txt]

Plant ``i`` (:func:`rigsim.scenarios.studies.model_suite.mismatch.mismatch_plants`, seeded) is a truck
drawn from ``scenarios/data/suites/mismatch_plants.toml``: payload mass and position, each wheel
station's own tire and leaf spring, axle and chassis masses, dampers harder in rebound, and with
probability 1/2 each a suspended cab and progressive tires; it runs on the generalization suite's
case ``i`` (ISO classes A-D, 30-100 km/h, payload 0-8000 kg). Per plant, in worker processes:
the road test (the reference), the rig test and the rig's identification before it; then, one
plant after the other, :func:`rigsim.scenarios.studies.model_suite.mismatch_score.score_plant`: the
rig test through the lab's measurement chain (``--lab``: :data:`rigsim.scenarios.core.lab.TYPICAL_LAB`
by default, the same without its load cells' drift, or the ideal load cell), its channels aligned as a lab that knows its anti-alias
filters and converter skew aligns them (``--channels aligned``, default:
:func:`rigsim.scenarios.core.lab.aligned`, the identification's LVDTs too) or as recorded (``raw``),
corrected linearly by the identified T_a and by the truck
model calibrated on the record (its fallback honoured, and forced where it refused; its drift
cut at ``--drift-cut-hz``, 0: none), against each plant's linear floor.

Writes the table and the goals to ``docs/results/mismatch_suite.md`` (``mismatch_suite_raw.md``
with ``--channels raw``; another lab or drift cut adds its name, e.g.
``mismatch_suite_typical_no_drift_cut0.md``; ``--results``: their folder)
and prints it, then one JSON line with every number. Goals: at least 95 % of wheels within 1 % of
the road DLC and at NRMSE <= 0.5 x the plant's linear floor; every wheel within 2 % and at most
0.05 NRMSE above the linear correction; every fallback with its reason, none where the model
correction it refused (the hybrid, forced) was better on every wheel.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import pathlib
import sys
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")


from rigsim.correction.output.denoise import DRIFT_HZ  # noqa: E402
from rigsim.scenarios.core.files import to_json  # noqa: E402
from rigsim.scenarios.core.lab import TYPICAL_LAB, LabChain  # noqa: E402
from rigsim.scenarios.core.pool import run_jobs  # noqa: E402
from rigsim.scenarios.records.model.cab_choice import AUTO, CAB_CHOICES  # noqa: E402
from rigsim.scenarios.records.model.fallback import HYBRID_LIMIT  # noqa: E402
from rigsim.scenarios.studies.model_suite.goals import pct, rows_and_goals  # noqa: E402
from rigsim.scenarios.records.model_settings import DRIFT_CUT_MAX_HZ  # noqa: E402
from rigsim.scenarios.studies import scoring  # noqa: E402
from rigsim.scenarios.studies.model_suite.mismatch import (describe, mismatch_job, mismatch_plants,  # noqa: E402
                                                           mismatch_scenario)
from rigsim.scenarios.studies.model_suite.mismatch_score import PlantScore, score_plant  # noqa: E402
from rigsim.scenarios.studies.results_page import script_command, write_results_page  # noqa: E402
from rigsim.scenarios.studies.suites import case_name, pick_cases  # noqa: E402

RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"
LABS = {"typical": TYPICAL_LAB, "typical-no-drift": dataclasses.replace(TYPICAL_LAB, drift_noise_N=0.0),
        "ideal": LabChain()}
CHANNELS = ("aligned", "raw")
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plants", type=int, default=24, help="how many plants (1-24; plant i on the suite's case i)")
    ap.add_argument("--duration-s", type=float, default=30.0, help="analysed seconds per run (default 30)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the plants' draws (default 0)")
    ap.add_argument("--lab", choices=sorted(LABS), default="typical", help="the lab's measurement (default typical)")
    ap.add_argument("--channels", choices=CHANNELS, default="aligned",
                    help="the lab's filters' phase and delays taken out before correcting, or not (default aligned)")
    ap.add_argument("--cab", choices=CAB_CHOICES, default=AUTO, help="the model's cab mode (default auto)")
    ap.add_argument("--drift-cut-hz", type=float, default=DRIFT_HZ,
                    help=f"the model correction's drift cut, Hz (default {DRIFT_HZ:g}; 0: none)")
    ap.add_argument("--noise-N", type=float, default=scoring.NOISE_N, help="white load-cell noise, N rms (default 100)")
    ap.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    ap.add_argument("--results", type=pathlib.Path, default=RESULTS, help="folder of mismatch_suite.md")
    ap.add_argument("--from-json", type=pathlib.Path, default=None,
                    help="write the page from a run's printed output (its JSON line) instead of running")
    args = ap.parse_args(argv)
    if args.from_json is not None:
        return _page_from_json(args.from_json, args.results)
    if (not 1 <= args.plants <= 24 or args.duration_s < scoring.MIN_DURATION_S or args.noise_N < 0
            or not 0 <= args.drift_cut_hz <= DRIFT_CUT_MAX_HZ):
        raise SystemExit(f"--plants must be 1-24, --duration-s >= {scoring.MIN_DURATION_S:g} s, --noise-N >= 0, "
                         f"--drift-cut-hz 0-{DRIFT_CUT_MAX_HZ:g} Hz")
    lab, align = LABS[args.lab], args.channels == "aligned"
    cases = pick_cases("generalization", None, args.duration_s)[:args.plants]
    plants = mismatch_plants(cases, args.seed)  # every plant validated before any run
    t0 = time.perf_counter()
    keys = [(i, k) for i in range(len(cases)) for k in ("road", "rig", "identify")]
    jobs = [(mismatch_job, (cases[i], plants[i], args.duration_s, k, lab, align)) for i, k in keys]

    def said(j, _r):
        i, k = keys[j]
        print(f"[{time.perf_counter() - t0:6.0f} s] {case_name(cases[i])}: {k}", file=sys.stderr, flush=True)

    by = dict(zip(keys, run_jobs(jobs, workers=args.workers, on_done=said)))
    scores = []
    for i, case in enumerate(cases):
        sc = mismatch_scenario(case, plants[i], args.duration_s)
        s = score_plant(case_name(case), plants[i], sc, by.pop((i, "road")), by.pop((i, "rig")),
                        by.pop((i, "identify")), lab=lab, noise_N=args.noise_N, seed=sc.seed, workers=args.workers,
                        cab=args.cab, align=align, drift_hz=args.drift_cut_hz or None)
        scores.append(s)
        print(f"[{time.perf_counter() - t0:6.0f} s] {s.name}: {s.method}, DLC "
              f"{' '.join(pct(x) for x in s.dlc_error['delivered'])}, NRMSE/floor "
              f"{' '.join(f'{x:.2f}' for x in s.nrmse['delivered'] / s.floor)}, {s.wall_s:.0f} s"
              + (f" ({s.reason})" if s.reason else ""), file=sys.stderr, flush=True)
    settings = {"lab": args.lab, "channels": args.channels, "cab": args.cab, "seed": args.seed,
                "duration_s": args.duration_s, "noise_N": args.noise_N, "drift_cut_hz": args.drift_cut_hz,
                "command": script_command(__file__, argv)}
    _write_page(scores, settings, args.results)
    print(json.dumps(json.loads(to_json(settings | {"summary": rows_and_goals(scores, _plant_text)[3],
                                                    "wall_time_s": round(time.perf_counter() - t0, 1),
                                                    "plants": [s.to_dict() for s in scores]}))))
    return 0


def _plant_text(score) -> str:
    return describe(score.plant)


def _page_from_json(path: pathlib.Path, results: pathlib.Path) -> int:
    """The page of a run whose printed output (ending in its JSON line) is ``path``."""
    lines = [line for line in path.read_text(encoding="utf-8").splitlines() if line.startswith("{")]
    if not lines:
        raise SystemExit(f"{path}: no JSON line of a mismatch_suite run in it; give the file its run printed")
    run = json.loads(lines[-1])
    scores = [PlantScore.from_dict(p) for p in run["plants"]]
    settings = {k: run[k] for k in ("lab", "cab", "seed", "duration_s")}
    settings["channels"] = run.get("channels", "raw")  # a run without the key did not align its channels
    settings["noise_N"] = run.get("noise_N", scoring.NOISE_N)
    settings["drift_cut_hz"] = run.get("drift_cut_hz", DRIFT_HZ)
    settings["command"] = run.get("command") or (
        f"python benchmarks/mismatch_suite.py --plants {len(scores)} --workers 2"
        + "".join(f" --{k} {settings[k]}" for k, d in (("lab", "typical"), ("channels", "aligned"), ("cab", AUTO),
                                                         ("seed", 0)) if settings[k] != d))
    _write_page(scores, settings, results)
    return 0


def _write_page(scores, settings: dict, results: pathlib.Path) -> None:
    head, rows, goals, numbers = rows_and_goals(scores, _plant_text)
    title = (f"The model correction on {len(scores)} random real trucks ({settings['duration_s']:g} s records, lab "
             f"measurement: {settings['lab']}, channels {settings['channels']}, {settings['noise_N']:g} N white load-cell noise, --cab {settings['cab']}"
             + (f", drift cut {settings['drift_cut_hz']:g} Hz" if settings["drift_cut_hz"] else ", no drift cut") + ")")
    note = ("Per plant the worse wheel: the model error the fallback reads (the calibrated model's dynamic "
            f"residual in the correction's band beyond the load cells' noise; limit {HYBRID_LIMIT:g}); DLC error of what "
            "`rigsim correct --model` delivered (the model, or the linear correction where it fell back) against the "
            "road DLC; NRMSE against the road force through the 30 Hz band limit, over the plant's linear floor "
            "(per-wheel affine FIR fitted on the road force itself); the linear correction's (identified T_a); the "
            "model correction forced where the fallback refused it, in its differential form F_rig + F_model(x_ref) "
            "- F_model(x_a) and as delivered, the hybrid F_model(x_ref) + L(W(F_rig - F_model(x_a))), the model's "
            "residual, its white noise taken out (W), corrected by the linear correction L. A fallback is wrong "
            "where the forced hybrid beats the linear correction on every wheel. Goals:\n\n" + goals)
    name = ("mismatch_suite" + ("_raw" if settings["channels"] == "raw" else "")
            + ("" if settings["lab"] == "typical" else "_" + settings["lab"].replace("-", "_"))
            + ("" if settings["drift_cut_hz"] == DRIFT_HZ else f"_cut{settings['drift_cut_hz']:g}"))
    page = write_results_page(results, name, title, head, rows, settings["command"], note=note)
    print(page.read_text(encoding="utf-8"))


if __name__ == "__main__":
    sys.exit(main())
