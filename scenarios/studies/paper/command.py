"""``rigsim paper``: the paper's cases run in road and rig mode, beside the paper's values.

The main job of the project. The paper's tables (reference copy in
``../shared/reference/paper-correction-of-dynamic-wheel-forces.md``) are kept here as data so
that every report prints them beside the simulated values.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import os
import pathlib
import sys

__all__ = ["PAPER_TABLE1", "PAPER_TABLE2", "add_parser", "cmd_paper", "run_cases"]

#: Table 2 of the paper: DLC of the road test, of DYNTRAC, and of DYNTRAC corrected, keyed by
#: the shipped scenario names (scenarios/data/paper/*.toml).
PAPER_TABLE2: dict[str, dict[str, float]] = {
    "paper-medium-72kmh-6360kg": {"road": 0.0985, "rig": 0.0854, "corrected": 0.0994},
    "paper-high-48kmh-3640kg": {"road": 0.1912, "rig": 0.1497, "corrected": 0.1794},
    "paper-high-72kmh-3640kg": {"road": 0.2105, "rig": 0.1754, "corrected": 0.2139},
}

#: Table 1 of the paper (high roughness, 72 km/h, 3640 kg): road test, DYNTRAC test, the
#: nonlinear model of the rig, the linearized model.
PAPER_TABLE1: dict[str, float] = {"road_test": 0.2105, "rig_test": 0.1754, "nonlinear_model": 0.1748,
                                  "linearized_model": 0.1724}


def _run_job(path: str, mode: str, duration_s: float | None = None, pose_rate_hz: float | None = None):
    """Worker: load and run one scenario in one mode (in its own process)."""
    import dataclasses

    from scenarios.core.config import load_scenario
    from scenarios.core.runner import run

    scenario = load_scenario(path)
    if duration_s is not None:
        scenario = dataclasses.replace(scenario, duration_s=duration_s)
    return run(scenario, mode, pose_rate_hz=pose_rate_hz)


def run_cases(jobs: list[tuple[str, str]], *, workers: int | None = None, quiet: bool = False,
              duration_s: float | None = None, pose_rate_hz: float | None = None) -> list:
    """Run ``(scenario_path, mode)`` jobs in a process pool; results in the order of ``jobs``.

    One run per process at a time: MuJoCo's actuator callbacks are process-global.
    ``duration_s`` (s) overrides every scenario's duration.
    """
    workers = max(1, min(len(jobs), workers or os.cpu_count() or 1))
    results = {}
    with cf.ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(_run_job, p, m, duration_s, pose_rate_hz): (p, m) for p, m in jobs}
        try:
            for n_done, fut in enumerate(cf.as_completed(futures), 1):
                r = fut.result()
                results[futures[fut]] = r
                if not quiet:
                    print(f"[{n_done}/{len(jobs)}] {r.scenario_name} {r.mode}: DLC {r.summary()['dlc_mean']:.4f} "
                          f"({r.info['wall_time_s']:.1f} s)", file=sys.stderr)
        except BaseException:
            for f in futures:
                f.cancel()
            raise
    return [results[j] for j in jobs]


def _table(rows: list[dict]) -> str:
    """Table 2 analogue: means over the four wheels, the paper's values in brackets."""
    head = (f"{'case':28s} {'road':>15s} {'rig':>15s} {'corr. paper':>15s} {'corrected':>10s} "
            f"{'road LP':>8s} {'NRMSE':>6s}")
    lines = [head, "-" * len(head)]
    for r in rows:
        ref = r["paper"]
        lines.append(
            f"{r['case']:28s} {r['dlc_road']:7.4f} ({ref['road']:.4f}) {r['dlc_rig']:7.4f} ({ref['rig']:.4f}) "
            f"{r['dlc_corrected_paper']:7.4f} ({ref['corrected']:.4f}) {r['dlc_corrected']:10.4f} "
            f"{r['dlc_road_lowpassed']:8.4f} {r['nrmse_corrected']:6.3f}"
        )
    lines.append("DLC = std/mean of the wheel force, mean of the four wheels; (paper's Table 2). corr. paper: eq. 4 and")
    lines.append("the paper's 16/24 Hz low-pass; corrected: T_a identified per wheel, 30 Hz low-pass; road LP: the road")
    lines.append("force through the same low-pass; NRMSE = rms(corrected - road LP) / std(road LP).")
    return "\n".join(lines)


