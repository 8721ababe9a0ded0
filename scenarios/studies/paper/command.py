"""``rigsim paper``: the command-line adapter of the paper study (arguments, progress, files)."""

from __future__ import annotations

import functools
import math
import pathlib
import sys

from rigsim.scenarios.core.flags import (add_command, add_duration, add_force, add_jobs, add_noise, add_out, add_quiet,
                                         add_recording, add_rig)

__all__ = ["add_parser", "cmd_paper", "RIG", "SERIES_FORMATS"]

#: The configuration ``rigsim paper`` runs unless ``--rig`` names another: the simulated DYNTRAC,
#: where the paper's method gives the paper's Table 2 (a key of
#: :data:`rigsim.scenarios.core.config.PAPER_CONFIGURATIONS`).
RIG = "dyntrac"
#: ``--series`` formats: the keys of :data:`rigsim.scenarios.core.results.TIMESERIES_FORMATS`, listed here
#: because importing that module for ``rigsim --help`` would load numpy (the tests pin them equal).
SERIES_FORMATS = ("csv", "mf4", "rsp", "tdms")


def add_parser(subparsers) -> None:
    """Register ``rigsim paper``."""
    pp = add_command(subparsers, "paper", "the paper's three cases: road and rig runs, output correction, Table 2",
                     "Runs each case on the road and on the rig (the simulated DYNTRAC fitted to the paper; "
                     "--rig design: the project's design rig), corrects the rig's forces, prints Table 2 and the "
                     "damage table and writes them with the figures; --series also writes every run's time series.")
    add_out(pp, holds="paper.json, report.md, figures, each run's result.json")
    add_jobs(pp)
    add_duration(pp, "every case's analysed record", "the paper's 60 s; shorter for a quick look")
    add_rig(pp, default=RIG)
    pp.add_argument("--series", default=None, choices=SERIES_FORMATS,
                    help="also write each road and rig run's time series, timeseries.<ext> beside its result.json: "
                         "csv (about 30 MB per case of 60 s), mf4 (ASAM MDF4), rsp (MTS RPC III, int16) or tdms "
                         "(NI); mf4 and tdms need pip install -e \".[lab]\" (default: none)")
    add_noise(pp)  # None: rigsim.scenarios.studies.scoring.NOISE_N, applied in cmd_paper
    add_recording(pp, "each case")
    pp.add_argument("--model", action="store_true",
                    help="add a third method: each rig record corrected by a truck model calibrated on its own "
                         "signals, the cab held and fitted, the better kept (about 1-2.5 CPU-minutes per case)")
    pp.add_argument("--truck", default=None, metavar="TRUCK.toml",
                    help="run the paper's cases with the truck this scenario file's [vehicle] describes (its "
                         "geometry, suspension, tires, masses; each case keeps its own payload)")
    add_force(pp)
    add_quiet(pp)
    pp.set_defaults(func=cmd_paper)


def _check(args) -> None:
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.core.pool import worker_count

    d = args.duration_s
    if d is not None and not (math.isfinite(d) and 0 < d <= 3600):
        raise ScenarioError(f"--duration-s must be in (0, 3600] s, got {d:g}")
    from rigsim.scenarios.studies.scoring import MIN_DURATION_S

    if d is not None and d < MIN_DURATION_S:
        raise ScenarioError(f"--duration-s {d:g} s is too short: the correction's start-up transient alone "
                            f"lasts ~4 s; use at least {MIN_DURATION_S:g} s")
    try:
        worker_count(args.jobs)
    except ValueError:
        raise ScenarioError(f"--jobs must be at least 1, got {args.jobs}") from None
    if args.noise_N is not None and not (math.isfinite(args.noise_N) and args.noise_N >= 0):
        raise ScenarioError(f"--noise-N must be >= 0 N, got {args.noise_N:g}")
    if args.series is not None:
        from rigsim.scenarios.core.results import check_timeseries_format

        check_timeseries_format(args.series, "--series")
    if getattr(args, "view", False) and getattr(args, "rrd", None) is None:
        raise ScenarioError("--view opens the recording that --rrd FILE.rrd writes; give --rrd too")
    if getattr(args, "rrd", None) is not None:
        from rigsim.scenarios.core.outputs import check_output_file

        check_output_file(args.rrd, "--rrd", force=getattr(args, "force", False), folder=args.out)


def _truck(path) -> dict | None:
    """The [vehicle] fields of the scenario file ``path`` but its payload (the cases keep theirs), None
    without a file; every check of the file before any work (ScenarioError, one sentence)."""
    if path is None:
        return None
    import dataclasses

    from rigsim.scenarios.core.config import load_scenario

    vehicle = load_scenario(path).vehicle
    fields = {f.name: getattr(vehicle, f.name) for f in dataclasses.fields(vehicle)}
    return {k: v for k, v in fields.items() if v is not None and k != "payload_kg"}


