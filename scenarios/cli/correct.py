"""``rigsim correct``: output correction of wheel forces measured on a real rig.

::

    rigsim correct IN (--actuator ACT.toml | --actuators ACTS.toml [--map fl=CH,...]
                   | --identify DRIVE_CH,DISP_CH) -o OUT [--force] [--time-col NAME]
                   [--lowpass paper|regularized] [--lowpass-hz HZ] [--mode causal|zerophase]
                   [--columns A,B] [--transient drop|mark|keep] [--quiet]
                   [--decimal .|,] [--thousands none|,|.|'|space]
    rigsim correct IN --model TRUCK.toml --pairs fl=DRIVE:LVDT,... -o OUT [--map fl=CH,...] ...

``IN`` is read by :func:`correction.io.measured.read_channels` (any CSV dialect, RPC III, MDF4, TDMS),
its channels named as the reader returns them (``Fz_FL`` for a header ``Fz_FL [kN]``) and in SI,
so a force in kN is corrected in N; ``--decimal`` and ``--thousands`` say how a text file writes
its numbers when they leave it ambiguous. Without ``--columns``/``--map`` every numeric channel
is read and the force channels (unit N, kN... or none) are the candidates; with them only the
named channels are read. A chosen channel that is not a force is refused. ``T_a`` comes from
``--actuator`` (one actuator file, :mod:`correction.io.actuator_file`, for every channel),
``--actuators`` (one ``T_a`` per corner; a corner corrects the channel whose name holds the
corner as a token, ``tire_force_fl_N`` or ``Fz_FL``, case-insensitive, or the one ``--map``
gives) or ``--identify`` (the drive and pan displacement channels of the same file, fitted by
:func:`correction.identification.actuator_fit.fit_actuator`). The one correction is
:func:`correction.output.pipeline.correct_forces`.

``OUT`` is written by :func:`correction.io.measured.write_channels` in its extension's format: the
time (s) and ``<channel>_corrected`` in N (and ``settled``, 0/1, with ``--transient mark``;
``drop``, the default, leaves out the correction's transients, ``keep`` keeps them), with
metadata on how it was made (input, T_a source, low-pass, mode, settling tolerance, rigsim
version). The per-channel DLC, stress factor and damage-equivalent load before and after
correction are printed. Bad input raises :class:`scenarios.core.config.ScenarioError` (one
sentence naming the channel or line and the fix) and nothing is written; ``-o`` naming an input,
or an existing file without ``--force``, is refused before any work, and so is an ``-o`` another
command is writing (the file is claimed for the command's run:
:func:`scenarios.records.output.claimed_out_file`).

``--model TRUCK.toml --pairs fl=DRIVE:LVDT,...`` corrects instead by a truck model calibrated on
the file's own drive, LVDT and force channels (:mod:`scenarios.cli.correct_model`).

This module parses and prints: the work is the records API's (:mod:`scenarios.records.api`; the
settings checked by :func:`scenarios.records.settings.correction_settings`, the file read and
the correction planned by their ``read``, then ``check_output``, ``run`` and the result's
``write``), whose messages name the command's flags (:data:`CLI_NAMING`).
"""

from __future__ import annotations

import argparse

from scenarios.records.naming import Naming
from scenarios.records.output import claimed_out_file
from scenarios.studies.identify.command import add_channel_timing, add_number_format, channel_timing

__all__ = ["CLI_NAMING", "add_parser", "cmd_correct"]