def _row(case: str, ev) -> dict:
    """paper.json's entry of one case: means over the wheels, per wheel, the paper's values."""
    m = ev.mean
    keys = {
        "dlc_road": "dlc_road",
        "dlc_rig": "dlc_rig",
        "dlc_corrected_paper": "dlc_corrected_paper",
        "dlc_corrected": "dlc_corrected_best",
        "dlc_road_lowpassed": "dlc_road_lowpassed_best",
        "nrmse_corrected": "nrmse_corrected_best",
        "dlc_road_lowpassed_paper": "dlc_road_lowpassed_paper",
        "nrmse_corrected_paper": "nrmse_corrected_paper",
    }
    row = {"case": case}
    row.update({k: round(m[v], 6) for k, v in keys.items()})
    row["wheels"] = {c: {k: round(w[v], 6) for k, v in keys.items()} for c, w in ev.wheels.items()}
    row["paper"] = PAPER_TABLE2.get(case, {})
    row["noise_N"] = ev.noise_N
    row["analysed_s"] = round(float(ev.settled.sum()) / (1.0 / float(ev.t_s[1] - ev.t_s[0])), 3)
    return row


def cmd_paper(args) -> int:
    from mjcf.build import build_model
    from mjcf.physics import tire_stiffness
    from scenarios.core.config import ScenarioError, load_scenario, paper_scenarios
    from scenarios.studies.evaluation import METHODS, evaluate
    from scenarios.studies.paper.report import write_report
    from scenarios.core.results import atomic_write_text, write_run
    from scenarios.core.rig import actuator_params

    paths = paper_scenarios()
    scenarios = [load_scenario(p) for p in paths]  # validate everything before anything runs
    if args.duration_s is not None and not 0 < args.duration_s <= 3600:
        raise ScenarioError(f"--duration-s must be in (0, 3600] s, got {args.duration_s:g}")
    if args.duration_s is not None and args.duration_s < 10:
        raise ScenarioError(
            f"--duration-s {args.duration_s:g} s is too short: the correction's start-up transient alone "
            "lasts ~4 s; use at least 10 s"
        )
    if args.jobs is not None and args.jobs < 1:
        raise ScenarioError(f"--jobs must be at least 1, got {args.jobs}")
    if not args.noise_N >= 0:
        raise ScenarioError(f"--noise-N must be >= 0 N, got {args.noise_N:g}")
    jobs = [(str(p), mode) for p in paths for mode in ("road", "rig")]
    pose_rate = None
    if args.rrd:
        from scenarios.review.recording import DEFAULT_POSE_RATE_HZ

        pose_rate = DEFAULT_POSE_RATE_HZ
    results = run_cases(jobs, workers=args.jobs, quiet=args.quiet, duration_s=args.duration_s,
                        pose_rate_hz=pose_rate)
    rows, evaluations = [], {}
    for scenario, road, rig in zip(scenarios, results[0::2], results[1::2]):
        kt = tire_stiffness(build_model(scenario.vehicle))
        ev = evaluate(road, rig, params=actuator_params(scenario), tire_N_per_m=kt, noise_N=args.noise_N,
                      seed=scenario.seed)
        evaluations[scenario.name] = (road, rig, ev)
        rows.append(_row(scenario.name, ev))
    doc = {
        "cases": rows,
        "methods": {m.name: m.description for m in METHODS},
        "note": ("means over the four wheels (per wheel under 'wheels'); statistics over the samples where "
                 "every correction filter has settled; 'paper': Table 2 of the reference paper"),
    }
    table = _table(rows)
    out = pathlib.Path(args.out)
    for r in results:
        write_run(r, out / r.scenario_name / r.mode)
    report_files = write_report(out, evaluations, rows, table)
    if args.rrd:
        from scenarios.review.recording import write_recording

        write_recording(args.rrd, results, corrected={n: e[2].corrected_N["best"] for n, e in evaluations.items()},
                        dlc_table=table, spawn=args.view)
        print(f"wrote recording {args.rrd} (one recording per case)")
    atomic_write_text(out / "paper.json", json.dumps(doc, indent=2) + "\n")
    print(table)
    print(f"wrote {out / 'paper.json'}, {out / 'report.md'}, {len(report_files) - 1} figures and one folder per case and mode")
    return 0


def add_parser(subparsers) -> None:
    """Register ``rigsim paper``."""
    from scenarios.studies.evaluation import NOISE_N

    pp = subparsers.add_parser("paper", help="the paper's three cases: road and rig runs, output correction, Table 2")
    pp.add_argument("--out", required=True, help="output folder")
    pp.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    pp.add_argument("--duration-s", type=float, default=None,
                    help="override every case's duration in s (a quick look; the paper's cases run 60 s)")
    pp.add_argument("--noise-N", type=float, default=NOISE_N,
                    help=f"rms of the white noise added to the measured rig force, N (default {NOISE_N:g}; 0: off)")
    pp.add_argument("--rrd", default=None, help="also write a rerun recording (.rrd), one recording per case")
    pp.add_argument("--view", action="store_true", help="with --rrd: open the recording in the rerun viewer")
    pp.add_argument("--quiet", action="store_true", help="no progress output")
    pp.set_defaults(func=cmd_paper)
