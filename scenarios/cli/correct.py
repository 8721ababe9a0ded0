"""``rigsim correct``: output correction of wheel forces measured on a real rig.

::

    rigsim correct IN (--actuator ACT.toml | --actuators ACTS.toml [--map fl=CH,...]
                   | --identify DRIVE,LVDT) -o OUT [--force] [--time-col NAME]
                   [--lowpass paper|regularized] [--lowpass-hz HZ] [--mode causal|zerophase]
                   [--columns A,B] [--transient drop|mark|keep] [--quiet]
                   [--decimal .|,] [--thousands none|,|.|'|space]
    rigsim correct IN --model TRUCK.toml --pairs fl=DRIVE:LVDT,... -o OUT [--map fl=CH,...] ...

``IN`` is read by :func:`rigsim.correction.io.measured.read_channels` (any CSV dialect, RPC III, MDF4, TDMS),
its channels named as the reader returns them (``Fz_FL`` for a header ``Fz_FL [kN]``) and in SI,
so a force in kN is corrected in N; ``--decimal`` and ``--thousands`` say how a text file writes
its numbers when they leave it ambiguous. Without ``--columns``/``--map`` every numeric channel
is read and the force channels (unit N, kN... or none) are the candidates; with them only the
named channels are read. A chosen channel that is not a force is refused. ``T_a`` comes from
``--actuator`` (one actuator file, :mod:`rigsim.correction.io.actuator_file`, for every channel),
``--actuators`` (one ``T_a`` per corner; a corner corrects the channel whose name holds the
corner as a token, ``tire_force_fl_N`` or ``Fz_FL``, case-insensitive, or the one ``--map``
gives) or ``--identify`` (one drive and pan displacement (LVDT) channel of the same file, fitted by
:func:`rigsim.correction.identification.actuator_fit.fit_actuator`; ``--model``'s ``--pairs`` names one
such pair per corner). The one correction is
:func:`rigsim.correction.output.pipeline.correct_forces`.

``OUT`` is written by :func:`rigsim.correction.io.measured.write_channels` in its extension's format: the
time (s) and ``<channel>_corrected`` in N (and ``settled``, 0/1, with ``--transient mark``;
``drop``, the default, leaves out the correction's transients, ``keep`` keeps them), with
metadata on how it was made (input, T_a source, low-pass, mode, settling tolerance, rigsim
version). The per-channel DLC, stress factor and damage-equivalent load before and after
correction are printed. Bad input raises :class:`rigsim.scenarios.core.config.ScenarioError` (one
sentence naming the channel or line and the fix) and nothing is written; ``-o`` naming an input,
or an existing file without ``--force``, is refused before any work, and so is an ``-o`` another
command is writing (the file is claimed for the command's run:
:func:`rigsim.scenarios.records.output.claimed_out_file`).

``--model TRUCK.toml --pairs fl=DRIVE:LVDT,...`` corrects instead by a truck model calibrated on
the file's own drive, LVDT and force channels (:mod:`rigsim.scenarios.cli.correct_model`).

``--help`` shows one line per option, in groups (input, channels, linear correction, model
correction, output); each option in full is on the guide's page, ``docs/guide/correct.md``.

This module parses and prints: the flags become the option objects a lab's script passes to
:func:`rigsim.correct_record` (:data:`rigsim.scenarios.records.naming.FLAGS`, one table of flag and field), and the work is the
records API's (:func:`rigsim.scenarios.records.api.plan_correction`, then the plan's
``check_output``, ``run`` and the result's ``write``), whose messages name the command's flags
(:data:`rigsim.scenarios.records.naming.CLI_NAMING`).
"""

from __future__ import annotations

import argparse

from rigsim.scenarios.core.flags import (add_channel_timing, add_command, add_force, add_number_format, add_out, add_quiet,
                                         add_time_col)
from rigsim.scenarios.records.naming import CLI_NAMING, FLAGS
from rigsim.scenarios.records.output import claimed_out_file
from rigsim.scenarios.studies.identify.command import channel_timing

__all__ = ["USAGE", "options_from_args", "refuse_model_options", "add_parser", "cmd_correct"]


def options_from_args(args):
    """(the :class:`~rigsim.scenarios.records.options.LinearOptions` or
    :class:`~rigsim.scenarios.records.options.ModelOptions`, ``correct_record``'s keywords) that
    ``rigsim correct``'s flags give, by :data:`~rigsim.scenarios.records.naming.FLAGS`."""
    from rigsim.scenarios.records.options import LinearOptions, ModelOptions

    parts = {"linear": {}, "model": {}, "call": {}}
    for _, dest, where, field in FLAGS:
        timing = field in ("force_filter", "lvdt_filter")
        parts[where][field] = channel_timing(args, field.split("_")[0]) if timing else getattr(args, dest)
    linear = LinearOptions(**parts["linear"])
    if parts["model"]["truck"] is None:
        return linear, parts["call"]
    model = parts["model"] | {"pairs": parts["model"]["pairs"] or None, "linear": linear,
                              "calibration_records": tuple(parts["model"]["calibration_records"] or ())}
    return ModelOptions(**model), parts["call"]


#: ``rigsim correct``'s usage line: the four ways to get T_a (or the model), then the rest.
USAGE = ("%(prog)s IN -o OUT (--actuators ACTS.toml | --actuator ACT.toml\n"
         "       | --identify DRIVE,LVDT | --model TRUCK.toml --pairs fl=DRIVE:LVDT,...)\n"
         "       [options]")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``correct`` on an ``argparse`` sub-parsers object; sets ``func=cmd_correct``. One line
    per option; the details are on the guide's page (``docs/guide/correct.md``)."""
    from rigsim.correction.output.lowpass import BAND_HZ
    from rigsim.scenarios.cli.correct_model import add_model_arguments

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


def refuse_model_options(args) -> None:
    """Refuse (one sentence) a flag of a :class:`~rigsim.scenarios.records.options.ModelOptions` field
    (:data:`rigsim.scenarios.records.naming.FLAGS`) given without ``--model``."""
    for option, dest, where, _ in FLAGS:
        if where == "model" and dest != "model" and getattr(args, dest, None) not in (None, False, ""):
            from rigsim.scenarios.core.config import ScenarioError

            raise ScenarioError(f"{option} goes with --model TRUCK.toml (the model correction); drop it, or give --model")


def cmd_correct(args) -> int:
    """Run ``rigsim correct``: the option objects from the flags, the records API's
    :func:`~rigsim.scenarios.records.api.plan_correction` (what ``correct_record`` runs), ``-o``
    checked before the work; returns 0, raises ScenarioError (one sentence) for bad input."""
    from rigsim.scenarios.cli import correct_model
    from rigsim.scenarios.records.api import plan_correction

    if args.model is None:
        refuse_model_options(args)
    inputs = [args.input, args.model, args.actuator, args.actuators, getattr(args, "calibration", None),
              *(getattr(args, "calibrate_also", None) or ())]
    with claimed_out_file(args.out, inputs, args.force):
        options, call = options_from_args(args)
        plan = plan_correction(args.input, options, **call, naming=CLI_NAMING, time_col=args.time_col,
                               decimal=args.decimal, thousands=args.thousands)
        plan.check_output(args.out)
        if args.model is not None:
            correct_model.check_calibration_output(args, plan.inputs)
            return correct_model.report_model(args, plan.run(progress=None if args.quiet else correct_model.say))
        result = plan.run()
        result.write(args.out, overwrite=args.force)
        correct_model.print_summary(args, result, f"({result.description})")
        return 0
