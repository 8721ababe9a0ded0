"""``rigsim correct``: output correction of wheel forces measured on a real rig.

::

    rigsim correct IN (--actuator ACT.toml | --actuators ACTS.toml [--map fl=CH,...]
                   | --identify DRIVE,LVDT) -o OUT [--force] [--time-col NAME]
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
gives) or ``--identify`` (one drive and pan displacement (LVDT) channel of the same file, fitted by
:func:`correction.identification.actuator_fit.fit_actuator`; ``--model``'s ``--pairs`` names one
such pair per corner). The one correction is
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

``--help`` shows one line per option, in groups (input, channels, linear correction, model
correction, output); each option in full is on the guide's page, ``docs/guide/correct.md``.

This module parses and prints: the work is the records API's (:mod:`scenarios.records.api`; the
settings checked by :func:`scenarios.records.settings.correction_settings`, the file read and
the correction planned by their ``read``, then ``check_output``, ``run`` and the result's
``write``), whose messages name the command's flags (:data:`CLI_NAMING`).
"""

from __future__ import annotations

import argparse

from scenarios.core.flags import (add_channel_timing, add_command, add_force, add_number_format, add_out, add_quiet,
                                  add_time_col)
from scenarios.records.naming import Naming
from scenarios.records.output import claimed_out_file
from scenarios.studies.identify.command import channel_timing

__all__ = ["CLI_NAMING", "USAGE", "add_parser", "cmd_correct"]

#: The records API's keywords as ``rigsim correct`` names them.
CLI_NAMING = Naming({"actuator": "--actuator", "actuators": "--actuators", "identify": "--identify",
                     "columns": "--columns", "corner_map": "--map", "lowpass": "--lowpass",
                     "lowpass_hz": "--lowpass-hz", "mode": "--mode", "transient": "--transient",
                     "normalize_dc": "--normalize-dc", "model": "--model", "pairs": "--pairs", "workers": "--jobs",
                     "max_evaluations": "--max-evaluations", "calibration_windows": "--calibration-windows",
                     "cab": "--cab", "drift_cut_hz": "--drift-cut-hz", "path": "-o", "force_filter": "--force-filter",
                     "lvdt_filter": "--lvdt-filter"})


#: ``rigsim correct``'s usage line: the four ways to get T_a (or the model), then the rest.
USAGE = ("%(prog)s IN -o OUT (--actuators ACTS.toml | --actuator ACT.toml\n"
         "       | --identify DRIVE,LVDT | --model TRUCK.toml --pairs fl=DRIVE:LVDT,...)\n"
         "       [options]")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``correct`` on an ``argparse`` sub-parsers object; sets ``func=cmd_correct``. One line
    per option; the details are on the guide's page (``docs/guide/correct.md``)."""
    from correction.output.lowpass import BAND_HZ
    from scenarios.cli.correct_model import add_model_arguments

    c = add_command(subparsers, "correct",
                    "correct wheel forces measured on a rig (CSV, RPC III, MDF4, TDMS) for the actuator dynamics",
                    "Writes them, in N, to OUT. Each option in full is on docs/guide/correct.md.", usage=USAGE)
    g = c.add_argument_group("input")
    g.add_argument("input", metavar="IN", help="the record: CSV, RPC III, MDF4 or TDMS")
    add_time_col(g)
    add_number_format(g)
    g = c.add_argument_group("channels")
    g.add_argument("--columns", metavar="CH,...", help="force channels to correct (default: all)")
    g.add_argument("--map", metavar="CORNER=CH,...", help="each corner's force channel, e.g. fl=Fz_FL")
    add_channel_timing(g)
    g = c.add_argument_group("linear correction: T_a^-1 T_F, T_a from one of")
    g.add_argument("--actuators", metavar="ACTS.toml", help="one T_a per corner (rigsim identify's file)")
    g.add_argument("--actuator", metavar="ACT.toml", help="one T_a for every force channel")
    g.add_argument("--identify", metavar="DRIVE,LVDT", help="one T_a fitted on IN's DRIVE,LVDT pair")
    g.add_argument("--lowpass", choices=("paper", "regularized"), default="regularized", metavar="KIND",
                   help="T_F: regularized (default) or paper (eq. 5)")
    g.add_argument("--lowpass-hz", type=float, default=None, metavar="HZ",
                   help=f"regularized T_F's -3 dB corner (default {BAND_HZ:g})")
    g.add_argument("--mode", choices=("causal", "zerophase"), default="zerophase", metavar="MODE",
                   help="zerophase (default, offline) or causal")
    g.add_argument("--normalize-dc", action="store_true", help="scale T_a to T_a(0) = 1 instead of refusing it")
    add_model_arguments(c.add_argument_group("model correction: a truck model calibrated on IN"))
    g = c.add_argument_group("output")
    add_out(g, "file", "its extension's format")
    g.add_argument("--transient", choices=("drop", "mark", "keep"), default="drop", metavar="WHAT",
                   help="filter transients: drop (default), mark or keep")
    add_force(g)
    add_quiet(g)
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
