"""Which physical effect each generalization case's DLC error comes from: a per-case decomposition.

::

    python benchmarks/generalization_blame.py [--cases 24] [--duration-s 30] [--jobs N] [--only gen01 gen02 ...]
                                              [--results docs/results]

For each case of the generalization suite (:func:`rigsim.scenarios.studies.suites.generalization_cases`,
as ``benchmarks/generalization.py`` runs it) the corrected DLC error (corrected against road, per
wheel, %) is taken apart along one chain, each step removing one cause with the rest kept
(the runs and the correction with one cause removed: :mod:`rigsim.scenarios.studies.decomposition`):

1. ``identified``: the project's correction, as ``benchmarks/generalization.py`` scores it (T_a identified
   before the test from independent random drives, ``rigsim identify``; nonlinear DYNTRAC rig;
   leaf-spring friction on; 100 N load-cell noise).
2. ``linearized``: the same rig run corrected with each wheel's own path of the linearized plant
   (its exact frequency response, zero-phase, under the same 30 Hz low-pass:
   :class:`rigsim.scenarios.studies.decomposition.ExactLinearCorrection`). Step 1 - 2: **identification** (what the
   fitted T_a gets wrong about the small-signal actuator).
3. ``linear pans``: a road-mode run whose pans follow the profile through that linear T_a per
   wheel, corrected by it exactly. Step 2 - 3: **actuators** (the rig's own nonlinearity, flow
   gain differing between extending and retracting under load, and the posts' coupling through
   the truck).
4. ``no friction``: step 3 with the leaf springs' dry friction off in both the road and the
   linear-pans run. Step 3 - 4: **friction** (the truck's stick-slip leaf springs respond to the
   attenuated pan motion otherwise than to the road: no linear correction restores that).
5. What step 4 leaves: **band limit** (the road's content above the 30 Hz corner, which no
   band-limited correction restores: the friction-free road force through the same low-pass
   against the road force) and the **rest** (rear-tire lift-off, large angles, noise).

All DLCs of a case are taken on the same samples, where every correction of the chain has
settled; so step 1 here differs from ``benchmarks/generalization.py``'s figure (each method on its own
settled samples) by a few hundredths of a percent. The shares are differences along this order
and not unique (the effects interact): read them as "what removing this cause, given the causes
before it are gone, changes". Per failing wheel (outside 1 %), the table names the largest share
of the error's sign ("blame").

Writes a table (one row per case, means over the wheels that fail, or over all four when none
does) and the count of wheels blamed on each cause to ``docs/results/generalization_blame.md``
(``--results``: its folder), ending in the line that says how and where it was measured
(:mod:`rigsim.scenarios.studies.results_page`); prints that file and one JSON line with every share per
wheel. A diagnostic: nothing here corrects anything in the project.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from rigsim.correction.metrics.dlc import dlc  # noqa: E402
from rigsim.correction.output.apply import band_limit, correct_zero_phase  # noqa: E402
from rigsim.correction.output.filters import reference_filter  # noqa: E402
from rigsim.correction.output.pipeline import correct_forces  # noqa: E402
from rigsim.mjcf.names import CORNERS  # noqa: E402
from rigsim.scenarios.core.config import parse_scenario  # noqa: E402
from rigsim.scenarios.core.pool import run_jobs  # noqa: E402
from rigsim.scenarios.core.rig import Rig  # noqa: E402
from rigsim.scenarios.core.run import run  # noqa: E402
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE  # noqa: E402
from rigsim.scenarios.studies import scoring  # noqa: E402
from rigsim.scenarios.studies.decomposition import ExactLinearCorrection, linear_pans_run, with_friction  # noqa: E402
from rigsim.scenarios.studies.identify.compute import identify_rig  # noqa: E402
from rigsim.scenarios.studies.model_suite.goals import DLC_GOOD  # noqa: E402
from rigsim.scenarios.studies.results_page import script_command, write_results_page  # noqa: E402
from rigsim.scenarios.studies.suites import generalization_cases  # noqa: E402

#: A wheel whose corrected DLC is further than this from the road DLC fails (%): the generalization
#: suite's goal for most wheels (``benchmarks/generalization.py``, :data:`DLC_GOOD`).
GOAL_MOST_PCT = 100 * DLC_GOOD
#: The chain's causes, in the order they are removed.
CAUSES = ("identification", "actuators", "friction", "band_limit", "rest")
#: Where the results file goes by default: docs/results of this repository.
RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"
#: Kernel tail (sum |taps|) the exact linear corrections leave outside their margins, 1: their
#: kernels carry T_a^-1's slow tail (the small-signal T_a's ~1 rad/s zero) for seconds; at the scoring's
#: 1e-3 a 30 s run would keep ~10 s.
EXACT_TOLERANCE = 1e-2


def scenario(doc: dict, friction: bool):
    """The case's scenario, leaf-spring friction on or off."""
    return with_friction(parse_scenario(doc), friction)


