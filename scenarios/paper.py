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
#: the shipped scenario names (scenarios/paper/*.toml).
PAPER_TABLE2: dict[str, dict[str, float]] = {
    "paper-medium-72kmh-6360kg": {"road": 0.0985, "rig": 0.0854, "corrected": 0.0994},
    "paper-high-48kmh-3640kg": {"road": 0.1912, "rig": 0.1497, "corrected": 0.1794},
    "paper-high-72kmh-3640kg": {"road": 0.2105, "rig": 0.1754, "corrected": 0.2139},
}

#: Table 1 of the paper (high roughness, 72 km/h, 3640 kg): road test, DYNTRAC test, the
#: nonlinear model of the rig, the linearized model.
PAPER_TABLE1: dict[str, float] = {"road": 0.2105, "rig": 0.1754, "nonlinear_model": 0.1748, "linearized_model": 0.1724}


def _run_job(path: str, mode: str, duration_s: float | None = None):
    """Worker: load and run one scenario in one mode (in its own process)."""
    import dataclasses

    from scenarios.config import load_scenario
    from scenarios.runner import run

    scenario = load_scenario(path)
    if duration_s is not None:
        scenario = dataclasses.replace(scenario, duration_s=duration_s)
    return run(scenario, mode)


def run_cases(jobs: list[tuple[str, str]], *, workers: int | None = None, quiet: bool = False,
              duration_s: float | None = None) -> list:
    """Run ``(scenario_path, mode)`` jobs in a process pool; results in the order of ``jobs``.

    One run per process at a time: MuJoCo's actuator callbacks are process-global.
    ``duration_s`` (s) overrides every scenario's duration.
    """
    workers = max(1, min(len(jobs), workers or os.cpu_count() or 1))
    results = {}
    with cf.ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(_run_job, p, m, duration_s): (p, m) for p, m in jobs}
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


def _table(by_case: dict, modes) -> str:
    head = f"{'case':28s}" + "".join(f"{'DLC ' + m:>10s}{'paper':>8s}" for m in modes) + f"{'rig/road':>10s}{'paper':>8s}"
    rows = [head, "-" * len(head)]
    for case, d in by_case.items():
        ref = PAPER_TABLE2.get(case, {})
        row = f"{case:28s}"
        for m in modes:
            row += f"{d['dlc_' + m]:10.4f}{ref.get(m, float('nan')):8.4f}"
        if "dlc_road" in d and "dlc_rig" in d:
            row += f"{d['dlc_rig'] / d['dlc_road']:10.3f}{ref['rig'] / ref['road'] if ref else float('nan'):8.3f}"
        rows.append(row)
    return "\n".join(rows)


def cmd_paper(args) -> int:
    from scenarios.config import load_scenario, paper_scenarios
    from scenarios.results import atomic_write_text, write_run

    from scenarios.config import ScenarioError

    paths = paper_scenarios()
    for p in paths:  # validate everything before anything runs
        load_scenario(p)
    if args.duration_s is not None and not 0 < args.duration_s <= 3600:
        raise ScenarioError(f"--duration-s must be in (0, 3600] s, got {args.duration_s:g}")
    if args.jobs is not None and args.jobs < 1:
        raise ScenarioError(f"--jobs must be at least 1, got {args.jobs}")
    jobs = [(str(p), mode) for p in paths for mode in args.modes]
    results = run_cases(jobs, workers=args.jobs, quiet=args.quiet, duration_s=args.duration_s)
    out = pathlib.Path(args.out)
    for r in results:
        write_run(r, out / r.scenario_name / r.mode)
    by_case: dict[str, dict[str, float]] = {}
    for r in results:
        by_case.setdefault(r.scenario_name, {})[f"dlc_{r.mode}"] = r.summary()["dlc_mean"]
    doc = {
        "cases": [
            {"case": case, **{k: round(v, 6) for k, v in d.items()},
             "paper": PAPER_TABLE2.get(case, {}),
             "wheels": {r.mode: {c: s["dlc"] for c, s in r.statistics().items()}
                        for r in results if r.scenario_name == case}}
            for case, d in by_case.items()
        ],
        "note": "dlc_* are means over the four wheels; paper: Table 2 of the reference paper",
    }
    print(_table(by_case, args.modes))
    atomic_write_text(out / "paper.json", json.dumps(doc, indent=2) + "\n")
    print(f"wrote {out / 'paper.json'} and one folder per case and mode")
    return 0


def add_parser(subparsers) -> None:
    """Register ``rigsim paper``."""
    pp = subparsers.add_parser("paper", help="run the paper's three cases and compare with its tables")
    pp.add_argument("--out", required=True, help="output folder")
    pp.add_argument("--modes", nargs="+", choices=("road", "rig"), default=["road", "rig"],
                    help="modes to run (default: road rig)")
    pp.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    pp.add_argument("--duration-s", type=float, default=None,
                    help="override every case's duration in s (a quick look; the paper's cases run 60 s)")
    pp.add_argument("--quiet", action="store_true", help="no progress output")
    pp.set_defaults(func=cmd_paper)
