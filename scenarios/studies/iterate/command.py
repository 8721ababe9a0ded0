"""``rigsim iterate``: input correction (drive-file iteration) on the simulated nonlinear rig.

::

    rigsim iterate SCENARIO.toml --target displacement|force --out DIR [--gain G]
                   [--max-iterations K] [--tolerance TOL] [--band-hz LO HI] [--duration-s S]

Sequence (every rig run is the nonlinear MuJoCo + hydraulics rig of :func:`scenarios.core.rig.run_rig`,
which accepts any drive):

1. road run (the target of the force iteration, the reference of every comparison) and the rig
   run with the original drive (the road profile; also the output correction's only rig run);
2. identification run: four independent broadband drives
   (:func:`scenarios.studies.validate.compute.identification_drive`), H1 FRF matrix drive -> pan displacement
   (``displacement``) or drive -> tire force (``force``), :func:`correction.iterate.identify_frf`;
3. the iteration :func:`correction.iterate.iterate_drive` on the analysed record (t >= 0; the
   lead-in's fade-in stays as it is, the update is tapered to zero at both ends), starting from
   the road profile: Moran's target (pan = profile) or the RPC-style target (tire force = road
   run's tire force);
4. :func:`scenarios.studies.evaluation.evaluate` on the original and on the iterated rig run: the DLC of
   road, rig with the original drive, rig with the iterated drive, and the output-corrected rig
   force (this project's method), with NRMSE against the road.

Writes ``DIR/drive.csv`` (the iterated drive, 1 kHz, t >= 0), ``DIR/iteration.json`` (error per
iteration, DLC table, run count, wall times) and ``DIR/iteration.png``. Bad input raises
:class:`scenarios.core.config.ScenarioError` before any run.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import json
import math
import pathlib
import time

import numpy as np

__all__ = ["add_parser", "cmd_iterate", "iterate_scenario", "TARGETS"]

TARGETS = ("displacement", "force")
IDENT_NPERSEG = 4096  # 1 kHz: 0.24 Hz resolution, ~30 averages per 60 s


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``iterate`` on an ``argparse`` sub-parsers object; sets ``func=cmd_iterate``."""
    c = subparsers.add_parser(
        "iterate", help="iterate the rig's drive file until the pans (or tire forces) match the road test",
        description="Input correction on the simulated rig: identify the rig's FRF matrix, then iterate "
                    "d_{k+1} = d_k + g H^-1 (target - response_k); compare with the output correction.")
    c.add_argument("scenario", help="scenario TOML file")
    c.add_argument("--target", choices=TARGETS, required=True,
                   help="displacement: pan displacement = road profile (Moran); force: tire force = the road "
                        "run's tire force (RPC-style remote target)")
    c.add_argument("--out", required=True, help="output folder (drive.csv, iteration.json, iteration.png)")
    c.add_argument("--gain", type=float, default=0.8, help="relaxation gain g (default 0.8; stable below ~2)")
    c.add_argument("--max-iterations", type=int, default=6, help="most drive updates (default 6)")
    c.add_argument("--tolerance", type=float, default=0.01, help="stop at this mean NRMSE (default 0.01)")
    c.add_argument("--band-hz", type=float, nargs=2, default=(0.3, 30.0), metavar=("LO", "HI"),
                   help="frequency band of the update, Hz (default 0.3 30)")
    c.add_argument("--coherence-min", type=float, default=0.8,
                   help="no update where the identification's coherence is below this (default 0.8)")
    c.add_argument("--duration-s", type=float, default=None, help="override the scenario's duration, s")
    c.add_argument("--noise-N", type=float, default=None, help="rms load-cell noise added to rig forces, N")
    c.add_argument("--run-anyway", action="store_true",
                   help="run even if the gain's predicted spectral radius is >= 1 (divergence still stops it)")
    c.add_argument("--quiet", action="store_true", help="no progress lines")
    c.set_defaults(func=cmd_iterate)
    return c


