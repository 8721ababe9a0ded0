"""The model correction on the paper's cases or the generalization suite, against the linear floor.

::

    python benchmarks/model_correction.py [--suite paper|generalization] [--duration-s 60]
                                          [--cases medium_72 high_48 high_72] [--workers N] [--noise-N 100]
                                          [--cab auto|held|fitted] [--plants rigid cab tire smooth]
                                          [--tire-ratio 0.25] [--results docs/results]

Suites (:func:`rigsim.scenarios.studies.suites.pick_cases`): ``paper``, the paper's three scenarios (60 s
by default; a per-wheel table per case with the fitted parameters); ``generalization``, the 24
cases of the generalization suite (``scenarios/data/suites/generalization.toml``: ISO classes
A-D, 30-100 km/h, payload 0-8000 kg, track types, seeds; 30 s by default; one table, two rows per
case: the worse wheel of each axle). ``--cases``: parts of the cases' names.

For each case the truck on the rig (the "plant") differs from the XML's nominal truck as a real
truck differs from its catalogue (``scenarios/data/suites/model_plants.toml``, read by
:func:`rigsim.scenarios.studies.suites.model_plants`; :data:`PLANT_FACTORS`: payload -5 % and 0.1 m
further forward, tire stiffness +10 % front / -10 % rear, tire damping +20 % / -20 %, leaf
friction +30 % / -30 %; the payload factor applies to the case's own payload, 0 kg included).
Four plants (``--plants``, :data:`PLANT_KEYS`; :mod:`rigsim.scenarios.studies.model_suite.plants`):

* ``rigid``: that truck with the XML's rigid cab and linear tires;
* ``cab``: the same with its cab on its own mounts at :data:`CAB_HZ`;
* ``tire``: the ``rigid`` plant with a bilinear progressive tire (``TruckVariant.tire_progressive_ratio``,
  ``--tire-ratio``, default :data:`TIRE_RATIO`, at the default onset, 2 cm): in the model family,
  whose tire is bilinear with each axle's ratio and onset fitted;
* ``smooth``: the ``rigid`` plant with tires that stiffen gradually, by 50 % over 2 cm of
  deflection about 2 cm (``TruckVariant.tire_progressive_spread_m``, five steps), which the
  family's one-kink tire cannot represent: the structural mismatch.

The model's cab (``--cab``, :func:`rigsim.scenarios.records.model.cab_choice.calibrate_cab`):
``auto`` (default) calibrates the cab held rigid and the cab's mount frequency fitted and keeps the
clearly better fit; ``held`` the rigid cab only; ``fitted`` the mount fitted only. The ``rigid``
plant is in the model family under every mode (under ``fitted`` nearly: the mount range's stiff end,
30 Hz), the ``cab`` plant under ``auto`` and ``fitted`` (out of it under ``held``), the ``tire``
plant under all three, the ``smooth`` plant under none: a row's mismatch (:func:`mismatch`) is "on"
where the plant is outside the family, "off" where inside.

Per case and plant, in worker processes (:func:`rigsim.scenarios.core.pool.run_jobs`, one pool over every
case's runs): the road test (the reference, never seen by the correction), the rig test, and the
rig's identification before the test (for the project's linear correction). Then, one case and
plant after the other in this process (the calibration starts its own pool of ``--workers``: pools
do not nest), the model correction of the measured rig force
(100 N rms load-cell noise on), :func:`rigsim.scenarios.records.model.differential.correct_with_model`:
calibration from x_a and F_rig only (first guess from the static loads and catalogue values, never
the plant's), then F_model(x_ref) + L(W(F_rig - F_model(x_a))), W the residual's white noise taken out, L the
linear correction by the identified T_a.
Scored per wheel on the samples where
every method has settled (the model's start-up, the linear correction's filter transients, the
band limit's): NRMSE against the road force through the 30 Hz band limit, and DLC against the road
DLC; beside them the linear floor (:func:`rigsim.correction.output.floor.linear_floor`, per wheel, taps -50..400
as ``benchmarks/nrmse_decomposition.py``, in-sample) and the project's linear correction
(:func:`rigsim.scenarios.studies.scoring.score_pair`, method ``best``).

Goals: NRMSE at most half the linear floor (mismatch off), below it (mismatch on), every wheel
within 1 % of the road DLC; calibration plus correction of a 60 s case within 5 minutes on 2
cores (wall time, and CPU time of this process and its workers, are printed: the machine may be shared).
Scored per wheel is what the method delivers: the model correction, or the linear correction where
it falls back (:func:`rigsim.scenarios.studies.model_suite.report.delivered`). Writes the suite's table
(two rows per case, the plants side by side, the cab the calibration chose) and the share of wheels
meeting each goal to ``docs/results/model_correction_<suite>.md`` (``--results``: its folder),
ending in the line that says how and where it was measured (:mod:`rigsim.scenarios.studies.results_page`);
prints, for the paper's cases, a per-wheel table per case with the fitted parameters first, then
that file and one JSON line with every number.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import resource
import sys
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from rigsim.correction.metrics.dlc import dlc, nrmse  # noqa: E402
from rigsim.correction.output.apply import band_limit  # noqa: E402
from rigsim.correction.output.floor import linear_floor  # noqa: E402
from rigsim.mjcf.names import CORNERS  # noqa: E402
from rigsim.scenarios.core.files import to_json  # noqa: E402
from rigsim.scenarios.core.pool import run_jobs  # noqa: E402
from rigsim.scenarios.core.rig import Rig  # noqa: E402
from rigsim.scenarios.records.model.cab_choice import AUTO, CAB_CHOICES  # noqa: E402
from rigsim.scenarios.records.model.differential import correct_with_model, settled_mask  # noqa: E402
from rigsim.scenarios.records.model.first_guess import xml_nominal  # noqa: E402, F401  (the plants' nominal values)
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE  # noqa: E402
from rigsim.scenarios.studies.correction_score import band_rows  # noqa: E402
from rigsim.scenarios.studies import scoring  # noqa: E402
from rigsim.scenarios.studies.model_suite.plants import (TIRE_PLANT, mismatch, plant_job, plant_keys,  # noqa: E402
                                                         plant_name, plant_scenario, plant_truck, plant_variant)
from rigsim.scenarios.studies.model_suite.report import (GOAL_S, goals, plants_line, suite_cells, suite_table,  # noqa: E402, F401
                                                         summary, table)
from rigsim.scenarios.studies.results_page import script_command, write_results_page  # noqa: E402
from rigsim.scenarios.studies.suites import SUITES, case_name, model_plants, pick_cases  # noqa: E402

#: The plants' catalogue offsets: factors on the XML's nominal values (payload: of the case's payload).
PLANT_FACTORS = dict(model_plants().factors)
#: The plant's payload x against the XML's (m, forward positive).
PLANT_PAYLOAD_SHIFT_M = model_plants().payload_x_shift_m
#: The plants, in their default order: rigid cab, cab on :data:`CAB_HZ` mounts, bilinear progressive
#: tire, gradually stiffening tire.
PLANT_KEYS = plant_keys()
#: The ``cab`` plant's cab bounce frequency, Hz.
CAB_HZ = plant_truck("cab")["cab_mount_hz"]
#: The ``tire`` plant's progressive tire: extra stiffness beyond the onset (``--tire-ratio``'s default, 1).
TIRE_RATIO = plant_truck(TIRE_PLANT)["tire_progressive_ratio"]
#: The linear floor's FIR, samples ahead and behind (benchmarks/nrmse_decomposition.py's defaults at 1 kHz).
LEAD, LAG = 50, 400
#: Where the results file goes by default: docs/results of this repository.
RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"


def pick(suite: str, keys: list[str] | None, duration_s: float) -> list:
    """The cases of ``suite`` whose names contain each of ``keys`` (all by default): paths or documents
    (:func:`rigsim.scenarios.studies.suites.pick_cases`); a key matching no case or several ends the run."""
    try:
        return pick_cases(suite, keys, duration_s)
    except ValueError as exc:
        raise SystemExit(f"--cases: {exc}") from None


def cpu_s() -> float:
    """CPU seconds of this process and its finished children (the pools' workers)."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def analyse(case, duration_s, plant, road, rig, ident, noise_N, workers, cab: str = AUTO,
            tire_ratio: float = TIRE_RATIO) -> dict:
    """Every figure of one case and plant (:data:`PLANT_KEYS`), the model calibrated with cab mode ``cab``."""
    sc = plant_scenario(case, duration_s, plant, tire_ratio)
    fs = road.rate_hz
    road_f = np.asarray(road.signals["tire_force_N"], dtype=float)
    rig_N = scoring.measured_force(rig, noise_N, sc.seed)
    score = scoring.score_pair(road, rig, Rig(sc), methods=(scoring.BEST,), identified=ident.actuators(),
                               noise_N=noise_N, seed=sc.seed)
    best = score.methods[scoring.BEST.name]
    wall0, cpu0 = time.perf_counter(), cpu_s()
    mc = correct_with_model(rig.t_s, rig.signals["profile_m"], rig.signals["pan_m"], rig_N, base_scenario=sc,
                            workers=workers, cab=cab, linear=scoring.best_linear(ident.actuators(), fs))
    wall, cpu = time.perf_counter() - wall0, cpu_s() - cpu0
    road_b = band_limit(road_f, fs, BAND_LOWPASS, BAND_MODE)
    rows = band_rows(road_f.shape[0], fs) & best.settled & settled_mask(rig.t_s)
    out = {"linear": nrmse(best.corrected_N[rows], road_b[rows]),
           "linear_dlc_error": dlc(best.corrected_N[rows]) / dlc(road_f[rows]) - 1.0,
           "rig": nrmse(band_limit(rig_N, fs, BAND_LOWPASS, BAND_MODE)[rows], road_b[rows]),
           "floor": linear_floor(rig_N, road_b, LEAD, LAG, rows=rows).nrmse}
    if not mc.use_linear:
        corr_b = band_limit(mc.corrected_N, fs, BAND_LOWPASS, BAND_MODE)
        out["model"] = nrmse(corr_b[rows], road_b[rows])
        out["model_dlc_error"] = dlc(mc.corrected_N[rows]) / dlc(road_f[rows]) - 1.0
    truth = {k: getattr(sc.vehicle, k) for k in (mc.calibration.names if mc.calibration else ())}
    return {"case": case_name(case), "mismatch": mismatch(plant, cab), "plant": plant_name(plant, tire_ratio),
            "plant_key": plant, "scored_s": float(rows.sum()) / fs,
            "wheels": {k: {c: float(v[i]) for i, c in enumerate(CORNERS)} for k, v in out.items()},
            "mean": {k: float(np.mean(v)) for k, v in out.items()}, "method": mc.method, "reason": mc.reason,
            "calibration": mc.calibration, "truth": truth, "wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
            "timings": dict(mc.timings)}


