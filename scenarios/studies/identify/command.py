"""``rigsim identify``: characterize the rig's actuators before a test (the command-line adapter).

On the simulated rig (``rigsim identify SCENARIO.toml --out DIR``) or from a recorded file of
drive and LVDT channels of a real rig (``rigsim identify --from-file REC --pairs
fl=DRIVE:LVDT,... [--time-col NAME] --out DIR``; REC in any format that
:func:`rigsim.correction.io.measured.read_channels` reads, lengths converted to m). Writes
``DIR/actuators.toml`` (one T_a per corner, the file ``rigsim correct --actuators`` reads),
``DIR/identification.json`` (fit diagnostics) and ``DIR/bode.png`` (data against fit).
"""

from __future__ import annotations

import math
import pathlib
import sys

from rigsim.scenarios.core.flags import (add_channel_timing, add_command, add_duration, add_force, add_number_format,
                                         add_out, add_pairs, add_quiet, add_time_col)

__all__ = ["channel_timing", "add_parser", "cmd_identify"]


def channel_timing(args, what: str):
    """The :class:`~rigsim.correction.io.acquisition.ChannelFilter` of ``--{what}-filter`` and ``--{what}-delay``
    (None when neither is given); one ScenarioError sentence naming the option otherwise."""
    from rigsim.scenarios.records.timing import channel_filter

    return channel_filter(getattr(args, f"{what}_filter", None), getattr(args, f"{what}_delay", None),
                          option=f"--{what}-filter", delay_option=f"--{what}-delay")


def add_parser(subparsers) -> None:
    """Register ``rigsim identify``."""
    p = add_command(
        subparsers, "identify", "identify T_a per corner: random drives on the simulated rig, or a recorded file",
        "Writes actuators.toml (the file rigsim correct --actuators reads), identification.json and bode.png.")
    p.add_argument("scenario", nargs="?", help="scenario TOML file (the truck on the simulated rig)")
    add_out(p, holds="actuators.toml, identification.json, bode.png")
    add_duration(p, "the identification record", "the scenario's duration_s, at least 60 s")
    p.add_argument("--seed", type=int, default=None, help="seed of the random drives (default: the project's)")
    add_force(p)
    add_quiet(p)
    g = p.add_argument_group("a recorded file of a real rig")
    g.add_argument("--from-file", default=None, metavar="REC",
                   help="identify from this file instead (CSV, RPC III, MDF4 or TDMS; needs --pairs)")
    add_pairs(g)
    add_time_col(g)
    add_number_format(g)
    add_channel_timing(g, force=False)
    p.set_defaults(func=cmd_identify)


def _check(args):
    from rigsim.scenarios.core.config import ScenarioError

    if (getattr(args, "decimal", None) or getattr(args, "thousands", None)) and args.from_file is None:
        raise ScenarioError("--decimal and --thousands go with --from-file; a simulated identification reads no "
                            "text")
    if (args.scenario is None) == (args.from_file is None):
        raise ScenarioError("give either a SCENARIO.toml (the simulated rig) or --from-file REC.csv, exactly one")
    if args.from_file is not None and not args.pairs:
        raise ScenarioError("--from-file needs --pairs fl=DRIVE:LVDT,... naming each corner's drive and LVDT columns")
    if args.pairs and args.from_file is None:
        raise ScenarioError("--pairs goes with --from-file; a simulated identification knows its channels")
    if args.time_col is not None and args.from_file is None:
        raise ScenarioError("--time-col goes with --from-file; a simulated identification knows its time")
    if (args.lvdt_filter is not None or args.lvdt_delay is not None) and args.from_file is None:
        raise ScenarioError("--lvdt-filter and --lvdt-delay go with --from-file; a simulated identification "
                            "measures its LVDTs as the scenario's [lab] says")
    if args.seed is not None and args.seed < 0:  # numpy's generators take seeds >= 0 only
        raise ScenarioError(f"--seed must be a whole number >= 0, got {args.seed}")
    d = args.duration_s
    if d is not None and not (math.isfinite(d) and 10.0 <= d <= 3600.0):
        raise ScenarioError(f"--duration-s must lie in [10, 3600] s, got {d:g}")


def cmd_identify(args) -> int:
    from rigsim.correction.io.actuator_file import write_actuators_file
    from rigsim.scenarios.core.config import ScenarioError, load_scenario
    from rigsim.scenarios.core.drive import IDENT_SEED
    from rigsim.scenarios.core.files import atomic_write_bytes, to_json
    from rigsim.scenarios.core.outputs import staged_output
    from rigsim.scenarios.records.naming import Naming
    from rigsim.scenarios.studies.identify.report import bode_png

    _check(args)
    seed = IDENT_SEED if args.seed is None else int(args.seed)
    scenario = load_scenario(args.scenario) if args.scenario is not None else None
    naming = Naming({"pairs": "--pairs", "lvdt_filter": "--lvdt-filter"})
    lvdt_filter = None
    if args.from_file is not None:
        from rigsim.scenarios.records.recorded import parse_pairs

        parse_pairs(args.pairs, naming)  # the syntax of --pairs before anything is written
        lvdt_filter = channel_timing(args, "lvdt")
    inputs = (args.from_file, *(scenario.input_files if scenario is not None else ()))
    with staged_output(args.out, force=getattr(args, "force", False), inputs=inputs) as stage:
        if args.from_file is not None:
            from rigsim.scenarios.records import recorded

            ident = recorded.identify_recorded(args.from_file, args.pairs, time_col=args.time_col,
                                               decimal=getattr(args, "decimal", None),
                                               thousands=getattr(args, "thousands", None), naming=naming,
                                               lvdt_filter=lvdt_filter)
            title = pathlib.Path(args.from_file).name
        else:
            from rigsim.correction.identification.actuator_fit import ActuatorFitError
            from rigsim.scenarios.studies.identify.compute import identify_rig

            if not args.quiet:
                print(f"identifying {scenario.name}: independent random drives on the four posts", file=sys.stderr,
                      flush=True)
            try:
                ident = identify_rig(scenario, duration_s=args.duration_s, seed=seed)
            except ActuatorFitError as exc:
                raise ScenarioError(str(exc)) from None
            title = scenario.name
        files = {"identification.json": to_json(ident).encode("utf-8"), "bode.png": bode_png(ident.fits, title)}
        write_actuators_file(stage.path / "actuators.toml", ident.fits, meta=ident.meta())
        for name, data in files.items():
            atomic_write_bytes(stage.path / name, data)
    out = pathlib.Path(args.out)
    print(f"{'corner':>6} {'orders':>7} {'bandwidth Hz':>13} {'held-out err':>13}")
    for c, fit in ident.fits.items():
        print(f"{c:>6} {fit.orders[0]:>3}/{fit.orders[1]:<3} {fit.bandwidth_hz:13.2f} {fit.held_out_error:13.4f}")
    print(f"wrote {out / 'actuators.toml'}, {out / 'identification.json'} and {out / 'bode.png'}")
    return 0