def _check_args(args) -> None:
    from scenarios.core.config import ScenarioError

    if not (math.isfinite(args.gain) and 0 < args.gain <= 4):
        raise ScenarioError(f"--gain must be in (0, 4], got {args.gain:g}")
    if args.gain >= 2 and not args.run_anyway:
        raise ScenarioError(
            f"--gain {args.gain:g} is not stable even with an exact rig model: the iteration's error map "
            f"I - g H H^-1 has spectral radius |1 - g| = {abs(1 - args.gain):g} >= 1; use 0 < g < 2 "
            "(or pass --run-anyway to watch it diverge)")
    if not 0 <= args.max_iterations <= 50:
        raise ScenarioError(f"--max-iterations must be in [0, 50], got {args.max_iterations}")
    if not (math.isfinite(args.tolerance) and 0 < args.tolerance < 1):
        raise ScenarioError(f"--tolerance must be in (0, 1), got {args.tolerance:g}")
    lo, hi = args.band_hz
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi <= 200):
        raise ScenarioError(f"--band-hz must be LO HI with 0 <= LO < HI <= 200 Hz, got {lo:g} {hi:g}")
    if not 0 <= args.coherence_min < 1:
        raise ScenarioError(f"--coherence-min must be in [0, 1), got {args.coherence_min:g}")
    if args.duration_s is not None and not (math.isfinite(args.duration_s) and 10 <= args.duration_s <= 3600):
        raise ScenarioError(
            f"--duration-s must be in [10, 3600] s (the output correction needs ~10 s to settle), got {args.duration_s:g}")
    if args.noise_N is not None and not (math.isfinite(args.noise_N) and args.noise_N >= 0):
        raise ScenarioError(f"--noise-N must be >= 0 N, got {args.noise_N:g}")


def _rig_runner(scenario, base_drive, decim: int, k0: int):
    """``run(drive_1k (N, 4)) -> recorded dict``: the rig with the drive replaced for t >= 0."""
    from scenarios.core.rig import run_rig
    from scenarios.core.runner import Drive

    t = base_drive.t_s
    t_out = t[k0::decim]

    def run(drive_1k: np.ndarray) -> dict:
        z = base_drive.z_m.copy()
        for i in range(z.shape[1]):
            z[k0:, i] = np.interp(t[k0:], t_out, drive_1k[:, i])
        d = Drive(t_s=t, z_m=z, v_mps=np.gradient(z, t, axis=0))
        return run_rig(scenario, d)

    return run


