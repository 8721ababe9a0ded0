"""``rigsim programme``: a lab's test programme corrected by the truck model, one calibration per truck.

::

    rigsim programme IN... --model TRUCK.toml --pairs fl=DRIVE:LVDT,... --out DIR [options]
    rigsim programme --programme FILE.toml --out DIR [options]

The package: :mod:`~rigsim.scenarios.studies.programme.settings` (the records and truck
configurations, from the flags or a programme file), :mod:`~rigsim.scenarios.studies.programme.run`
(each truck calibrated once, the records corrected side by side on the local pool or a Dask
cluster, resumable), :mod:`~rigsim.scenarios.studies.programme.report` (``programme.json``,
``programme.md``, ``programme.png``). This module is the argparse adapter: bad options end with
one sentence and exit code 2 before anything is written; the exit code is 1 when some records
failed (named on stderr), 0 when all were corrected.
"""

from __future__ import annotations

import pathlib
import sys

from rigsim.scenarios.core.flags import add_command, add_jobs, add_number_format, add_out, add_pairs, add_quiet, add_time_col

__all__ = ["add_parser", "cmd_programme"]

#: ``rigsim programme``'s usage: records and a truck, or a programme file.
USAGE = ("%(prog)s IN... --model TRUCK.toml --pairs fl=DRIVE:LVDT,... --out DIR [options]\n"
         "       %(prog)s --programme FILE.toml --out DIR [options]")

#: The corrected files' formats (``settings.FORMATS``, pinned by the tests; the parser imports no settings).
FORMATS = ("csv", "rsp", "mf4", "tdms")
_TRUCK_FLAGS = ("model", "pairs", "map", "columns", "time_col", "decimal", "thousands", "cab", "calibration_windows",
                "max_evaluations", "calibrate_on")


def _programme(args):
    """The :class:`~rigsim.scenarios.studies.programme.settings.Programme` the flags give."""
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.studies.programme.settings import from_flags, read_programme

    if args.programme is not None:
        given = [f"--{k.replace('_', '-')}" for k in _TRUCK_FLAGS if getattr(args, k) is not None]
        if args.inputs or given:
            what = "IN" if args.inputs else given[0]
            raise ScenarioError(f"{what} goes with the flags' one truck, not with --programme, whose file names the "
                                "records and trucks; give one of them")
        return read_programme(args.programme, args.format)
    return from_flags(args.inputs, out_format=args.format, **{k: getattr(args, k) for k in _TRUCK_FLAGS})


def cmd_programme(args) -> int:
    """``rigsim programme``: check the options, correct the records, print where the report is;
    returns 0 (all corrected) or 1 (some failed, named on stderr)."""
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.core.outputs import claim_output_folder
    from rigsim.scenarios.studies.sweep.executors import checked_where, executor_for

    scheduler = checked_where(args.scheduler, args.jobs)
    for flag, value in (("--calibration-windows", args.calibration_windows), ("--max-evaluations", args.max_evaluations),
                        ("--calibrate-on", args.calibrate_on)):
        if value is not None and value < 1:
            raise ScenarioError(f"{flag} must be a whole number >= 1, got {value}; give a positive number")
    programme = _programme(args)
    inputs = [e.path for e in programme.records] + [t.model for t in programme.trucks]
    claim_output_folder(args.out, written_by="rigsim programme", inputs=inputs)
    executor_cm, label = executor_for(scheduler, args.jobs, len(programme.records))
    if not args.quiet:
        print(f"programme: {len(programme.records)} records of {len(programme.trucks)} truck configuration(s) on "
              f"{label}", file=sys.stderr)
    from rigsim.scenarios.studies.programme.run import run_programme

    with executor_cm as executor:
        claim_output_folder(args.out, written_by="rigsim programme", inputs=inputs, create=True)
        outcome = run_programme(programme, args.out, executor, progress=not args.quiet)
    report = outcome.report
    out = pathlib.Path(args.out)
    print(f"{report.corrected} of {len(programme.records)} records corrected ({outcome.skipped} from an earlier run, "
          f"{outcome.ran} now in {outcome.wall_time_s:.1f} s); wrote {out / 'programme.md'}, "
          f"{out / 'programme.json'} and the corrected files in {out}")
    if outcome.failed:
        for r in outcome.failed:
            print(f"rigsim: record {r.name} ({r.record}) failed: {r.error}", file=sys.stderr)
        print(f"rigsim: {len(outcome.failed)} of {len(programme.records)} records failed: "
              f"{', '.join(r.name for r in outcome.failed)}; mend them and run the same command to correct them",
              file=sys.stderr)
        return 1
    return 0


def add_parser(subparsers) -> None:
    """Register ``rigsim programme`` on an argparse sub-parsers object (``func=cmd_programme``)."""
    p = add_command(subparsers, "programme", "correct a test programme's records by the truck model, one calibration "
                    "per truck, on all cores or a Dask cluster",
                    "Calibrates each truck on its first record(s), corrects every record with that calibration "
                    "(checked on each, refitted where it does not hold), and writes the corrected files, the "
                    "calibrations and a report to OUT (resumable). Each option in full is on docs/guide/programme.md.",
                    usage=USAGE)
    g = p.add_argument_group("records")
    g.add_argument("inputs", nargs="*", metavar="IN", help="record files, folders or globs")
    g.add_argument("--programme", metavar="FILE.toml", default=None,
                   help="a programme file: [[records]] path, truck; [trucks.NAME] model, pairs, options")
    add_time_col(g)
    add_number_format(g)
    g = p.add_argument_group("truck (one configuration for every IN)")
    g.add_argument("--model", metavar="TRUCK.toml", default=None, help="the truck, as rigsim correct --model")
    add_pairs(g)
    g.add_argument("--map", metavar="CORNER=CH,...", default=None, help="each corner's force channel, e.g. fl=Fz_FL")
    g.add_argument("--columns", metavar="CH,...", default=None, help="the four force channels, fl fr rl rr")
    g.add_argument("--cab", choices=("auto", "held", "fitted"), default=None, metavar="auto|held|fitted",
                   help="the cab (default auto)")
    g.add_argument("--calibration-windows", type=int, default=None, metavar="N", help="windows of the fit (default 2)")
    g.add_argument("--max-evaluations", type=int, default=None, metavar="N", help="most evaluations of the fit (default 60)")
    g.add_argument("--calibrate-on", type=int, default=None, metavar="N",
                   help="fit windows of the truck's first N records (default 3)")
    g = p.add_argument_group("where")
    add_jobs(g)
    g.add_argument("--scheduler", metavar="tcp://HOST:PORT", default=None,
                   help="a Dask cluster instead (workers with --nthreads 1, sharing the files' paths)")
    g = p.add_argument_group("output")
    add_out(g, holds="NAME_corrected.EXT, TRUCK.calibration.json, programme.md, programme.json, records/")
    g.add_argument("--format", choices=FORMATS, default=None, metavar="|".join(FORMATS),
                   help="the corrected files' format (default: each record's own)")
    add_quiet(g)
    p.set_defaults(func=cmd_programme)
