"""``rigsim validate`` on the command line: the argparse adapter of :func:`compute.validate`.

Arguments are checked before any work (a bad duration, ``--jobs`` below 1 or an ``--out`` that
is a file: one sentence, nothing written); then the validation runs, the folder is written
(:func:`scenarios.studies.validate.report.write_report`) and the key numbers are printed.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

__all__ = ["add_parser", "cmd_validate"]


def __getattr__(name: str):
    # The computation is imported when first used, not with the parser (``rigsim --help`` stays
    # light); ``command.validate`` and ``command.check_arguments`` still name it (tests wrap it).
    if name in ("check_arguments", "validate"):
        from scenarios.studies.validate import compute

        return getattr(compute, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``validate`` on an ``argparse`` sub-parser collection; sets ``func=cmd_validate``."""
    p = subparsers.add_parser(
        "validate", help="validate the linearized actuator model (eq. 4) against the multibody plant")
    p.add_argument("--out", "-o", required=True, help="output folder (validate.json, report.md, PNGs)")
    p.add_argument("--duration-s", type=float, default=None,
                   help="analysed duration of the Table 1 runs in s (default: the scenario's 60 s)")
    p.add_argument("--ident-duration-s", type=float, default=None,
                   help="identification record in s (default: twice --duration-s, at least 10 s)")
    p.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores, at most 8)")
    p.add_argument("--rrd", default=None, help="also write a rerun recording of the Table 1 road and rig runs")
    p.add_argument("--view", action="store_true", help="with --rrd: open the recording in the rerun viewer")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.set_defaults(func=cmd_validate)
    return p


def cmd_validate(args) -> int:
    """Run :func:`validate`, write the report into ``args.out``, print the key numbers; returns 0.

    Raises
    ------
    ScenarioError
        Bad arguments, before any work.
    """
    from scenarios.core.config import ScenarioError
    from scenarios.studies.validate.report import summary_lines, write_report

    this = sys.modules[__name__]  # check_arguments and validate through __getattr__ (or a test's wrapper)
    duration_s = getattr(args, "duration_s", None)
    ident_s = getattr(args, "ident_duration_s", None)
    jobs = getattr(args, "jobs", None)
    this.check_arguments(duration_s, ident_s, jobs)
    out = pathlib.Path(args.out)
    if out.exists() and not out.is_dir():
        raise ScenarioError(f"--out {out} exists and is not a folder; give a folder (new or existing)")
    quiet = getattr(args, "quiet", False)
    progress = None if quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    rrd = getattr(args, "rrd", None)
    pose_rate = None
    if rrd:
        from scenarios.core.poses import DEFAULT_POSE_RATE_HZ

        pose_rate = DEFAULT_POSE_RATE_HZ
    result = this.validate(duration_s=duration_s, ident_duration_s=ident_s, jobs=jobs, progress=progress,
                      pose_rate_hz=pose_rate)
    paths = write_report(result, out)
    lines = summary_lines(result)
    if rrd:
        from scenarios.review.recording import write_recording

        runs = [result.runs[k] for k in ("road", "rig") if k in result.runs]
        write_recording(rrd, runs, dlc_table="\n".join(lines), spawn=getattr(args, "view", False))
        print(f"wrote recording {rrd} (Table 1 road and rig runs)")
    for line in lines:
        print(line)
    print(f"wrote {paths['validate.json']}, {paths['report.md']} and {len(paths) - 2} PNGs")
    return 0
