"""The model correction on real trucks: random plant trucks, several differences at once, measured as a lab measures.

::

    python benchmarks/mismatch_suite.py [--plants 24] [--duration-s 30] [--seed 0]
                                        [--lab typical|typical-no-drift|ideal] [--channels aligned|raw]
                                        [--cab auto|held|fitted] [--drift-cut-hz 0.7] [--workers N] [--noise-N 100]
                                        [--results docs/results] [--from-json RUN.txt]

Plant ``i`` (:func:`scenarios.studies.model_suite.mismatch.mismatch_plants`, seeded) is a truck
drawn from ``scenarios/data/suites/mismatch_plants.toml``: payload mass and position, each wheel
station's own tire and leaf spring, axle and chassis masses, dampers harder in rebound, and with
probability 1/2 each a suspended cab and progressive tires; it runs on the generalization suite's
case ``i`` (ISO classes A-D, 30-100 km/h, payload 0-8000 kg). Per plant, in worker processes:
the road test (the reference), the rig test and the rig's identification before it; then, one
plant after the other, :func:`scenarios.studies.model_suite.mismatch_score.score_plant`: the
rig test through the lab's measurement chain (``--lab``: :data:`scenarios.core.lab.TYPICAL_LAB`
by default, the same without its load cells' drift, or the ideal load cell), its channels aligned as a lab that knows its anti-alias
filters and converter skew aligns them (``--channels aligned``, default:
:func:`scenarios.core.lab.aligned`, the identification's LVDTs too) or as recorded (``raw``),
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

import numpy as np  # noqa: E402

from correction.output.denoise import DRIFT_HZ  # noqa: E402
from scenarios.core.files import to_json  # noqa: E402
from scenarios.core.lab import TYPICAL_LAB, LabChain  # noqa: E402
from scenarios.core.pool import run_jobs  # noqa: E402
from scenarios.records.model.cab_choice import AUTO, CAB_CHOICES  # noqa: E402
from scenarios.records.model.differential import HYBRID_LIMIT  # noqa: E402
from scenarios.records.settings import DRIFT_CUT_MAX_HZ  # noqa: E402
from scenarios.studies import scoring  # noqa: E402
from scenarios.studies.model_suite.mismatch import (describe, mismatch_job, mismatch_plants,  # noqa: E402
                                                    mismatch_scenario)
from scenarios.studies.model_suite.mismatch_score import PlantScore, score_plant  # noqa: E402
from scenarios.studies.results_page import script_command, write_results_page  # noqa: E402
from scenarios.studies.suites import case_name, pick_cases  # noqa: E402

RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"
LABS = {"typical": TYPICAL_LAB, "typical-no-drift": dataclasses.replace(TYPICAL_LAB, drift_noise_N=0.0),
        "ideal": LabChain()}
CHANNELS = ("aligned", "raw")
#: Goals of the suite: DLC within 1 % (95 % of wheels) and 2 % (all), NRMSE at most half the floor
#: (95 %), at most 0.05 above the linear correction (all).
DLC_GOOD, DLC_ALL, FLOOR_RATIO, SHARE, ABOVE_LINEAR = 0.01, 0.02, 0.5, 0.95, 0.05


def _pct(x: float) -> str:
    return f"{100 * x:+.2f} %"


def limit_evidence(scores) -> dict:
    """Where the fallback's limit belongs, wheel by wheel: each wheel's model error (what the fallback
    reads) against whether the hybrid model correction, forced, beat the linear correction's NRMSE
    there. ``beats_up_to``: the largest model error of a wheel where it beat; ``loses_from``: the
    smallest where it did not (None where no wheel did not); a limit between them (when the first is
    below the second) separates the wheels; otherwise the wheels between them overlap, counted in
    ``overlap``."""
    err, beat = [], []
    for s in scores:
        if s.model_error is None or "hybrid" not in s.nrmse:
            continue
        err.extend(np.asarray(s.model_error, float))
        beat.extend(np.asarray(s.nrmse["hybrid"]) < np.asarray(s.nrmse["linear"]))
    err, beat = np.asarray(err), np.asarray(beat, bool)
    if not err.size:
        return {"wheels": 0, "beats_up_to": None, "loses_from": None, "overlap": 0}
    up_to = float(err[beat].max()) if beat.any() else None
    loses = float(err[~beat].min()) if (~beat).any() else None
    overlap = 0 if up_to is None or loses is None else int(np.sum((err >= loses) & (err <= up_to)))
    return {"wheels": int(err.size), "beats_up_to": up_to, "loses_from": loses, "overlap": overlap,
            "beats": int(beat.sum())}


def _limit_text(ev: dict) -> str:
    if not ev["wheels"]:
        return "- the fallback's limit: no calibrated wheel to read it from"
    where = (f"beat the linear correction on {ev['beats']} of {ev['wheels']} wheels; the largest model error where it "
             f"beat: {ev['beats_up_to']:.3f}" if ev["beats_up_to"] is not None else
             f"beat the linear correction on none of {ev['wheels']} wheels")
    where += (f", the smallest where it did not: {ev['loses_from']:.3f}" if ev["loses_from"] is not None else
              ", on every wheel")
    if ev["loses_from"] is not None and ev["beats_up_to"] is not None:
        where += (f" ({ev['overlap']} wheels between them)" if ev["overlap"] else ": a limit between them separates them")
    return f"- the forced hybrid {where} (the fallback's limit: {HYBRID_LIMIT:g})"


def rows_and_goals(scores) -> tuple[list[str], list[list], str, dict]:
    """The table (one row per plant), the goals' text and their numbers."""
    head = ["case", "plant", "method", "model error (worst)", "worst DLC error", "NRMSE / floor (worst)",
            "linear NRMSE (worst)", "forced differential NRMSE (worst)", "hybrid NRMSE / floor (worst)",
            "hybrid worst DLC error", "wall s"]
    rows = []
    for s in scores:
        d, n = s.dlc_error["delivered"], s.nrmse["delivered"]
        forced = s.nrmse.get("forced")
        rows.append([s.name, describe(s.plant), s.method,
                     "" if s.model_error is None else f"{np.max(s.model_error):.3f}", _pct(d[np.argmax(np.abs(d))]),
                     f"{np.max(n / s.floor):.2f}", f"{np.max(s.nrmse['linear']):.3f}",
                     "" if forced is None else f"{np.max(forced):.3f}",
                     "" if forced is None else f"{np.max(s.nrmse['hybrid'] / s.floor):.2f}",
                     "" if forced is None else _pct(s.dlc_error["hybrid"][np.argmax(np.abs(s.dlc_error["hybrid"]))]),
                     f"{s.wall_s:.0f}"])
    d = np.concatenate([s.dlc_error["delivered"] for s in scores])
    ratio = np.concatenate([s.nrmse["delivered"] / s.floor for s in scores])
    above = np.concatenate([s.nrmse["delivered"] - s.nrmse["linear"] for s in scores])
    lin = np.concatenate([s.dlc_error["linear"] for s in scores])
    good = np.mean((np.abs(d) <= DLC_GOOD) & (ratio <= FLOOR_RATIO))
    fallbacks = [s for s in scores if s.method != "model"]
    # the model correction the fallback refused is the hybrid (what --model delivers where the model holds)
    wrong = [s.name for s in fallbacks if "hybrid" in s.nrmse and np.all(s.nrmse["hybrid"] < s.nrmse["linear"])]
    numbers = {"wheels": int(d.size), "share_good": float(good), "worst_dlc_error": float(np.max(np.abs(d))),
               "worst_above_linear": float(np.max(above)), "fallbacks": len(fallbacks),
               "fallbacks_without_reason": sum(1 for s in fallbacks if not s.reason), "wrong_fallbacks": wrong,
               "median_wall_s": float(np.median([s.wall_s for s in scores])), "limit": limit_evidence(scores)}
    met = {"share": good >= SHARE, "dlc": numbers["worst_dlc_error"] <= DLC_ALL,
           "linear": numbers["worst_above_linear"] <= ABOVE_LINEAR,
           "fallbacks": not wrong and not numbers["fallbacks_without_reason"]}
    text = "\n".join([
        f"- wheels within {100 * DLC_GOOD:g} % of the road DLC and at NRMSE <= {FLOOR_RATIO:g} x the linear floor: "
        f"{100 * good:.1f} % of {d.size} (goal >= {100 * SHARE:g} %): {'met' if met['share'] else 'NOT met'}",
        f"- worst DLC error: {100 * numbers['worst_dlc_error']:.2f} % (goal <= {100 * DLC_ALL:g} %): "
        f"{'met' if met['dlc'] else 'NOT met'}",
        f"- worst NRMSE above the linear correction: {numbers['worst_above_linear']:+.3f} (goal <= {ABOVE_LINEAR:g}): "
        f"{'met' if met['linear'] else 'NOT met'}",
        f"- fallbacks: {len(fallbacks)}, without a reason: {numbers['fallbacks_without_reason']}, where the forced "
        f"model correction (hybrid) was better on every wheel: {len(wrong)} ({', '.join(wrong) or 'none'}): "
        f"{'met' if met['fallbacks'] else 'NOT met'}",
        f"- the two goals apart: within {100 * DLC_GOOD:g} % of the road DLC {100 * np.mean(np.abs(d) <= DLC_GOOD):.0f} % "
        f"of the wheels, at NRMSE <= {FLOOR_RATIO:g} x the floor {100 * np.mean(ratio <= FLOOR_RATIO):.0f} %",
        f"- DLC error over the wheels: median {_pct(np.median(d))}, {100 * np.mean(d > 0):.0f} % above the road's "
        f"(the linear correction: median {_pct(np.median(lin))}, {100 * np.mean(lin > 0):.0f} % above)",
        _limit_text(numbers["limit"]),
        f"- median wall time of a calibration and correction: {numbers['median_wall_s']:.0f} s"])
    return head, rows, text, numbers | {"met": met}


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
              f"{' '.join(_pct(x) for x in s.dlc_error['delivered'])}, NRMSE/floor "
              f"{' '.join(f'{x:.2f}' for x in s.nrmse['delivered'] / s.floor)}, {s.wall_s:.0f} s"
              + (f" ({s.reason})" if s.reason else ""), file=sys.stderr, flush=True)
    settings = {"lab": args.lab, "channels": args.channels, "cab": args.cab, "seed": args.seed,
                "duration_s": args.duration_s, "noise_N": args.noise_N, "drift_cut_hz": args.drift_cut_hz,
                "command": script_command(__file__, argv)}
    _write_page(scores, settings, args.results)
    print(json.dumps(json.loads(to_json(settings | {"summary": rows_and_goals(scores)[3],
                                                    "wall_time_s": round(time.perf_counter() - t0, 1),
                                                    "plants": [s.to_dict() for s in scores]}))))
    return 0


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
    head, rows, goals, numbers = rows_and_goals(scores)
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