def note(rows: list[dict], duration_s: float, cab: str) -> str:
    """The text under the results table: what the columns are, which plant is which, the goals."""
    return ("NRMSE against the road force through the 30 Hz band limit (zero-phase), on the samples where every "
            f"method has settled; linear floor: per-wheel affine FIR (taps -{LEAD}..{LAG}) fitted on the road force "
            "itself, in-sample; per axle, the worse of its two wheels; DLC error delivered: the model correction's, "
            "or the linear correction's where it fell back, against the unfiltered road DLC on the same samples; "
            "CPU: calibration plus correction, this process and its workers; cab: the calibrated model's (held "
            "rigid, or its mount frequency fitted).\n\n" + plants_line(rows) + f"\n\nGoals (--cab {cab}):\n\n"
            + goals(rows, duration_s))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", choices=SUITES, default="paper",
                    help="the paper's three cases (default) or the 24 cases of the generalization suite")
    ap.add_argument("--duration-s", type=float, default=None,
                    help="analysed seconds per run (default 60 for the paper's cases, 30 for the suite)")
    ap.add_argument("--cases", nargs="+", help="parts of the cases' names (default: all of the suite)")
    ap.add_argument("--noise-N", type=float, default=scoring.NOISE_N, help="rms load-cell noise, N (default 100)")
    ap.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    ap.add_argument("--cab", choices=CAB_CHOICES, default=AUTO,
                    help="the model's cab: auto (default) calibrates it held rigid and with its mount frequency "
                         "fitted and keeps the clearly better fit (3-4 times the CPU of one); held: rigid only (the cab "
                         "plant is then outside the model family); fitted: the mount frequency fitted only")
    ap.add_argument("--plants", nargs="+", choices=PLANT_KEYS, default=list(PLANT_KEYS),
                    help=f"the plant trucks, in this order (default all four): rigid (the XML's rigid cab), cab "
                         f"(the same with its cab on {CAB_HZ:g} Hz mounts), tire (the rigid one with a bilinear "
                         "progressive tire, --tire-ratio: in the model family), smooth (the rigid one with a "
                         f"{plant_name('smooth').replace('%', '%%')}: outside it)")
    ap.add_argument("--tire-ratio", type=float, default=TIRE_RATIO,
                    help=f"the tire plant's extra tire stiffness beyond the onset, 1 (default {TIRE_RATIO:g}: +"
                         f"{100 * TIRE_RATIO:g} %%)")
    ap.add_argument("--results", type=pathlib.Path, default=RESULTS,
                    help="folder of the results file model_correction_<suite>.md (default docs/results)")
    args = ap.parse_args(argv)
    duration = args.duration_s if args.duration_s is not None else (60.0 if args.suite == "paper" else 30.0)
    if not (duration >= scoring.MIN_DURATION_S and args.noise_N >= 0):
        raise SystemExit(f"--duration-s must be >= {scoring.MIN_DURATION_S:g} s and --noise-N >= 0")
    plants, ratio = list(dict.fromkeys(args.plants)), float(args.tire_ratio)
    try:  # a bad --tire-ratio refused before any run
        [plant_variant(0.0, p, ratio) for p in plants]
    except ValueError as exc:
        raise SystemExit(f"--tire-ratio: {exc}") from None
    cases = pick(args.suite, args.cases, duration)
    t0 = time.perf_counter()
    keys = [(i, p, k) for i in range(len(cases)) for p in plants for k in ("road", "rig", "identify")]
    jobs = [(plant_job, (cases[i], duration, p, k, ratio)) for i, p, k in keys]

    def said(j, _r):
        i, p, k = keys[j]
        print(f"[{time.perf_counter() - t0:6.0f} s] {case_name(cases[i])} {plant_name(p, ratio)}: {k}",
              file=sys.stderr, flush=True)

    by = dict(zip(keys, run_jobs(jobs, workers=args.workers, on_done=said)))
    rows = []
    for i, case in enumerate(cases):
        for p in plants:
            road, rig, ident = (by.pop((i, p, k)) for k in ("road", "rig", "identify"))
            rows.append(analyse(case, duration, p, road, rig, ident, args.noise_N, args.workers, args.cab, ratio))
            r = rows[-1]
            print(f"[{time.perf_counter() - t0:6.0f} s] {r['case']} {r['plant']} (mismatch {r['mismatch']}): "
                  f"{r['method']} correction, {r['wall_s']:.0f} s wall, {r['cpu_s']:.0f} s CPU",
                  file=sys.stderr, flush=True)
    if args.suite == "paper":
        print(table(rows))
        print("\nNRMSE against the road force through the 30 Hz band limit (zero-phase), on the samples where every "
              f"method has settled; linear floor: per-wheel affine FIR (taps -{LEAD}..{LAG}) fitted on the road "
              "force itself, in-sample; DLC errors against the unfiltered road DLC on the same samples (the model "
              "correction unfiltered, the linear one band-limited as the project scores it); fit NRMSE: the "
              "calibrated model against the measured F_rig on the calibration windows (load-cell noise included), "
              "in brackets the model error, beyond the noise, that the fallback reads.")
    heads, cells = suite_cells(rows)
    page = write_results_page(args.results, f"model_correction_{args.suite}",
                              f"The truck-model correction on the {args.suite} suite: {len(cases)} case{'s' if len(cases) != 1 else ''} of "
                              f"{duration:g} s, {args.noise_N:g} N load-cell noise, --cab {args.cab}", heads, cells,
                              script_command(__file__, argv), note=note(rows, duration, args.cab))
    print(page.read_text(encoding="utf-8"))
    result = {"suite": args.suite, "duration_s": duration, "noise_N": args.noise_N, "plant_factors": PLANT_FACTORS,
              "plant_payload_shift_m": PLANT_PAYLOAD_SHIFT_M, "cab": args.cab, "plants": plants, "cab_hz": CAB_HZ,
              "tire_ratio": ratio, "goal_s": GOAL_S, "wall_time_s": round(time.perf_counter() - t0, 1),
              "cpu_count": os.cpu_count(), "summary": summary(rows), "rows": rows}
    print(json.dumps(json.loads(to_json(result))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
