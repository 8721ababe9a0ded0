"""``rigsim validate`` on the command line: the argparse adapter of :func:`compute.validate`.

Arguments are checked before any work (a bad duration, ``--jobs`` below 1, an ``--out`` that
is a file or holds a previous result without ``--force``, an ``--rrd`` that cannot be written: one
sentence, nothing written); then the validation runs, the folder is built beside ``--out`` and
renamed onto it (:func:`rigsim.scenarios.core.outputs.staged_output`;
:func:`rigsim.scenarios.studies.validate.report.write_report` writes its files) and the key numbers are
printed.
"""

from __future__ import annotations

import argparse
import sys

from rigsim.scenarios.core.flags import (add_command, add_duration, add_force, add_jobs, add_out, add_quiet, add_recording,
                                         add_rig)

__all__ = ["add_parser", "cmd_validate", "MIN_DURATION_S", "MIN_IDENT_DURATION_S"]

#: Shortest Table 1 record, s: two output samples at the scenario's 1 kHz (a DLC needs two;
#: a shorter one, ``--duration-s 1e-6``, would run all eleven jobs, then fail on the DLC).
MIN_DURATION_S = 1e-3
#: Shortest identification record, s: route 3's Welch segments are a quarter of the record, so
#: d s resolve 4/d Hz and give ~12.5 d points below 50 Hz for a fit of 10 coefficients (0.1 s would
#: run every job, then fail with "1 usable frequency points cannot determine 10 coefficients").
MIN_IDENT_DURATION_S = 1.0


def __getattr__(name: str):
    # The computation is imported when first used, not with the parser (``rigsim --help`` stays
    # light); ``command.validate`` and ``command.check_arguments`` still name it (tests wrap it).
    if name in ("check_arguments", "validate"):
        from rigsim.scenarios.studies.validate import compute

        return getattr(compute, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``validate`` on an ``argparse`` sub-parser collection; sets ``func=cmd_validate``."""
    p = add_command(subparsers, "validate", "validate the linearized actuator model (eq. 4) against the multibody plant",
                    "Eq. 4, the linearized plant and the FRF identified on the nonlinear rig side by side: Bode "
                    "overlays, step responses (Figure 7) and Table 1.")
    add_out(p, holds="validate.json, report.md, PNGs")
    add_duration(p, "the Table 1 runs' analysed record", "the scenario's 60 s")
    p.add_argument("--ident-duration-s", type=float, default=None, metavar="S",
                   help="identification record in s (default: twice --duration-s, at least 10 s)")
    add_jobs(p, most=8)
    add_rig(p)
    add_recording(p, "the Table 1 road and rig runs")
    add_force(p)
    add_quiet(p)
    p.set_defaults(func=cmd_validate)
    return p


def cmd_validate(args) -> int:
    """Run :func:`validate`, write the report into ``args.out``, print the key numbers; returns 0.

    Raises
    ------
    ScenarioError
        Bad arguments, before any work.
    """
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.core.outputs import check_output_file, staged_output
    from rigsim.scenarios.studies.validate.report import summary_lines, write_report

    this = sys.modules[__name__]  # check_arguments and validate through __getattr__ (or a test's wrapper)
    duration_s = getattr(args, "duration_s", None)
    ident_s = getattr(args, "ident_duration_s", None)
    jobs = getattr(args, "jobs", None)
    this.check_arguments(duration_s, ident_s, jobs)
    for option, value, least in (("--duration-s", duration_s, MIN_DURATION_S),
                                 ("--ident-duration-s", ident_s, MIN_IDENT_DURATION_S)):
        if value is not None and value < least:
            raise ScenarioError(f"{option} {value:g} s is too short for the validation's analysis; give at least "
                                f"{least:g} s")
    force, rrd, view = getattr(args, "force", False), getattr(args, "rrd", None), getattr(args, "view", False)
    if view and rrd is None:
        raise ScenarioError("--view opens the recording that --rrd FILE.rrd writes; give --rrd too")
    if rrd is not None:  # checked with --out before any work: both are written, or neither
        check_output_file(rrd, "--rrd", force=force, folder=args.out)
    quiet = getattr(args, "quiet", False)
    progress = None if quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    pose_rate = None
    if rrd is not None:
        from rigsim.scenarios.core.poses import DEFAULT_POSE_RATE_HZ

        pose_rate = DEFAULT_POSE_RATE_HZ
    with staged_output(args.out, force=force) as stage:
        result = this.validate(duration_s=duration_s, ident_duration_s=ident_s, jobs=jobs, progress=progress,
                               pose_rate_hz=pose_rate, rig=getattr(args, "rig", "design"))
        paths = {k: stage.final(p) for k, p in write_report(result, stage.path).items()}
        lines = summary_lines(result)
        if rrd is not None:
            from rigsim.scenarios.review.recording import write_recording

            runs = [result.runs[k] for k in ("road", "rig") if k in result.runs]
            write_recording(stage.place(rrd), runs, dlc_table="\n".join(lines))
    if rrd is not None:
        print(f"wrote recording {rrd} (Table 1 road and rig runs)" + (" and opened the viewer" if view else ""))
        if view:
            from rigsim.scenarios.review.recording import open_viewer

            open_viewer(rrd)
    for line in lines:
        print(line)
    print(f"wrote {paths['validate.json']}, {paths['report.md']} and {len(paths) - 2} PNGs")
    return 0
