"""Where the output correction's time-history error (NRMSE) comes from, measured on the paper's cases.

::

    python benchmarks/nrmse_decomposition.py [--duration-s 60] [--cases medium_72 high_48 high_72]
                                             [--lead-s 0.05] [--lag-s 0.4] [--workers N] [--results docs/results]

For each case it runs (in worker processes, one MuJoCo run each, :func:`rigsim.scenarios.core.pool.run_jobs`)
the road test, the rig's identification (:func:`rigsim.scenarios.studies.identify.compute.identify_rig`,
as ``rigsim paper`` does) and three pan motions, each with the leaf springs' dry friction on and off:

* ``rig``: the nonlinear DYNTRAC rig (the real case), scored by the project's scoring
  (:func:`rigsim.scenarios.studies.scoring.score_pair`, method ``best``);
* ``linear``: a road-mode run whose pans follow the profile through a linear T_a per wheel (the
  linearized plant's own path of each wheel, :meth:`rigsim.scenarios.core.plant.PlantLinearization.simulate`
  with ``diagonal=True``), corrected with that same T_a (its exact frequency response, zero-phase,
  under the same 30 Hz low-pass): what is left is the truck's own nonlinearity (friction, lift-off,
  large angles), the noise, and the truck's coupling seen through front and rear T_a that differ;
* ``linear_mimo``: the same with the whole linearized plant (``diagonal=False``: each pan also
  moves with the other posts' drives, through the truck loading the actuators), corrected per wheel
  by the same diagonal T_a: adds the rig's own wheel-to-wheel coupling;

and for every configuration, on the correction's settled samples:

* ``corrected_identified`` (rig rows): NRMSE of the project's correction (T_a per corner identified
  before the test from independent random drives, as ``rigsim paper`` does);
* ``corrected_linear``: NRMSE of the correction with the linearized plant's T_a per wheel (on the
  linear rows the exact inverse of the pans' T_a);
* ``floor_per_wheel``, ``floor_4x4``: NRMSE of the best affine FIR filter (taps ``-lead .. lag``)
  fitted by least squares from the measured rig force(s) to the band-limited road force
  (:func:`rigsim.correction.output.floor.linear_floor`): the floor of any per-wheel / 4 x 4 linear correction of
  that length; in-sample (a lower bound: the fit also fits part of the residual, much more so
  when the residual is narrow-band, as lift-off bursts are) and ``_cv``, out-of-fold over
  :data:`FOLDS` contiguous folds (what such a filter does on samples it was not fitted on);
* ``noise``: the NRMSE the load cells' noise alone leaves after the correction (the correction
  applied to the noise only), ``bias``: |mean error| / std of the reference (in the NRMSE too);
* ``liftoff_road``, ``liftoff_measured``: fraction of samples in which a rear tire carries less than
  1 % of its static load (rest state of the rig), in the road run and in the rig / linear run;
  ``corrected_away_from_liftoff``: the correction's NRMSE on the samples farther than
  :data:`LIFTOFF_GUARD_S` from any such sample;
* ``floor_per_wheel_half``, ``floor_per_wheel_double``: the per-wheel floor with half and twice
  the taps, to show what the FIR's length leaves.

The FIR's length (defaults 0.05 s ahead, 0.4 s behind: 451 taps per input at 1 kHz): the kernel it
stands for, ``T_a^-1 |T_F|``, has a two-sided part from the zero-phase 30 Hz Butterworth (tens of
ms each side) and a causal tail from ``T_a^-1``'s slow pole at T_a's ~1 rad/s zero, which no
sub-second FIR holds. A scan on high/72 km/h (30 s, nonlinear rig, friction on) found: more than
0.05 s ahead changes nothing; behind, the per-wheel out-of-fold NRMSE falls up to ~0.5 s and
rises beyond (a longer filter fits noise), the 4 x 4 one is lowest at 0.2-0.3 s; 0.4 s is between.
The ``_half`` / ``_double`` columns of every run repeat that check. Where the error is small (the
linear rows without friction) the FIR's missing tail shows: the exact inverse then scores below
the FIR "floor", so read the floor as a floor only where it lies below the corrections.

NRMSE = rms(x - road_band) / std(road_band) (:func:`rigsim.correction.metrics.dlc.nrmse`), road_band = the road
force through ``band_limit(road, fs, "regularized", "zerophase")``; means over the four wheels.
Writes a table, one row per case and configuration, to ``docs/results/nrmse_decomposition.md``
(``--results``: its folder), ending in the line that says how and where it was measured
(:mod:`rigsim.scenarios.studies.results_page`); prints that file, then one JSON line with every number
(per wheel too). Nothing here corrects anything in the project: the floor is a diagnostic.
The runs through the linearized plant and its exact correction are
:mod:`rigsim.scenarios.studies.decomposition`'s.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import pathlib
import sys
import time

# One worker process per core does the least squares: BLAS threads on top would oversubscribe the
# cores (set before numpy is imported; the workers inherit it).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from rigsim.correction.metrics.dlc import nrmse  # noqa: E402
from rigsim.correction.output.apply import band_limit, correct_zero_phase  # noqa: E402
from rigsim.correction.output.filters import reference_filter  # noqa: E402
from rigsim.correction.output.floor import linear_floor  # noqa: E402
from rigsim.correction.output.pipeline import correct_forces  # noqa: E402
from rigsim.mjcf.names import CORNERS, REAR  # noqa: E402
from rigsim.mjcf.physics import tire_forces  # noqa: E402
from rigsim.scenarios.core.config import load_scenario  # noqa: E402
from rigsim.scenarios.core.files import to_json  # noqa: E402
from rigsim.scenarios.core.pool import run_jobs  # noqa: E402
from rigsim.scenarios.core.rig import Rig  # noqa: E402
from rigsim.scenarios.core.run import run  # noqa: E402
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE  # noqa: E402
from rigsim.scenarios.studies import scoring  # noqa: E402
from rigsim.scenarios.studies.decomposition import ExactLinearCorrection, linear_pans_run, with_friction  # noqa: E402
from rigsim.scenarios.studies.identify.compute import identify_rig  # noqa: E402
from rigsim.scenarios.studies.results_page import script_command, write_results_page  # noqa: E402
from rigsim.scenarios.studies.suites import paper_cases  # noqa: E402

CONFIGS = tuple((k, f) for k in ("rig", "linear", "linear_mimo") for f in (True, False))
LABELS = {"rig": "nonlinear rig", "linear": "linear T_a per wheel", "linear_mimo": "linear 4x4 T (coupled pans)"}
#: A rear tire below this fraction of its static load counts as lifted off, 1.
LIFTOFF_FRACTION = 0.01
#: Samples closer than this to a rear lift-off (road or measured run) are left out of
#: ``corrected_away_from_liftoff``: about the correction kernel's half-width, s.
LIFTOFF_GUARD_S = 0.25
#: Folds of the floors' cross-validation (out-of-fold NRMSE beside the in-sample one).
FOLDS = 5
#: Where the results file goes by default: docs/results of this repository.
RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"


def scenario_of(path: str, duration_s: float, friction: bool):
    """The scenario at ``path`` with ``duration_s`` (s), leaf-spring friction on or off."""
    return with_friction(dataclasses.replace(load_scenario(path), duration_s=float(duration_s)), friction)


# ----------------------------------------------------------------------------- worker jobs: runs
def run_job(path: str, duration_s: float, kind: str, friction: bool):
    """One MuJoCo run: ``kind`` "road", "rig", "linear" (road mode, the pans through the linear T_a
    per wheel), "linear_mimo" (the pans through the whole linearized 4 x 4 plant: each pan also
    moved by the other posts' drives) or "identify" (the rig characterized before the test, as the
    paper study does)."""
    sc = scenario_of(path, duration_s, friction)
    if kind == "identify":
        return identify_rig(sc)
    if kind not in ("linear", "linear_mimo"):
        return run(sc, kind)
    return linear_pans_run(sc, diagonal=(kind == "linear"))


# ----------------------------------------------------------------------------- worker jobs: analysis
def _lifted(force_N: np.ndarray, static_N: np.ndarray) -> np.ndarray:
    """Samples where a rear tire carries less than LIFTOFF_FRACTION of its static load."""
    rear = [CORNERS.index(c) for c in REAR]
    return np.any(force_N[:, rear] < LIFTOFF_FRACTION * static_N[rear], axis=1)


def _liftoff(force_N: np.ndarray, static_N: np.ndarray) -> float:
    return float(np.mean(_lifted(force_N, static_N)))


def _mean(a) -> float:
    return float(np.mean(a))


def analyse_job(path: str, duration_s: float, kind: str, friction: bool, road, measured, identification,
                lead: int, lag: int, noise_N: float) -> dict:
    """Every figure of one case and configuration (see the module notes); per wheel and means.

    ``kind`` "rig" (``measured`` the nonlinear rig run, corrected by the project's scoring with
    ``identification``'s T_a and by the linearized plant's T_a), "linear" (``measured`` the run
    through the linear T_a per wheel, corrected by it exactly) or "linear_mimo" (the run through
    the linear 4 x 4 plant, corrected per wheel by its diagonal).
    """
    sc = scenario_of(path, duration_s, friction)
    rig_model = Rig(sc)
    plant = rig_model.linearize()  # the same linear T_a the "linear" run's pans followed
    fs = road.rate_hz
    tol = scoring.SETTLING_TOLERANCE
    road_band = band_limit(np.asarray(road.signals["tire_force_N"], dtype=float), fs, BAND_LOWPASS, BAND_MODE)
    rig_N = scoring.measured_force(measured, noise_N, sc.seed)  # the load cells' force with their noise
    noise = rig_N - np.asarray(measured.signals["tire_force_N"], dtype=float)
    rows = reference_filter(fs, BAND_LOWPASS, settling_tolerance=tol).transient_mask(rig_N.shape[0], BAND_MODE)
    cache: dict = {}
    exact = [ExactLinearCorrection(plant, i, fs, tol, cache) for i in range(4)]
    for e in exact:
        rows &= e.transient_mask(rows.size)
    corr_lin = np.column_stack([correct_zero_phase(rig_N[:, i], e) for i, e in enumerate(exact)])
    out: dict = {}
    if kind == "rig":
        score = scoring.score_pair(road, measured, rig_model, methods=(scoring.BEST,),
                                   identified=identification.actuators(), noise_N=noise_N, seed=sc.seed)
        best = score.methods[scoring.BEST.name]
        if not np.array_equal(score.rig_N, rig_N):
            raise RuntimeError("the scoring measured another rig force than scoring.measured_force gives")
        rows &= best.settled
        corr = best.corrected_N
        corr_noise = correct_forces(noise, identification.actuators(), fs, lowpass=BAND_LOWPASS, mode=BAND_MODE,
                                    settling_tolerance=tol).corrected_N
        out["corrected_identified"] = nrmse(corr[rows], road_band[rows])
        out["corrected_identified_scoring"] = np.asarray(best.figures["nrmse_corrected"])  # on its own samples
    else:
        corr = corr_lin
        corr_noise = np.column_stack([correct_zero_phase(noise[:, i], e) for i, e in enumerate(exact)])
    out["corrected_linear"] = nrmse(corr_lin[rows], road_band[rows])
    out["noise"] = nrmse(road_band[rows] + corr_noise[rows], road_band[rows])
    err = corr[rows] - road_band[rows]
    out["bias"] = np.abs(err.mean(axis=0)) / road_band[rows].std(axis=0)
    for name, ld, lg, coupled in (("floor_per_wheel", lead, lag, False), ("floor_4x4", lead, lag, True),
                                  ("floor_per_wheel_half", lead // 2, lag // 2, False),
                                  ("floor_per_wheel_double", 2 * lead, 2 * lag, False)):
        fl = linear_floor(rig_N, road_band, ld, lg, coupled=coupled, rows=rows, folds=FOLDS)
        out[name], out[name + "_cv"] = fl.nrmse, fl.nrmse_cv
    data = rig_model.rest_state()
    static = tire_forces(rig_model.model, data, rig_model.index)  # every element on the tire tendon
    road_f, meas_f = np.asarray(road.signals["tire_force_N"]), np.asarray(measured.signals["tire_force_N"])
    out["liftoff_road"], out["liftoff_measured"] = _liftoff(road_f, static), _liftoff(meas_f, static)
    # the correction away from lift-off: rows farther than LIFTOFF_GUARD_S from any rear lift-off
    lifted = _lifted(road_f, static) | _lifted(meas_f, static)
    guard = int(round(LIFTOFF_GUARD_S * fs))
    near = np.convolve(lifted.astype(float), np.ones(2 * guard + 1), mode="same") > 0
    away = rows & ~near
    out["away_from_liftoff_s"] = float(np.count_nonzero(away)) / fs
    if np.count_nonzero(away) > 1:
        out["corrected_away_from_liftoff"] = nrmse(corr[away], road_band[away])
    wheels = {k: {c: float(v[i]) for i, c in enumerate(CORNERS)} for k, v in out.items() if np.ndim(v) == 1}
    means = {k: (_mean(v) if np.ndim(v) == 1 else float(v)) for k, v in out.items()}
    return {"case": sc.name, "configuration": kind, "friction": friction, "noise_N": float(noise_N),
            "mean": means, "wheels": wheels,
            "scored_s": float(np.count_nonzero(rows)) / fs, "static_tire_N": static.tolist(),
            "events": {k: sorted(v) for k, v in measured.events.items()}}


# ----------------------------------------------------------------------------- the table
HEADER = ("case", "pans", "leaf friction", "corrected, identified T_a", "corrected, linearized T_a",
          "linear floor per wheel (CV)", "linear floor 4x4 (CV)", "noise alone", "corrected away from lift-off",
          "rear lift-off road / measured")


def table_rows(rows: list[dict]) -> list[list[str]]:
    """The results table's cells, one row per case and configuration, means over the wheels (:data:`HEADER`)."""
    out = []
    for r in rows:
        m = r["mean"]
        ident = f"{m['corrected_identified']:.4f}" if "corrected_identified" in m else "-"
        away = m.get("corrected_away_from_liftoff")
        away = "-" if away is None else f"{away:.4f} ({m['away_from_liftoff_s']:.0f} s)"
        out.append([f"{r['case']} ({r['scored_s']:.0f} s)", LABELS[r["configuration"]],
                    "on" if r["friction"] else "off", ident, f"{m['corrected_linear']:.4f}",
                    f"{m['floor_per_wheel']:.4f} ({m['floor_per_wheel_cv']:.4f})",
                    f"{m['floor_4x4']:.4f} ({m['floor_4x4_cv']:.4f})", f"{m['noise']:.4f}", away,
                    f"{m['liftoff_road']:.2%} / {m['liftoff_measured']:.2%}"])
    return out


