"""``rigsim correct --model``: measured wheel forces corrected by a truck model calibrated on the same record.

::

    rigsim correct IN --model TRUCK.toml --pairs fl=DRIVE:LVDT,fr=...,rl=...,rr=... -o OUT
                   [--map fl=CH,... | --columns A,B,C,D] [--actuator ACT.toml | --actuators ACTS.toml]
                   [--jobs N] [--max-evaluations N] [--calibration-windows N] [--cab auto|held|fitted]
                   [--drift-cut-hz HZ] [--calibration CAL.json] [--calibrate-also REC]... [--quiet]
                   [--transient drop|mark|keep] [--force] [--time-col NAME]

The truck model (the truck ``TRUCK.toml`` describes) is calibrated on ``IN`` (and on windows of the
other records of the same truck ``--calibrate-also`` names, read with the same channels): per
corner the drive x_ref and the LVDT x_a (``--pairs``, the syntax of ``rigsim identify
--from-file``; lengths, converted to m) and the wheel force F_rig (the force channel whose name
holds the corner as a token, or ``--map``'s; converted to N); then
F_corrected = F_model(x_ref) + L(W(F_rig - F_model(x_a))) per wheel, W the residual's white noise
and its drift below ``--drift-cut-hz`` (0.7 Hz; 0: none) taken out (rigsim.correction.output.denoise), L
the linear correction
T_a^-1 T_F with ``--actuator``/``--actuators`` if given, else T_a identified per corner from the
``--pairs`` channels (:func:`rigsim.scenarios.records.model.differential.correct_with_model`). ``TRUCK.toml`` is a
scenario file (:func:`rigsim.scenarios.core.config.load_scenario`): its rig (actuator stroke) is used,
and its ``[vehicle]`` tire stiffness, tire damping, tire stiffening (``tire_progressive_ratio``,
``tire_progressive_onset_m``, and the rear tires' ``_ratio_rear`` / ``_onset_rear_m``, which
default to the all-wheel values) and leaf friction, where given, are the calibration's first guesses
instead of the catalogue values; the payload and its position always
start from the record's static loads. The cab (``--cab``): by default the model is calibrated
with the cab held (rigid, or at ``[vehicle] cab_mount_hz`` if given) and, where a cab on its own
mounts could fit clearly better, once more with the cab's mount frequency fitted (from that value
or 2.5 Hz), and the clearly better fit is kept
(:func:`rigsim.scenarios.records.model.cab_choice.calibrate_cab`); ``--cab held`` or
``--cab fitted`` calibrates once. Every fitted value is only a starting guess.

Where the model cannot be trusted on this record (its calibration did not converge or could not
run, or it does not reproduce F_rig on any wheel) L alone corrects the record; where it does not
reproduce F_rig on some wheels, L alone corrects those; the reason is printed and written to the
output's metadata. ``OUT`` is the file :meth:`rigsim.scenarios.records.corrected.CorrectionResult.write`
writes: ``<channel>_corrected`` in N (``settled`` with ``--transient mark``; the model runs' first
:data:`~rigsim.scenarios.records.model.differential.START_S` are not settled), with metadata:
the method (and why), the calibration (fitted values with units and 1-sigma, fit NRMSE per
wheel), the scenario file and the rigsim version. Every refusal comes before any work, as one
:class:`rigsim.scenarios.core.config.ScenarioError` sentence. ``--quiet`` silences the progress lines
and notes on stderr.

This module adds the flags and prints: the option objects and the work are ``rigsim correct``'s
(:mod:`rigsim.scenarios.cli.correct`, the records API). Imports nothing heavy at module level.
"""

from __future__ import annotations

import sys


__all__ = ["add_model_arguments", "report_model", "print_summary", "say"]


