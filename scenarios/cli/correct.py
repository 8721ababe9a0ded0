"""``rigsim correct``: output correction of wheel forces measured on a real rig.

::

    rigsim correct IN (--actuator ACT.toml | --actuators ACTS.toml [--map fl=CH,...]
                   | --identify DRIVE_CH,DISP_CH) -o OUT [--force] [--time-col NAME]
                   [--lowpass paper|regularized] [--mode causal|zerophase] [--columns A,B]
                   [--transient drop|mark|keep] [--decimal .|,] [--thousands none|,|.|'|space]
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
or an existing file without ``--force``, is refused before any work.

``--model TRUCK.toml --pairs fl=DRIVE:LVDT,...`` corrects instead by a truck model calibrated on
the file's own drive, LVDT and force channels (:mod:`scenarios.cli.correct_model`); the shared
parts are :mod:`scenarios.records.channels` (which channels) and
:mod:`scenarios.records.output` (checks, the linear correction, the file and the table).
"""

from __future__ import annotations

import argparse

from scenarios.records.channels import parse_options, plan_channels, read_input
from scenarios.studies.identify.command import add_number_format
from scenarios.records.output import (check_out_file, fit_metadata, linear_correction,
                                          linear_metadata, output_units, probe_output, rigsim_version,
                                          write_corrected)

__all__ = ["add_parser", "cmd_correct"]


def _error(message: str):
    from scenarios.core.config import ScenarioError

    return ScenarioError(message)


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``correct`` on an ``argparse`` sub-parsers object; sets ``func=cmd_correct``."""
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
                        "regularized: 6th-order Butterworth at 30 Hz, inverse ~exact to 20 Hz (default)")
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
    add_model_arguments(c)
    c.set_defaults(func=cmd_correct)
    return c


def _read_actuators(args):
    from correction.io.actuator_file import read_actuator_file, read_actuators_file

    given = [o for o in ("actuator", "actuators", "identify") if getattr(args, o) is not None]
    if len(given) != 1:
        raise _error("give exactly one of --actuator ACT.toml, --actuators ACTS.toml and --identify DRIVE_COL,DISP_COL")
    if args.map is not None and args.actuators is None:
        raise _error("--map maps corners of a per-corner file: use it with --actuators ACTS.toml")
    try:
        if args.actuator is not None:
            return read_actuator_file(args.actuator)
        if args.actuators is not None:
            return read_actuators_file(args.actuators)
    except ValueError as exc:
        raise _error(str(exc)) from None
    return None


def _metadata(args, id_cols, cols, corners) -> dict[str, str]:
    """How the output was made: rigsim version, input, T_a source, low-pass, mode, tolerance."""
    source = f"identified from {','.join(id_cols)}" if args.identify else str(args.actuator or args.actuators)
    meta = {"made_by": "rigsim correct", "rigsim_version": rigsim_version(), "input": str(args.input),
            "ta_source": source}
    if corners is not None:
        meta["corners"] = ",".join(f"{k}={c}" for k, c in zip(corners, cols))
    meta.update(linear_metadata(args))
    return fit_metadata(args.out, meta)


def cmd_correct(args) -> int:
    """Run ``rigsim correct``; returns 0, raises ScenarioError (one sentence) for bad input."""
    from scenarios.cli import correct_model

    if args.model is not None:
        return correct_model.cmd_correct_model(args)
    correct_model.refuse_model_options(args)
    import numpy as np

    from correction.identification.actuator_fit import fit_actuator

    inputs = [args.input, args.actuator, args.actuators]
    check_out_file(args.out, inputs, args.force)
    asked, items, id_cols = parse_options(args)
    ta_file = _read_actuators(args)
    mc, name = read_input(args, asked, items, id_cols)
    asked = None if asked is None else [name(c) for c in asked]
    items = None if items is None else [(k, name(c)) for k, c in items]
    force_cols, id_cols, corners = plan_channels(args, mc, asked, items, [name(c) for c in id_cols],
                                                 list(ta_file) if args.actuators is not None else None)
    if not force_cols:
        raise _error(f"{str(args.input)!r} has no force channel to correct (unit N, kN... or none); name them with "
                     "--columns")
    fs = mc.fs_hz
    meta = _metadata(args, id_cols, force_cols, corners)
    probe_output(args.out, output_units(force_cols, args.transient), meta)
    source = f"from {str(args.actuator or args.actuators)!r}"
    if args.identify is not None:
        drive, disp = (mc.data[c] for c in id_cols)
        if np.std(drive) == 0 or np.std(disp) == 0:
            raise _error(f"--identify columns {id_cols[0]!r} and {id_cols[1]!r} must vary to identify T_a")
        try:
            fit = fit_actuator(drive, disp, fs)
        except ValueError as exc:
            raise _error(f"cannot identify T_a from {id_cols[0]!r} and {id_cols[1]!r}: {exc}") from None
        tas = fit
        source = (f"identified (orders {fit.orders[0]}/{fit.orders[1]}, held-out error {fit.held_out_error:.1%}, "
                  f"bandwidth {fit.bandwidth_hz:.3g} Hz)")
    else:
        tas = ta_file if corners is None else [ta_file[c] for c in corners]
    forces = mc.array(force_cols)
    res = linear_correction(args, forces, tas, fs, force_cols, corners)
    write_corrected(args, mc, force_cols, forces, res.corrected_N, res.settled, meta, inputs)
    print(f"corrected {len(force_cols)} channel(s) of {str(args.input)!r} at {fs:.6g} Hz (T_a {source}, low-pass "
          f"{res.filters[0].lowpass.description}, {args.mode}); {forces.shape[0] - int(res.settled.sum())} transient "
          f"samples {'dropped' if args.transient == 'drop' else 'kept'}; wrote {args.out}")
    return 0
