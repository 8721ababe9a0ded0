"""``rigsim run``: one scenario file in road or rig mode, its result folder and, with ``--rrd``, a
rerun recording (written by a child process while this one writes the rest,
:mod:`rigsim.scenarios.review.recording_process`)."""

from __future__ import annotations

import contextlib
import json
import os
import sys

from rigsim.scenarios.core.flags import add_command, add_duration, add_force, add_out, add_quiet, add_recording

__all__ = ["add_parser", "cmd_run"]


def add_parser(subparsers) -> None:
    """Register ``rigsim run`` (``func=cmd_run``)."""
    r = add_command(subparsers, "run", "run one scenario file in road or rig mode",
                    "Writes result.json (the DLC table and the run's settings) and the time series.")
    r.add_argument("scenario", help="scenario TOML file")
    r.add_argument("--mode", choices=("road", "rig"), default="road",
                   help="road: pans follow the profile exactly; rig: hydraulic actuators drive the pans")
    add_out(r, holds="result.json, timeseries.csv or --format's")
    add_duration(r, "the analysed record", "the scenario's duration_s")
    r.add_argument("--format", default="csv", choices=("csv", "mf4", "tdms", "rsp"),
                   help="time series file: csv (default), mf4 (ASAM MDF4, float64), tdms (NI) or rsp (MTS RPC III, "
                        "int16); mf4 and tdms need pip install -e \".[lab]\"")
    add_recording(r, "the run")
    add_force(r)
    add_quiet(r)
    r.set_defaults(func=cmd_run)


@contextlib.contextmanager
def _progress_bar(label: str, quiet: bool):
    """A tqdm bar on stderr (only on a terminal) fed by the runner's progress callback."""
    if quiet:
        yield None
        return
    from tqdm import tqdm

    bar = tqdm(total=100, desc=label, unit="%", leave=False, disable=None, file=sys.stderr,
               bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}")
    try:
        def update(done_s: float, total_s: float) -> None:
            bar.n = min(100.0, 100.0 * done_s / total_s)
            bar.refresh()

        yield update
    finally:
        bar.close()


def cmd_run(args) -> int:
    """Run ``rigsim run``; returns 0 (1: the recording process failed), raises ScenarioError (one
    sentence) for bad input."""
    from rigsim.scenarios.core.config import ScenarioError, load_scenario
    from rigsim.scenarios.core.memory import return_freed_arrays
    from rigsim.scenarios.core.outputs import check_output_file, claimed_output_file
    from rigsim.scenarios.core.results import check_timeseries_format

    return_freed_arrays()  # freed arrays leave the process: a long run peaks at its record plus one temporary
    check_timeseries_format(args.format)
    scenario = load_scenario(args.scenario)
    if args.duration_s is not None:
        import dataclasses
        import math

        if not (math.isfinite(args.duration_s) and 0 < args.duration_s <= 3600):
            raise ScenarioError(f"--duration-s must lie in (0, 3600] s, got {args.duration_s:g}")
        scenario = dataclasses.replace(scenario, duration_s=float(args.duration_s))
    rate = scenario.output_rate_hz
    if scenario.duration_s * rate < 1.0 - 1e-9:  # the DLC, the table's first column, needs two samples
        raise ScenarioError(f"duration_s (--duration-s) = {scenario.duration_s:g} s is shorter than one output "
                            f"sample at output_rate_hz = {rate:g} Hz; a DLC needs two, so give at least "
                            f"{1.0 / rate:g} s")
    if args.view and args.rrd is None:
        raise ScenarioError("--view opens the recording that --rrd FILE.rrd writes; give --rrd too")
    from rigsim.scenarios.core.cost import check_disk, run_cost

    cost = run_cost(args.mode, scenario.lead_in_s + scenario.duration_s,
                    int(scenario.duration_s * rate) + 1, args.format)
    check_disk(cost, args.out)
    with contextlib.ExitStack() as claims:
        if args.rrd is not None:  # checked with --out before the run: both are written, or neither
            check_output_file(args.rrd, "--rrd", force=args.force, folder=args.out)
            if os.path.exists(args.rrd) and os.path.samefile(args.rrd, args.scenario):
                raise ScenarioError(f"--rrd {args.rrd} is the scenario file; name another file for the recording")
            if os.path.relpath(os.path.abspath(args.rrd), os.path.abspath(args.out)).startswith(os.pardir):
                # outside --out (inside, it is written into the staging folder): one command writes it
                claims.enter_context(claimed_output_file(
                    args.rrd, "--rrd", force=args.force,
                    check=lambda: check_output_file(args.rrd, "--rrd", force=args.force, folder=args.out)))
        return _run_and_write(args, scenario, cost)


def _run_and_write(args, scenario, cost) -> int:
    """``rigsim run`` once its arguments are checked (and ``--rrd`` claimed): the run, its folder and recording."""
    from rigsim.scenarios.core.outputs import staged_output
    from rigsim.scenarios.core.results import write_run
    from rigsim.scenarios.review.recording_process import RecordingError, RecordingProcess

    # --rrd: a child process imports rerun and writes the recording (rigsim.scenarios.review.recording_process);
    # it starts before the simulation's imports, so that its own overlap them and the run
    recording = RecordingProcess() if args.rrd is not None else contextlib.nullcontext()
    if cost.long and not args.quiet:
        print(f"rigsim: {cost.sentence(f'a {scenario.duration_s:g} s {args.mode} run')}", file=sys.stderr,
              flush=True)
    try:
        with staged_output(args.out, force=args.force, inputs=scenario.input_files) as stage, recording as recorder:
            from rigsim.scenarios.core.poses import DEFAULT_POSE_RATE_HZ
            from rigsim.scenarios.core.run import run

            with _progress_bar(f"{scenario.name} [{args.mode}]", args.quiet) as progress:
                result = run(scenario, args.mode, progress=progress,
                             pose_rate_hz=None if recorder is None else DEFAULT_POSE_RATE_HZ)
            table = result.table()
            if recorder is not None:  # the child writes the .rrd while this process writes the rest
                recorder.submit(stage.place(args.rrd), [result], dlc_table=table)
            paths = {k: stage.final(p) for k, p in write_run(result, stage.path, fmt=args.format).items()}
            if recorder is not None:
                recorder.commit()
    except RecordingError as exc:  # not bad input nor an unwritable file: exit 1, nothing written
        print(f"rigsim: error: {exc}", file=sys.stderr)
        return 1
    if args.rrd is not None:
        print(f"wrote recording {args.rrd}" + (" and opened the viewer" if args.view else ""))
        if args.view:
            from rigsim.scenarios.review.recording import open_viewer

            open_viewer(args.rrd)
    print(table)
    if result.events:
        print("events: " + json.dumps(result.events))
    print(f"wrote {paths['result']} and {paths['timeseries']}")
    return 0