def add_model_arguments(group) -> None:
    """Add ``--model`` and its options to ``group`` of ``rigsim correct``'s parser, one line each (the
    numbers are literals, pinned to their homes by the tests; the details: ``docs/guide/correct.md``)."""
    from rigsim.scenarios.core.flags import add_jobs, add_pairs

    group.add_argument("--model", metavar="TRUCK.toml", help="this truck, on at least 10 s of record")
    add_pairs(group)
    add_jobs(group)
    group.add_argument("--max-evaluations", type=int, default=None, metavar="N",
                       help="most evaluations of the fit (default 60)")
    group.add_argument("--calibration-windows", type=int, default=None, metavar="N",
                       help="windows, each 5 s lead-in + 5 s (default 2)")
    group.add_argument("--cab", choices=("auto", "held", "fitted"), default=None, metavar="auto|held|fitted",
                       help="the cab (default auto): docs/model_correction.md")
    group.add_argument("--drift-cut-hz", type=float, default=None, metavar="HZ",
                       help="drift cut, Hz; 0: none (default 0.7, at most 1.5)")
    group.add_argument("--calibration", metavar="CAL.json", default=None,
                       help="reuse an earlier run's OUT.calibration.json")
    group.add_argument("--calibrate-also", action="append", metavar="REC", default=None,
                       help="fit windows of this record too (repeat for more)")


def check_calibration_output(args, inputs) -> None:
    """Refuse, before the work, a calibration file beside ``-o`` that exists (without ``--force``) or is
    an input (:func:`~rigsim.scenarios.records.corrected.calibration_path`)."""
    from rigsim.scenarios.records.corrected import calibration_path
    from rigsim.scenarios.records.model.saved import check_target

    check_target(calibration_path(args.out), overwrite=args.force, inputs=inputs, beside=f"of -o {args.out}")


def report_model(args, result) -> int:
    """Print what ``rigsim correct --model`` found (the method, the calibration, the model error,
    the loads) and write ``result`` to ``-o`` (checked and claimed by the caller); returns 0."""
    cal, meta = result.calibration, result.metadata
    if result.method == "linear":
        print(f"linear correction used: {result.reason}")
    elif result.reason:
        print(f"truck model used on {meta['model_wheels']}: {result.reason}")
    if cal is not None:
        print(cal.table())
        print(f"fit NRMSE per wheel (calibrated model against the measured force): {meta['cal_fit_nrmse']}; "
              f"{meta['cal_runs']}")
        print(f"model error per wheel (dynamic fit NRMSE in the correction's band beyond the load cells' noise): "
              f"{meta['cal_model_error']}")
        print(f"load cells' mass: {meta['cal_cell_mass']}")
        for said in cal.choices:
            print(said[0].upper() + said[1:])
    if "residual_noise" in meta:
        print(meta["residual_noise"][0].upper() + meta["residual_noise"][1:])
    calibration = _write_both(args, result)
    print_summary(args, result, f"by {result.description}" if result.method == "model"
                  else f"by the linear correction ({result.description})", calibration)
    return 0


def print_summary(args, result, how: str, calibration=None) -> None:
    """Print ``rigsim correct``'s last lines: the loads table (where samples settled) and one line of
    what was corrected ``how``, and the files written (``-o``, and the ``calibration`` file if any)."""
    if result.settled.any():
        print(result.table())
    wrote = str(args.out) + ("" if calibration is None else f" and {calibration}")
    print(f"corrected {len(result.channels)} channel(s) of {str(args.input)!r} at {result.fs_hz:.6g} Hz {how}; "
          f"{result.transient_samples} transient samples {'dropped' if args.transient == 'drop' else 'kept'}; "
          f"wrote {wrote}")


def _write_both(args, result):
    """Write the corrected file and (where the truck was calibrated) its calibration beside it, both
    or neither: the calibration first, removed again if the corrected file cannot be written.
    Returns the calibration file written, or None."""
    import os

    from rigsim.scenarios.records.corrected import calibration_path

    if result.saved_calibration is None:
        result.write(args.out, overwrite=args.force)
        return None
    cal = result.write_calibration(calibration_path(args.out), overwrite=args.force)
    try:
        result.write(args.out, overwrite=args.force)
    except BaseException:
        os.unlink(cal)
        raise
    return cal


def say(line: str) -> None:
    """A progress line or note of the calibration, on stderr."""
    print(line, file=sys.stderr, flush=True)