def run_job(doc: dict, kind: str, friction: bool):
    """One MuJoCo run of the chain: "road", "rig", "identify" or "linear" (road mode, the pans
    following the profile through the linearized plant's own path of each wheel)."""
    sc = scenario(doc, friction)
    if kind == "identify":
        return identify_rig(sc)
    if kind != "linear":
        return run(sc, kind)
    return linear_pans_run(sc, diagonal=True)


def analyse_job(doc: dict, runs: dict) -> dict:
    """The chain's DLC errors (%) and shares per wheel for one case (``runs`` keyed (kind, friction))."""
    sc = scenario(doc, True)
    fs = runs[("road", True)].rate_hz
    tol = scoring.SETTLING_TOLERANCE
    plant = Rig(sc).linearize()  # friction never enters the linearization
    cache: dict = {}
    exact = [ExactLinearCorrection(plant, i, fs, EXACT_TOLERANCE, cache) for i in range(4)]

    def measured(r):
        return scoring.measured_force(r, scoring.NOISE_N, sc.seed)

    def exactly(force):
        return np.column_stack([correct_zero_phase(force[:, i], e) for i, e in enumerate(exact)])

    ident = correct_forces(measured(runs[("rig", True)]), runs[("identify", True)].actuators(), fs,
                           lowpass=BAND_LOWPASS, mode=BAND_MODE, settling_tolerance=tol)
    n = ident.corrected_N.shape[0]
    rows = ident.settled & reference_filter(fs, BAND_LOWPASS, settling_tolerance=tol).transient_mask(n, BAND_MODE)
    for e in exact:
        rows &= e.transient_mask(n)
    road_on = np.asarray(runs[("road", True)].signals["tire_force_N"], dtype=float)
    road_off = np.asarray(runs[("road", False)].signals["tire_force_N"], dtype=float)

    def err(force, road):
        return 100.0 * (dlc(force[rows]) / dlc(road[rows]) - 1.0)

    steps = {
        "identified": err(ident.corrected_N, road_on),
        "linearized": err(exactly(measured(runs[("rig", True)])), road_on),
        "linear_pans": err(exactly(measured(runs[("linear", True)])), road_on),
        "no_friction": err(exactly(measured(runs[("linear", False)])), road_off),
        "band_limit": err(band_limit(road_off, fs, BAND_LOWPASS, BAND_MODE), road_off),
    }
    shares = {"identification": steps["identified"] - steps["linearized"],
              "actuators": steps["linearized"] - steps["linear_pans"],
              "friction": steps["linear_pans"] - steps["no_friction"],
              "band_limit": steps["band_limit"],
              "rest": steps["no_friction"] - steps["band_limit"]}
    blame = {}
    for i, c in enumerate(CORNERS):
        e = steps["identified"][i]
        if abs(e) > GOAL_MOST_PCT:
            same_sign = {k: v[i] * np.sign(e) for k, v in shares.items()}
            blame[c] = max(same_sign, key=same_sign.get)
    return {"case": sc.name, "scored_s": float(np.count_nonzero(rows)) / fs,
            "steps_pct": {k: {c: float(v[i]) for i, c in enumerate(CORNERS)} for k, v in steps.items()},
            "shares_pct": {k: {c: float(v[i]) for i, c in enumerate(CORNERS)} for k, v in shares.items()},
            "blame": blame}


