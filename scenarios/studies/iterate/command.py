"""``rigsim iterate``: the command-line adapter of the drive-file iteration (arguments, progress, files).

::

    rigsim iterate SCENARIO.toml --target displacement|force --out DIR [--gain G]
                   [--max-iterations K] [--tolerance TOL] [--band-hz LO HI] [--duration-s S]

The computation is :func:`rigsim.scenarios.studies.iterate.compute.iterate_scenario`, the files
(``DIR/drive.csv``, the same drive as the RPC III drive file ``DIR/drive.drv`` a lab can play on
a real rig, ``DIR/iteration.json``, ``DIR/iteration.png``, appearing together:
:func:`rigsim.scenarios.core.outputs.staged_output`) and the table :mod:`rigsim.scenarios.studies.iterate.report`.
Bad options, a bad scenario and an ``--out`` holding a previous result (without ``--force``) raise
:class:`rigsim.scenarios.core.config.ScenarioError` before any run.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

from rigsim.scenarios.core.flags import add_command, add_duration, add_force, add_noise, add_out, add_quiet

__all__ = ["add_parser", "cmd_iterate"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``iterate`` on an ``argparse`` sub-parsers object; sets ``func=cmd_iterate``."""
    # The targets are rigsim.scenarios.studies.iterate.compute.TARGETS and the noise default
    # rigsim.scenarios.studies.scoring.NOISE_N: importing those here would load the whole simulator for
    # ``rigsim --help`` (tests/scenarios/cli/test_startup.py pins both). The band limit's module is light.
    from rigsim.correction.output.lowpass import BAND_HZ

    c = add_command(subparsers, "iterate",
                    "iterate the rig's drive file until the pans (or tire forces) match the road test",
                    "Input correction on the simulated rig: identify the rig's FRF matrix, then iterate "
                    "d_{k+1} = d_k + g H^-1 (target - response_k); compare with the output correction.")
    c.add_argument("scenario", help="scenario TOML file")
    c.add_argument("--target", choices=("displacement", "force"), required=True,
                   help="displacement: pan displacement = road profile (Moran); force: tire force = the road "
                        "run's tire force (RPC-style remote target)")
    add_out(c, holds="drive.csv, drive.drv (RPC III drive file), iteration.json, iteration.png")
    c.add_argument("--gain", type=float, default=0.8, help="relaxation gain g (default 0.8; stable below ~2)")
    c.add_argument("--max-iterations", type=int, default=6, help="most drive updates (default 6)")
    c.add_argument("--tolerance", type=float, default=0.01, help="stop at this mean NRMSE (default 0.01)")
    c.add_argument("--band-hz", type=float, nargs=2, default=(0.3, BAND_HZ), metavar=("LO", "HI"),
                   help=f"frequency band of the update, Hz (default 0.3 {BAND_HZ:g})")
    c.add_argument("--coherence-min", type=float, default=0.8,
                   help="no update where the identification's coherence is below this (default 0.8)")
    add_duration(c, "the analysed record", "the scenario's duration_s")
    add_noise(c)
    c.add_argument("--run-anyway", action="store_true",
                   help="run even if the gain's predicted spectral radius is >= 1 (divergence still stops it)")
    add_force(c)
    add_quiet(c)
    c.set_defaults(func=cmd_iterate)
    return c


def _options(args) -> dict:
    return dict(gain=args.gain, max_iterations=args.max_iterations, tolerance=args.tolerance,
                band_hz=tuple(args.band_hz), coherence_min=args.coherence_min, noise_N=args.noise_N,
                run_anyway=args.run_anyway)


def cmd_iterate(args) -> int:
    """Run ``rigsim iterate``: check everything, run, write the files, print the comparison."""
    from rigsim.scenarios.core.config import load_scenario
    from rigsim.scenarios.core.outputs import staged_output
    from rigsim.scenarios.studies.iterate.compute import check_options, iterate_scenario
    from rigsim.scenarios.studies.iterate.report import comparison_table, write_files

    check_options(args.target, duration_s=args.duration_s, **_options(args))
    scenario = load_scenario(args.scenario)
    if args.duration_s is not None:
        scenario = dataclasses.replace(scenario, duration_s=float(args.duration_s))
    check_options(args.target, duration_s=scenario.duration_s, **_options(args))  # the file's duration too
    say = None if args.quiet else (lambda s: print(s, file=sys.stderr, flush=True))
    with staged_output(args.out, force=getattr(args, "force", False), inputs=scenario.input_files) as stage:
        result = iterate_scenario(scenario, args.target, say=say, **_options(args))
        paths = {k: stage.final(p) for k, p in write_files(result, stage.path).items()}
    print(comparison_table(result))
    print(f"wrote {', '.join(str(p) for p in paths.values())}")
    return 0