def _identify(scenario, target: str, duration_s: float, dt: float, decim: int):
    """Broadband identification run and the H1 FRF matrix (drive -> pan or tire force)."""
    from correction.iterate import identify_frf
    from scenarios.core.rig import run_rig
    from scenarios.core.runner import Drive
    from scenarios.studies.validate.compute import IDENT_SKIP_S, identification_drive

    z = identification_drive(duration_s + IDENT_SKIP_S, dt)
    t = np.arange(z.shape[0]) * dt
    rec = run_rig(scenario, Drive(t_s=t, z_m=z, v_mps=np.gradient(z, t, axis=0)))
    u = z[::decim][: rec["pan_m"].shape[0]]
    y = rec["pan_m"] if target == "displacement" else rec["tire_force_N"]
    fs = 1.0 / (dt * decim)
    skip = int(IDENT_SKIP_S * fs)
    nper = min(IDENT_NPERSEG, (u.shape[0] - skip) // 4)
    return identify_frf(u[skip:], y[skip:], fs, nper)


def iterate_scenario(scenario, target: str, *, gain: float = 0.8, max_iterations: int = 6,
                     tolerance: float = 0.01, band_hz=(0.3, 30.0), coherence_min: float = 0.8,
                     noise_N: float | None = None, run_anyway: bool = False, say=None) -> dict:
    """Run road, rig, identification and the iteration; return everything for the report.

    Returns a dict with ``iteration`` (:class:`correction.iterate.IterationResult`), ``road``,
    ``rig`` and ``rig_iterated`` (:class:`scenarios.core.results.RunResult`), ``eval_original`` and
    ``eval_iterated`` (:class:`scenarios.studies.evaluation.CaseEvaluation`), ``summary`` (JSON-ready).
    """
    from correction.iterate import IterationStabilityError, iterate_drive
    from mjcf.build import build_model
    from scenarios.core.config import ScenarioError
    from scenarios.studies.evaluation import NOISE_N, evaluate
    from scenarios.core.results import RunResult
    from scenarios.core.rig import actuator_params
    from scenarios.core.runner import HALF_STROKE_M, output_schedule, prepare_drive, run
    from scenarios.studies.sweep.case import tire_stiffness

    if target not in TARGETS:
        raise ScenarioError(f"target must be one of {', '.join(TARGETS)}, got {target!r}")
    say = say or (lambda s: None)
    noise = NOISE_N if noise_N is None else float(noise_N)
    params = actuator_params(scenario)
    model = build_model(scenario.vehicle)
    dt = float(model.opt.timestep)
    base = prepare_drive(scenario, model)
    k0, decim, _ = output_schedule(base, dt, scenario.output_rate_hz)
    fs = scenario.output_rate_hz
    walls = {}

    w0 = time.perf_counter()
    road = run(scenario, "road")
    walls["road_s"] = time.perf_counter() - w0
    say(f"road run: {walls['road_s']:.1f} s")
    w0 = time.perf_counter()
    rig = run(scenario, "rig")
    walls["rig_original_s"] = time.perf_counter() - w0
    say(f"rig run with the original drive: {walls['rig_original_s']:.1f} s")

    w0 = time.perf_counter()
    frf = _identify(scenario, target, max(30.0, scenario.duration_s), dt, decim)
    walls["identification_s"] = time.perf_counter() - w0
    say(f"identification run: {walls['identification_s']:.1f} s")

    key = "pan_m" if target == "displacement" else "tire_force_N"
    tgt = np.asarray(road.signals[key], dtype=float)
    if target == "displacement":
        tgt = np.asarray(rig.signals["profile_m"], dtype=float)
    drive0 = np.asarray(rig.signals["profile_m"], dtype=float)
    runner = _rig_runner(scenario, base, decim, k0)
    records = [{"pan_m": rig.signals["pan_m"], "tire_force_N": rig.signals["tire_force_N"], "events": rig.events}]

    def system(d):
        rec = runner(d)
        records.append(rec)
        return rec[key]

    def progress(step):
        say(f"iteration {step.index}: mean NRMSE {step.nrmse_mean:.4f}")

    w0 = time.perf_counter()
    try:
        res = iterate_drive(system, tgt, frf, fs, drive0=drive0, response0=np.asarray(rig.signals[key], dtype=float),
                            gain=gain, band_hz=tuple(band_hz), coherence_min=coherence_min,
                            max_iterations=max_iterations, tolerance=tolerance, drive_limit=HALF_STROKE_M,
                            on_unstable="run" if run_anyway else "raise", callback=progress)
    except IterationStabilityError as exc:
        raise ScenarioError(f"{exc} (or pass --run-anyway)") from None
    walls["iteration_s"] = time.perf_counter() - w0

    best = records[res.best_index]
    rig_it = RunResult(scenario_name=scenario.name, mode="rig", t_s=rig.t_s,
                       signals={"profile_m": res.drive, "pan_m": best["pan_m"], "tire_force_N": best["tire_force_N"]},
                       vehicle_mass_kg=rig.vehicle_mass_kg, events=best.get("events", {}), info={})
    kt = tire_stiffness(scenario.vehicle)
    try:
        ev0 = evaluate(road, rig, params=params, tire_N_per_m=kt, noise_N=noise, seed=scenario.seed)
        ev1 = evaluate(road, rig_it, params=params, tire_N_per_m=kt, noise_N=noise, seed=scenario.seed)
        eval_error = None
    except (ValueError, IndexError, np.linalg.LinAlgError) as exc:
        # The output correction's per-wheel identification can fail on a strongly nonlinear rig;
        # the drive iteration's result stands on its own, so report without the output correction.
        ev0 = ev1 = None
        eval_error = f"output correction failed: {type(exc).__name__}: {exc}"
    road_all = np.asarray(road.signals["tire_force_N"], dtype=float)
    rng = np.random.default_rng((int(scenario.seed), 8))  # the same noise as evaluate() adds
    noise_arr = noise * rng.standard_normal(road_all.shape) if noise > 0 else 0.0
    rig0_N = ev0.rig_N if ev0 is not None else np.asarray(rig.signals["tire_force_N"]) + noise_arr
    rig1_N = ev1.rig_N if ev1 is not None else np.asarray(best["tire_force_N"]) + noise_arr
    if ev0 is not None:
        s = ev0.settled & ev1.settled
    else:  # no correction filters: drop the iteration's end tapers (0.5 s) plus 0.5 s
        s = np.zeros(road_all.shape[0], dtype=bool)
        s[int(fs):-int(fs)] = True
    road_f = road_all[s]

    def nrmse_vs_road(x):
        return float(np.mean(np.sqrt(np.mean((x[s] - road_f) ** 2, axis=0)) / road_f.std(axis=0)))

    def dlc(x):
        return float(np.mean(x[s].std(axis=0) / x[s].mean(axis=0)))

    rig_runs_iter = 2 + (res.runs)  # original + identification + updates
    comparison = {
        "road": {"dlc": dlc(road_all), "nrmse_vs_road": 0.0, "rig_runs": 0},
        "rig_original_drive": {"dlc": dlc(rig0_N), "nrmse_vs_road": nrmse_vs_road(rig0_N), "rig_runs": 1,
                               "wall_s": walls["rig_original_s"]},
        "rig_iterated_drive": {"dlc": dlc(rig1_N), "nrmse_vs_road": nrmse_vs_road(rig1_N),
                               "rig_runs": rig_runs_iter,
                               "wall_s": walls["rig_original_s"] + walls["identification_s"] + walls["iteration_s"]},
    }
    if ev0 is not None:
        comparison["output_corrected"] = {
            "dlc": dlc(ev0.corrected_N["best"]), "nrmse_vs_road": nrmse_vs_road(ev0.corrected_N["best"]),
            "nrmse_vs_road_lowpassed": ev0.mean["nrmse_corrected_best"], "rig_runs": 1,
            "wall_s": walls["rig_original_s"]}
    for row in comparison.values():
        row["dlc_error"] = row["dlc"] / comparison["road"]["dlc"] - 1.0
    band_mask = (frf.f_hz >= band_hz[0]) & (frf.f_hz <= band_hz[1])
    summary = {
        "scenario": scenario.name,
        "target": target,
        "iteration": res.summary(),
        "identification": {"nperseg": int((frf.f_hz.size - 1) * 2), "averages": frf.averages,
                           "coherence_min_in_band": float(np.nanmin(frf.coherence[band_mask])),
                           "coherence_mean_in_band": float(np.nanmean(frf.coherence[band_mask]))},
        "comparison": comparison,
        "events_original": dict(rig.events),
        "events_iterated": best.get("events", {}),
        "output_correction_error": eval_error,
        "wall_time_s": {k: round(v, 2) for k, v in walls.items()},
        "noise_N": noise,
        "note": ("DLC and NRMSE averaged over the four wheels on the samples where all correction filters have "
                 "settled; rig forces include the load-cell noise; nrmse_vs_road: against the unfiltered road "
                 "force; rig_runs of the iteration count the original run, the identification run and the updates"),
    }
    return {"iteration": res, "road": road, "rig": rig, "rig_iterated": rig_it, "eval_original": ev0,
            "eval_iterated": ev1, "frf": frf, "summary": summary}


def _plot(summary: dict) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    steps = summary["iteration"]["steps"]
    fig, ax = plt.subplots(figsize=(6, 4))
    k = [s["index"] for s in steps]
    ax.semilogy(k, [s["nrmse_mean"] for s in steps], "o-k", label="mean")
    for i, c in enumerate(("fl", "fr", "rl", "rr")):
        ax.semilogy(k, [s["nrmse"][i] for s in steps], ".--", lw=0.8, label=c)
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.set_xlabel("iteration (rig run after the original)")
    ax.set_ylabel("NRMSE against the target")
    ax.set_title(f"{summary['scenario']}: target {summary['target']}, g = {summary['iteration']['gain']:g}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    return buf.getvalue()


def cmd_iterate(args) -> int:
    import sys

    from scenarios.core.config import load_scenario
    from scenarios.core.results import atomic_write_bytes, atomic_write_text

    _check_args(args)
    scenario = load_scenario(args.scenario)
    if args.duration_s is not None:
        scenario = dataclasses.replace(scenario, duration_s=float(args.duration_s))
    say = None if args.quiet else (lambda s: print(s, file=sys.stderr, flush=True))
    out = iterate_scenario(scenario, args.target, gain=args.gain, max_iterations=args.max_iterations,
                           tolerance=args.tolerance, band_hz=tuple(args.band_hz), coherence_min=args.coherence_min,
                           noise_N=args.noise_N, run_anyway=args.run_anyway, say=say)
    summary = out["summary"]
    res = out["iteration"]
    t = out["rig"].t_s
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack([t, res.drive]), delimiter=",", fmt="%.10g",
               header="time_s,drive_fl_m,drive_fr_m,drive_rl_m,drive_rr_m", comments="")
    d = pathlib.Path(args.out)
    png = _plot(summary)
    atomic_write_bytes(d / "drive.csv", buf.getvalue().encode("ascii"))
    atomic_write_text(d / "iteration.json", json.dumps(summary, indent=2) + "\n")
    atomic_write_bytes(d / "iteration.png", png)
    print(f"{scenario.name}: target {args.target}, {res.status}: {res.message}")
    print(f"{'':22s} {'DLC':>7s} {'DLC err':>8s} {'NRMSE':>7s} {'rig runs':>8s}")
    for name, row in summary["comparison"].items():
        print(f"{name:22s} {row['dlc']:7.4f} {100 * row['dlc_error']:7.1f}% {row['nrmse_vs_road']:7.3f} "
              f"{row['rig_runs']:8d}")
    print(f"wrote {d / 'drive.csv'}, {d / 'iteration.json'} and {d / 'iteration.png'}")
    return 0