def cmd_paper(args) -> int:
    import gc

    # The imports make ~180 000 objects that live as long as the process. The collector is off
    # while they are made (its full passes over them, ~0.06 s each, would find nothing), and they
    # are then frozen out of its reach before the pool forks: no full collection, here or in a
    # worker, traverses them again (~0.1 s per case's figures otherwise).
    gc.disable()
    try:
        # matplotlib too: every worker draws figures; imported once here, it is shared by the
        # forked workers instead of imported by each of them.
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot  # noqa: F401

        from rigsim.scenarios.core.config import load_scenario, paper_scenarios
        from rigsim.scenarios.core.files import to_json
        from rigsim.scenarios.core.outputs import staged_output
        from rigsim.scenarios.studies.paper.compute import case_scenario, run_paper
        from rigsim.scenarios.studies.paper.report import case_figure_jobs, render_report, write_case_run, write_files
        from rigsim.scenarios.studies.scoring import NOISE_N
    finally:
        gc.freeze()
        gc.enable()

    paths = paper_scenarios(args.rig)
    truck = _truck(getattr(args, "truck", None))
    for p in paths:  # validate everything before anything runs
        case_scenario(p, None, truck)
    _check(args)
    pose_rate = None
    if args.rrd:
        from rigsim.scenarios.core.poses import DEFAULT_POSE_RATE_HZ

        pose_rate = DEFAULT_POSE_RATE_HZ
    n_jobs, done = 2 * len(paths), [0]

    def progress(r) -> None:
        done[0] += 1
        if not args.quiet:
            print(f"[{done[0]}/{n_jobs}] {r.scenario_name} {r.mode}: DLC {r.summary()['dlc_mean']:.4f} "
                  f"({r.info['wall_time_s']:.1f} s)", file=sys.stderr)

    noise_N = NOISE_N if args.noise_N is None else args.noise_N
    inputs = [*paths, *([args.truck] if truck else [])]
    with staged_output(args.out, force=getattr(args, "force", False), inputs=inputs) as stage:
        rendered = {}

        def report(result) -> None:
            tables = (result.table(), result.damage_table(), result.model_table())
            rendered.update(result=result, tables=tables, files=render_report(result, case_files=False, tables=tables))

        # Each run's files are written by the worker that ran it, each figure of a case by the next
        # free worker once the case is scored, while the other runs go on; the report as soon as
        # every case is scored, while the last figures are drawn (with --model: after it).
        model = getattr(args, "model", False)
        result = run_paper(paths, workers=args.jobs, duration_s=args.duration_s, noise_N=noise_N,
                           pose_rate_hz=pose_rate, on_done=progress,
                           case_jobs=functools.partial(case_figure_jobs, out=stage.path),
                           finish_run=functools.partial(write_case_run, out=stage.path, series=args.series),
                           on_scored=None if model else report,
                           configuration=args.rig, truck=truck)
        if model:
            import dataclasses

            from rigsim.scenarios.studies.paper.model import model_scores

            say = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
            result = dataclasses.replace(result, models=model_scores(result, workers=args.jobs, progress=say))
        if rendered.get("result") is not result:
            report(result)
        table, damage_table, model_table = rendered["tables"]
        files = dict(rendered["files"])
        files["paper.json"] = to_json(result).encode("utf-8")
        write_files(stage.path, files)
        n_fig = sum(1 for f in stage.path.glob("*.png"))
        if args.rrd:
            from rigsim.scenarios.review.recording import write_recording

            runs = [r for c in result.cases for r in (c.road, c.rig)]
            write_recording(stage.place(args.rrd), runs,
                            corrected={c.name: c.score.corrected_N["best"] for c in result.cases},
                            dlc_table=table + "\n\n" + damage_table)
    out = pathlib.Path(args.out)
    if args.rrd:
        print(f"wrote recording {args.rrd} (one recording per case)" + (" and opened the viewer" if args.view else ""))
        if args.view:
            from rigsim.scenarios.review.recording import open_viewer

            open_viewer(args.rrd)
    print(table)
    print()
    print(damage_table)
    if model_table is not None:
        print()
        print(model_table)
    series = "" if args.series is None else f" with its timeseries.{args.series}"
    print(f"wrote {out / 'paper.json'}, {out / 'report.md'}, {n_fig} figures and one folder per case and mode"
          f"{series}")
    return 0