def note(rows: list[dict], taps: tuple[int, int], fs: float) -> str:
    """The text under the table: what the columns are, and the FIR length check per row."""
    lead, lag = taps
    text = ("NRMSE against the road force through the 30 Hz band limit (zero-phase), mean of the four wheels, on the "
            "samples where every correction of the row has settled (seconds after the case name). Identified T_a: the "
            "project's correction (the rig characterized before the test, rigsim identify); linearized T_a: each "
            "wheel's own path of the linearized plant, which the per-wheel linear rows' pans follow (there: the "
            "exact inverse). Linear floor: the best affine FIR "
            f"(lags -{lead}..{lag} samples: {lead / fs:g} s ahead, {lag / fs:g} s behind) fitted on the road force "
            f"itself, in-sample (CV: {FOLDS}-fold out-of-fold). Noise alone: the {rows[0]['noise_N']:g} N load-cell "
            "noise through the row's first correction. Away from lift-off: that correction on the samples farther "
            f"than {LIFTOFF_GUARD_S:g} s from any rear tire below {LIFTOFF_FRACTION:.0%} of its static load.")
    check = ["FIR length check, per-wheel floor in-sample [CV] with half / these / twice the taps:", ""]
    for r in rows:
        m = r["mean"]
        check.append(f"- {r['case']}, {LABELS[r['configuration']]}, friction {'on' if r['friction'] else 'off'}: "
                     + " / ".join(f"{m['floor_per_wheel' + k]:.4f} [{m['floor_per_wheel' + k + '_cv']:.4f}]"
                                  for k in ("_half", "", "_double")))
    return text + "\n\n" + "\n".join(check)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration-s", type=float, default=60.0, help="analysed seconds per run (default 60)")
    ap.add_argument("--cases", nargs="+", help="parts of the paper scenarios' file names (default: all three)")
    ap.add_argument("--lead-s", type=float, default=0.05, help="non-causal span of the floor's FIR, s (default 0.05)")
    ap.add_argument("--lag-s", type=float, default=0.4, help="causal span of the floor's FIR, s (default 0.4)")
    ap.add_argument("--noise-N", type=float, default=scoring.NOISE_N,
                    help=f"rms load-cell noise, N (default the scoring's {scoring.NOISE_N:g})")
    ap.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    ap.add_argument("--results", type=pathlib.Path, default=RESULTS,
                    help="folder of the results file nrmse_decomposition.md (default docs/results)")
    args = ap.parse_args(argv)
    if not (args.duration_s > 0 and args.lead_s >= 0 and args.lag_s > 0 and args.noise_N >= 0):
        raise SystemExit("--duration-s and --lag-s must be > 0 s, --lead-s and --noise-N >= 0")
    try:
        paths = [str(p) for p in paper_cases(args.cases)]
    except ValueError as exc:
        raise SystemExit(f"--cases: {exc}") from None
    fs = load_scenario(paths[0]).output_rate_hz
    lead, lag = int(round(args.lead_s * fs)), int(round(args.lag_s * fs))
    t0 = time.perf_counter()
    kinds = [(k, f) for k in ("identify", "rig", "linear", "linear_mimo", "road") for f in (True, False)]
    jobs = [(run_job, (p, args.duration_s, k, f)) for k, f in kinds for p in paths]

    def said(i, _r):
        p, _, k, f = jobs[i][1]
        print(f"[{time.perf_counter() - t0:6.0f} s] run {pathlib.Path(p).stem} {k} friction {'on' if f else 'off'}",
              file=sys.stderr, flush=True)

    runs = run_jobs(jobs, workers=args.workers, on_done=said)
    by = {(jobs[i][1][0], jobs[i][1][2], jobs[i][1][3]): r for i, r in enumerate(runs)}
    analyses = [(analyse_job, (p, args.duration_s, k, f, by[(p, "road", f)], by[(p, k, f)],
                               by[(p, "identify", f)] if k == "rig" else None, lead, lag, args.noise_N))
                for p in paths for k, f in CONFIGS]

    def analysed(i, r):
        print(f"[{time.perf_counter() - t0:6.0f} s] analysed {r['case']} {r['configuration']} friction "
              f"{'on' if r['friction'] else 'off'}", file=sys.stderr, flush=True)

    rows = run_jobs(analyses, workers=args.workers, on_done=analysed)
    page = write_results_page(args.results, "nrmse_decomposition",
                              f"Where the linear correction's NRMSE comes from: the paper's cases, {args.duration_s:g} s",
                              HEADER, table_rows(rows), script_command(__file__, argv), note=note(rows, (lead, lag), fs))
    print(page.read_text(encoding="utf-8"))
    result = {"duration_s": args.duration_s, "rate_hz": fs, "lead_samples": lead, "lag_samples": lag,
              "noise_N": args.noise_N, "liftoff_fraction_of_static": LIFTOFF_FRACTION,
              "wall_time_s": round(time.perf_counter() - t0, 1), "cpu_count": os.cpu_count(), "rows": rows}
    print(json.dumps(json.loads(to_json(result))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
