"""``rigsim sweep``: a grid of scenarios, each run on the road and on the rig and scored, on all
cores or on a Dask cluster, with nothing lost.

::

    rigsim sweep GRID.toml --out DIR [--scheduler tcp://HOST:PORT] [--jobs N] [--no-resume]

The package: :mod:`~rigsim.scenarios.studies.sweep.grid` (the grid file), :mod:`~rigsim.scenarios.studies.sweep.axes`
(its axes and the cap on cases) and :mod:`~rigsim.scenarios.studies.sweep.settings` (its evaluation keys),
:mod:`~rigsim.scenarios.studies.sweep.case` (one case: road and rig runs scored by
:func:`rigsim.scenarios.studies.scoring.score_pair`, by default with the paper study's ``best`` method
and noise), :mod:`~rigsim.scenarios.studies.sweep.executors` (local process pool or Dask) and
:mod:`~rigsim.scenarios.studies.sweep.scheduler` (``--scheduler`` checked and reached within deadlines),
:mod:`~rigsim.scenarios.studies.sweep.store` (case files, ``results.csv``, ``sweep.json``),
:mod:`~rigsim.scenarios.studies.sweep.run` (running and resuming), :mod:`~rigsim.scenarios.studies.sweep.plot`
(``summary.png``). This module is the argparse adapter.

Outputs in ``DIR``: ``cases/<case_id>.json`` (one per finished case, written as it finishes),
``results.csv`` (one row per finished case, sorted by case id), ``summary.png`` (DLC against
speed per roughness and payload, correction error against each swept key), ``sweep.json``.
Resume is the default; Ctrl-C keeps every finished case, and the same command resumes.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

from rigsim.scenarios.core.flags import add_command, add_jobs, add_out, add_quiet

__all__ = ["add_parser", "cmd_sweep"]


def cmd_sweep(args) -> int:
    """``rigsim sweep``: validate the options and the grid, run it, print where the results are."""
    from rigsim.scenarios.studies.sweep.executors import checked_where, executor_for
    from rigsim.scenarios.studies.sweep.grid import load_grid
    from rigsim.scenarios.studies.sweep.run import SUMMARY_FILE, SweepOutcome, run_sweep
    from rigsim.scenarios.studies.sweep.store import CASES_DIR

    scheduler = checked_where(args.scheduler, args.workers)  # before the grid is read
    from rigsim.scenarios.core.outputs import claim_output_folder

    # a new, empty or earlier sweep's folder is resumed into; anything else is refused now
    claim_output_folder(args.out, written_by="rigsim sweep", inputs=(args.grid,))
    grid = load_grid(args.grid)  # every case validated before anything starts
    out = pathlib.Path(args.out)
    quiet = getattr(args, "quiet", False)
    executor_cm, label = executor_for(scheduler, args.workers, len(grid.cases))
    if not quiet:
        print(f"sweep {grid.name}: {len(grid.cases)} cases on {label}, scored by {grid.settings.method.name} "
              f"({grid.settings.method.description}; noise {grid.settings.noise_N:g} N rms)", file=sys.stderr)
    try:
        with executor_cm as executor:
            claim_output_folder(args.out, written_by="rigsim sweep", inputs=(args.grid,), create=True)
            outcome = run_sweep(grid, out, executor, resume=not args.no_resume, progress=not quiet,
                                executor_label=label)
    except KeyboardInterrupt as exc:
        o = exc.args[0] if exc.args and isinstance(exc.args[0], SweepOutcome) else None
        if o is not None:
            print(f"rigsim: sweep interrupted: {o.skipped + o.ok + o.failed} of {o.total} cases finished and kept "
                  f"in {out / CASES_DIR}, {o.results} written; run the same command to resume", file=sys.stderr)
        raise
    done = outcome.skipped + outcome.ok + outcome.failed
    print(f"{done} of {outcome.total} cases finished ({outcome.skipped} from an earlier run, {outcome.ok} ok and "
          f"{outcome.failed} failed now, {outcome.wall_time_s:.1f} s, {outcome.cases_per_min:.2f} cases/min); "
          f"wrote {outcome.results}, {out / SUMMARY_FILE} and {out / CASES_DIR}/")
    return 0


def add_parser(subparsers) -> None:
    """Register ``rigsim sweep`` on an argparse sub-parsers object (``func=cmd_sweep``)."""
    sp = add_command(subparsers, "sweep", "run a grid of scenarios (road, rig, corrected) on all cores or a Dask cluster",
                     "Runs every case of a grid file in road and rig mode, corrects the rig forces, and collects "
                     "one row per case in OUT/results.csv (resumable; one file per case in OUT/cases).")
    sp.add_argument("grid", metavar="GRID.toml", help="grid file: a base scenario plus axes and/or [[cases]]")
    add_out(sp, holds="results.csv, summary.png, sweep.json, cases/")
    sp.add_argument("--scheduler", metavar="tcp://HOST:PORT", default=None,
                    help="run on an existing Dask distributed cluster (workers started with --nthreads 1)")
    add_jobs(sp, dest="workers")
    sp.add_argument("--workers", dest="workers", type=int, default=None, help=argparse.SUPPRESS)
    sp.add_argument("--no-resume", action="store_true", help="run every case again, even those already finished")
    add_quiet(sp)
    sp.set_defaults(func=cmd_sweep)