#: The records API's keywords as ``rigsim correct`` names them.
CLI_NAMING = Naming({"actuator": "--actuator", "actuators": "--actuators", "identify": "--identify",
                     "columns": "--columns", "corner_map": "--map", "lowpass": "--lowpass",
                     "lowpass_hz": "--lowpass-hz", "mode": "--mode", "transient": "--transient",
                     "normalize_dc": "--normalize-dc", "model": "--model", "pairs": "--pairs", "workers": "--jobs",
                     "max_evaluations": "--max-evaluations", "calibration_windows": "--calibration-windows",
                     "cab": "--cab", "drift_cut_hz": "--drift-cut-hz", "path": "-o", "force_filter": "--force-filter",
                     "lvdt_filter": "--lvdt-filter"})


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``correct`` on an ``argparse`` sub-parsers object; sets ``func=cmd_correct``."""
    from correction.output.lowpass import BAND_HZ, BAND_ORDER
    from scenarios.cli.correct_model import add_model_arguments

    c = subparsers.add_parser(
        "correct", help="correct wheel forces measured on a rig (CSV, RPC III, MDF4, TDMS) for the actuator dynamics",
        description="Filter measured wheel forces by the inverse actuator transfer function times a "
                    "low-pass (the paper's output correction) and write them, in N, to a new file; with --model, "
                    "correct them by a truck model calibrated on the same file instead.")
    c.add_argument("input", metavar="IN", help="measured file (.csv/.txt/.dat in any dialect, RPC III .rsp/.drv/.tim, "
                   ".mf4, .tdms) on a uniform time axis; units converted to SI (kN -> N, mm -> m)")
    c.add_argument("--time-col", metavar="NAME", help="the time column (default: the one named time, t, zeit...)")
    add_number_format(c)
    c.add_argument("--actuator", metavar="ACT.toml",
                   help="actuator file for every channel: [transfer_function] num, den (descending powers of s) "
                        "or [parameters] (eq. 4)")
    c.add_argument("--actuators", metavar="ACTS.toml",
                   help="per-corner actuator file: one table per corner ([fl], [fr], ...) with num, den; each "
                        "corner corrects the force channel whose name holds the corner as a token (or see --map)")
    c.add_argument("--map", metavar="CORNER=CH[,...]",
                   help="with --actuators or --model: the channel (name without [unit]) of each corner, e.g. "
                        "fl=Fz_FL,fr=Fz_FR")
    c.add_argument("-o", "--out", required=True, metavar="OUT",
                   help="output file (.csv, .rsp RPC III, .mf4, .tdms) with <channel>_corrected in N")
    c.add_argument("--force", action="store_true", help="replace OUT if it exists (never an input file)")
    c.add_argument("--lowpass", choices=("paper", "regularized"), default="regularized",
                   help="paper: eq. 5 (2 x 2nd order, 16/24 Hz, zeta 1; already -3 dB near 8 Hz); "
                        f"regularized: Butterworth of order {BAND_ORDER} at --lowpass-hz, inverse ~exact to "
                        "two thirds of it (default)")
    c.add_argument("--lowpass-hz", type=float, default=None, metavar="HZ",
                   help=f"with --lowpass regularized: the Butterworth's corner (-3 dB), Hz, below half the "
                        f"sampling rate (default {BAND_HZ:g})")
    c.add_argument("--mode", choices=("causal", "zerophase"), default="zerophase",
                   help="zerophase: |T_a^-1 T_F| with T_a^-1's phase, offline (default); causal: as a "
                        "real-time filter (adds T_F's phase lag)")
    c.add_argument("--identify", metavar="DRIVE_CH,DISP_CH",
                   help="identify T_a from these two channels (drive and pan displacement) instead of --actuator")
    c.add_argument("--columns", metavar="CH[,CH...]",
                   help="force channels to correct (default: every force channel but the --identify ones; with "
                        "--actuators, those of the file's corners)")
    c.add_argument("--transient", choices=("drop", "mark", "keep"), default="drop",
                   help="samples inside the filters' transients: drop (default), mark ('settled' channel) or keep")
    c.add_argument("--normalize-dc", action="store_true", help="scale T_a to T_a(0) = 1 instead of refusing it")
    c.add_argument("--quiet", action="store_true",
                   help="no progress lines or notes on stderr (the result is printed)")
    add_channel_timing(c)
    add_model_arguments(c)
    c.set_defaults(func=cmd_correct)
    return c


def cmd_correct(args) -> int:
    """Run ``rigsim correct``; returns 0, raises ScenarioError (one sentence) for bad input."""
    from scenarios.cli import correct_model

    if args.model is None:
        correct_model.refuse_model_options(args)
    with claimed_out_file(args.out, [args.input, args.model, args.actuator, args.actuators], args.force):
        if args.model is not None:
            return correct_model.cmd_correct_model(args, CLI_NAMING)
        return _correct_linear(args)


def _correct_linear(args) -> int:
    """``rigsim correct`` without ``--model``, ``-o`` checked and claimed."""
    from scenarios.records.settings import correction_settings

    settings = correction_settings(
        actuator=args.actuator, actuators=args.actuators, identify=args.identify, columns=args.columns,
        corner_map=args.map, lowpass=args.lowpass, lowpass_hz=args.lowpass_hz, mode=args.mode,
        transient=args.transient, normalize_dc=args.normalize_dc, force_filter=channel_timing(args, "force"),
        lvdt_filter=channel_timing(args, "lvdt"), naming=CLI_NAMING)
    plan = settings.read(args.input, time_col=args.time_col, decimal=args.decimal, thousands=args.thousands)
    plan.check_output(args.out)
    result = plan.run()
    result.write(args.out, overwrite=args.force)
    if result.settled.any():
        print(result.table())
    print(f"corrected {len(result.channels)} channel(s) of {str(args.input)!r} at {result.fs_hz:.6g} Hz "
          f"({result.description}); {result.transient_samples} transient samples "
          f"{'dropped' if args.transient == 'drop' else 'kept'}; wrote {args.out}")
    return 0