HEADER = ("case", "corrected vs road (fl fr rl rr)", "identification", "actuators", "friction", "band limit", "rest",
          "blame (wheels outside 1 %)")


def table_rows(rows: list[dict]) -> list[list[str]]:
    """Per case the error and the shares (means over the failing wheels, or all four): :data:`HEADER`'s cells."""
    out = []
    for r in rows:
        failing = list(r["blame"]) or list(CORNERS)
        err = " ".join(f"{r['steps_pct']['identified'][c]:+.1f}" for c in CORNERS)
        shares = [f"{np.mean([r['shares_pct'][k][c] for c in failing]):+.2f}" for k in CAUSES]
        blame = ", ".join(f"{c} {k}" for c, k in r["blame"].items()) or "-"
        out.append([r["case"], f"{err} %", *shares, blame])
    return out


def blame_counts(rows: list[dict]) -> dict[str, int]:
    """Per cause: how many wheels outside 1 % it is blamed for."""
    return {k: sum(1 for r in rows for b in r["blame"].values() if b == k) for k in CAUSES}


def note(rows: list[dict]) -> str:
    """The text under the table: what the shares are, and the wheels blamed on each cause."""
    counts = blame_counts(rows)
    scored = [r["scored_s"] for r in rows]
    return ("Shares in percentage points of the corrected DLC error, along the chain identification -> "
            "actuators -> friction -> band limit + rest, each step removing one cause with the rest kept; "
            f"means over the wheels outside {GOAL_MOST_PCT:g} % (all four where none is); blame: per wheel "
            "outside it, the largest share of the error's sign. Every step of a case on the same samples, where "
            f"every correction of the chain has settled ({min(scored):.0f}-{max(scored):.0f} s per case).\n\n"
            f"Wheels outside {GOAL_MOST_PCT:g} %: {sum(counts.values())}; blamed on "
            + ", ".join(f"{k.replace('_', ' ')} {n}" for k, n in counts.items()) + ".")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=24, help="the generalization suite's first N cases (1-24, default 24)")
    ap.add_argument("--duration-s", type=float, default=30.0, help="seconds per run (default 30)")
    ap.add_argument("--only", nargs="+", help="parts of case names to analyse (default: every case)")
    ap.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    ap.add_argument("--results", type=pathlib.Path, default=RESULTS,
                    help="folder of the results file generalization_blame.md (default docs/results)")
    args = ap.parse_args(argv)
    try:
        docs = generalization_cases(args.cases, args.duration_s)
    except ValueError as exc:
        raise SystemExit(f"--cases: {exc}") from None
    if args.only:
        docs = [d for d in docs if any(k in d["name"] for k in args.only)]
        if not docs:
            raise SystemExit(f"--only {' '.join(args.only)} matches no case of the suite")
    t0 = time.perf_counter()
    kinds = (("road", True), ("rig", True), ("identify", True), ("linear", True), ("road", False), ("linear", False))
    jobs = [(run_job, (d, k, f)) for d in docs for k, f in kinds]
    runs = run_jobs(jobs, workers=args.jobs, on_done=lambda i, _r: print(
        f"[{time.perf_counter() - t0:5.0f} s] {jobs[i][1][0]['name']} {jobs[i][1][1]} friction "
        f"{'on' if jobs[i][1][2] else 'off'}", file=sys.stderr, flush=True))
    by_case = {}
    for (_, (d, k, f)), r in zip(jobs, runs):
        by_case.setdefault(d["name"], {})[(k, f)] = r
    rows = run_jobs([(analyse_job, (d, by_case[d["name"]])) for d in docs], workers=args.jobs)
    page = write_results_page(args.results, "generalization_blame",
                              f"Where the corrected DLC error of {len(rows)} generalization case{'s' if len(rows) != 1 else ''} comes from, "
                              f"{args.duration_s:g} s each", HEADER, table_rows(rows),
                              script_command(__file__, argv), note=note(rows))
    print(page.read_text(encoding="utf-8"))
    counts = blame_counts(rows)
    print(json.dumps({"cases": len(rows), "duration_s": args.duration_s, "failing_wheels": sum(counts.values()),
                      "blamed": counts, "wall_s": round(time.perf_counter() - t0, 1), "rows": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
