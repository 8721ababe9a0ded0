"""``rigsim correct --model``: measured wheel forces corrected by a truck model calibrated on the same record.

::

    rigsim correct IN --model TRUCK.toml --pairs fl=DRIVE:LVDT,fr=...,rl=...,rr=... -o OUT
                   [--map fl=CH,... | --columns A,B,C,D] [--actuator ACT.toml | --actuators ACTS.toml]
                   [--jobs N] [--max-evaluations N] [--calibration-windows N] [--quiet]
                   [--transient drop|mark|keep] [--force] [--time-col NAME]

The truck model (the project's truck, ``truck_rig.xml``) is calibrated on ``IN`` alone: per
corner the drive x_ref and the LVDT x_a (``--pairs``, the syntax of ``rigsim identify
--from-file``; lengths, converted to m) and the wheel force F_rig (the force channel whose name
holds the corner as a token, or ``--map``'s; converted to N); then
F_corrected = F_rig + F_model(x_ref) - F_model(x_a) per wheel
(:func:`scenarios.records.model.differential.correct_with_model`). ``TRUCK.toml`` is a
scenario file (:func:`scenarios.core.config.load_scenario`): its rig (actuator stroke) is used,
and its ``[vehicle]`` tire stiffness, tire damping, tire stiffening (``tire_progressive_ratio``,
``tire_progressive_onset_m``, and the rear tires' ``_ratio_rear`` / ``_onset_rear_m``, which
default to the all-wheel values) and leaf friction, where given, are the calibration's first guesses
instead of the catalogue values; the payload and its position always
start from the record's static loads. The cab (``--cab``): by default the model is calibrated
twice, the cab held (rigid, or at ``[vehicle] cab_mount_hz`` if given) and the cab's mount
frequency fitted (from that value or 2.5 Hz), and the clearly better fit is kept
(:func:`scenarios.records.model.cab_choice.calibrate_cab`); ``--cab held`` or
``--cab fitted`` calibrates once. Every fitted value is only a starting guess.

Where the model cannot be trusted on this record (it does not reproduce F_rig, or its calibration
did not converge or could not run) the linear correction is used instead, with ``--actuator`` /
``--actuators`` if given, else T_a identified per corner from the ``--pairs`` channels
(:func:`scenarios.records.recorded.identify_recorded`), and the reason is printed and
written to the output's metadata. ``OUT`` is the linear path's file
(:func:`scenarios.records.output.write_corrected`): ``<channel>_corrected`` in N (``settled``
with ``--transient mark``; the model runs' first
:data:`~scenarios.records.model.differential.START_S` are not settled), with metadata:
the method (and why), the calibration (fitted values with units and 1-sigma, fit NRMSE per
wheel), the scenario file and the rigsim version. Every refusal comes before any work, as one
:class:`scenarios.core.config.ScenarioError` sentence. Imports nothing heavy at module level.
"""

from __future__ import annotations

import sys
import textwrap

__all__ = ["add_model_arguments", "refuse_model_options", "cmd_correct_model", "MODEL_OPTIONS", "cal_key"]

#: The options only ``--model`` reads: argparse dest -> option.
MODEL_OPTIONS = {"pairs": "--pairs", "jobs": "--jobs", "max_evaluations": "--max-evaluations",
                 "calibration_windows": "--calibration-windows", "cab": "--cab", "quiet": "--quiet"}
#: The fields the payload's first guess comes from the record for (a [vehicle] value is not used).
FROM_STATIC_LOADS = ("payload_kg", "payload_x_m")


def add_model_arguments(parser) -> None:
    """Add ``--model`` and its options to ``rigsim correct``'s parser (help literals pinned by the tests)."""
    g = parser.add_argument_group(
        "correction by a truck model calibrated on the record (instead of T_a^-1 T_F)")
    g.add_argument("--model", metavar="TRUCK.toml",
                   help="correct each wheel as F_rig + F_model(drive) - F_model(LVDT), the truck model calibrated "
                        "on IN's own drive, LVDT and force channels (payload and its position, tire stiffness and "
                        "damping and leaf friction per axle, the tires' stiffening (ratio and onset of a bilinear "
                        "tire per axle), the cab's mount frequency where it fits clearly better (--cab); minutes of "
                        "CPU). TRUCK.toml is a scenario file: its rig (actuator stroke) is used, its [vehicle] "
                        "cab_mount_hz is the cab's mount (held, or the first guess of its fit), and its tire and "
                        "leaf-friction values (tire_progressive_ratio and _onset_m included) are only the "
                        "starting guess (default: catalogue values; payload and position start from the record's "
                        "static loads). Needs --pairs and at least 6.5 s of record (the windows are spread over "
                        "it). Where the model does not reproduce the forces, the linear correction is used "
                        "(--actuator or --actuators if given, else T_a identified per corner from --pairs; "
                        "--lowpass, --mode apply) and the reason is printed and written to OUT")
    g.add_argument("--pairs", metavar="fl=DRIVE:LVDT,...",
                   help="with --model: per corner (fl, fr, rl, rr) the drive and the pan displacement (LVDT) "
                        "channels, named without their [unit] as for rigsim identify --from-file; lengths from "
                        "mid-stroke (m, mm... converted to m)")
    g.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="with --model: worker processes (default: all cores)")
    g.add_argument("--max-evaluations", type=int, default=None, metavar="N",
                   help="with --model: most evaluations of the fit's residual (scipy's max_nfev; each Jacobian "
                        "adds one model run per fitted value and window) (default 60); a fit stopped by it has "
                        "not converged and the linear correction is used")
    g.add_argument("--calibration-windows", type=int, default=None, metavar="N",
                   help="with --model: windows of the record the model is fitted on, each 2.5 s lead-in + 4 s "
                        "(default 3); 1 is about 3 times faster, on less of the record")
    g.add_argument("--cab", choices=("auto", "held", "fitted"), default=None,
                   help="with --model: the model's cab. auto (default): calibrate with the cab held and with its "
                        "mount frequency fitted (1-30 Hz), keep the fit that reproduces the forces clearly better "
                        "(3-4 times the CPU of one); held: the cab rigid, or at TRUCK.toml's vehicle.cab_mount_hz; fitted: "
                        "always fit the mount (a smooth record may not pin it: see the README)")
    g.add_argument("--quiet", action="store_true", help="with --model: no progress lines on stderr")


def _error(message: str):
    from scenarios.core.config import ScenarioError

    return ScenarioError(message)


def refuse_model_options(args) -> None:
    """Refuse (one sentence) an option of :data:`MODEL_OPTIONS` given without ``--model``."""
    for dest, option in MODEL_OPTIONS.items():
        if getattr(args, dest, None) not in (None, False):
            raise _error(f"{option} goes with --model TRUCK.toml (the model correction); drop it, or give --model")


def _check_options(args):
    """(pairs corner -> (drive, LVDT) in corner order, windows, max_nfev, workers); flags only."""
    from mjcf.names import CORNERS
    from scenarios.core.pool import worker_count
    from scenarios.records.recorded import parse_pairs
    from scenarios.records.model.calibrate import MAX_NFEV, WINDOWS

    if args.identify is not None:
        raise _error("--identify fits one T_a for the linear correction; with --model the fallback identifies each "
                     "corner from --pairs: drop --identify")
    if args.actuator is not None and args.actuators is not None:
        raise _error("give at most one of --actuator and --actuators (the T_a of --model's linear fallback)")
    if not args.pairs:
        raise _error("--model needs --pairs fl=DRIVE:LVDT,fr=...,rl=...,rr=... naming each corner's drive and LVDT "
                     "channels")
    pairs = parse_pairs(args.pairs)
    for corner in pairs:
        if corner not in CORNERS:
            raise _error(f"--pairs names corner {corner!r}; the truck's corners are {', '.join(CORNERS)}")
    missing = [c for c in CORNERS if c not in pairs]
    if missing:
        raise _error(f"--pairs has no corner {missing[0]!r}; give CORNER=DRIVE:LVDT for each of {', '.join(CORNERS)}")
    try:
        workers = worker_count(args.jobs)
    except ValueError:
        raise _error(f"--jobs must be a whole number >= 1, got {args.jobs}") from None
    for option, value in (("--max-evaluations", args.max_evaluations), ("--calibration-windows",
                                                                        args.calibration_windows)):
        if value is not None and value < 1:
            raise _error(f"{option} must be a whole number >= 1, got {value}")
    windows = WINDOWS if args.calibration_windows is None else int(args.calibration_windows)
    max_nfev = MAX_NFEV if args.max_evaluations is None else int(args.max_evaluations)
    return {c: pairs[c] for c in CORNERS}, windows, max_nfev, workers


def _fallback_file(args):
    """The linear fallback's T_a from --actuator / --actuators (one, or one per corner), or None."""
    from correction.io.actuator_file import read_actuator_file, read_actuators_file
    from mjcf.names import CORNERS

    try:
        if args.actuator is not None:
            return read_actuator_file(args.actuator)
        if args.actuators is None:
            return None
        table = read_actuators_file(args.actuators)
    except ValueError as exc:
        raise _error(str(exc)) from None
    missing = [c for c in CORNERS if c not in table]
    if missing:
        raise _error(f"--actuators {str(args.actuators)!r} has no corner {missing[0]!r}; the linear fallback of "
                     f"--model corrects the four corners {', '.join(CORNERS)}")
    return [table[c] for c in CORNERS]


def _check_pairs(args, mc, pairs) -> None:
    """Each --pairs channel: in the file, not the time, a length, varying and finite."""
    import numpy as np

    from scenarios.records.channels import LENGTH_UNITS, unit_text

    names = list(mc.names)
    for corner, cols in pairs.items():
        for col in cols:
            if col == mc.time_name or col not in names:
                what = "is the time column" if col == mc.time_name else f"is not in {str(args.input)!r}"
                raise _error(f"--pairs {corner}: channel {col!r} {what}; its channels are {', '.join(names)}")
            if mc.units[col] not in LENGTH_UNITS:
                raise _error(f"--pairs {corner}: channel {col!r} is in {unit_text(mc, col)}, not a length; give the "
                             "drive and the LVDT (pan displacement) channels, in m or mm")
        if any(np.std(mc.data[c]) == 0 for c in cols):
            raise _error(f"--pairs {corner}: channels {cols[0]!r} and {cols[1]!r} must vary (a drive and the pan's "
                         "motion)")


def _plan(args, pairs, windows: int):
    """Everything checked before any work: (channels, ``pairs`` as read, force channels in corner
    order, fallback T_a or None, scenario); one ScenarioError sentence otherwise."""
    import numpy as np

    from mjcf.names import CORNERS
    from scenarios.records.channels import parse_options, plan_channels, read_input
    from scenarios.core.config import ScenarioError, load_scenario
    from scenarios.records.model.calibrate import WINDOW_LEAD_S, WINDOW_S, fit_windows

    scenario = load_scenario(args.model)
    asked, items, _ = parse_options(args)
    fallback_tas = _fallback_file(args)
    mc, name = read_input(args, asked, items, [c for cols in pairs.values() for c in cols])
    pairs = {corner: (name(d), name(x)) for corner, (d, x) in pairs.items()}
    _check_pairs(args, mc, pairs)
    asked = None if asked is None else [name(c) for c in asked]
    items = None if items is None else [(k, name(c)) for k, c in items]
    cols, _, corners = plan_channels(args, mc, asked, items, [c for cs in pairs.values() for c in cs], CORNERS,
                                     owner="the truck model")  # the --pairs channels are never corrected
    mapping = dict(zip(corners, cols))
    missing = [c for c in CORNERS if c not in mapping]
    if missing:
        raise _error(f"corner {missing[0]!r} has no force channel; fix: --map {missing[0]}=CHANNEL (--model corrects "
                     f"the four wheels {', '.join(CORNERS)} together)")
    force_cols = [mapping[c] for c in CORNERS]
    for col in force_cols:
        if not np.all(np.isfinite(mc.data[col])):
            raise _error(f"channel {col!r} has NaN or infinite values; clean or cut the record first")
    try:
        fit_windows(mc.time_s, windows, WINDOW_S, WINDOW_LEAD_S)
    except ScenarioError as exc:
        raise _error(f"{str(args.input)!r}: {exc}") from None
    return mc, pairs, force_cols, fallback_tas, scenario


def _first_guess(scenario) -> tuple[dict, list[str]]:
    """(fitted fields' first guesses from TRUCK.toml's [vehicle], its other given fields: not used)."""
    from scenarios.records.model.calibrate import FITTED

    given = {k: getattr(scenario.vehicle, k) for k in type(scenario.vehicle).field_names()
             if getattr(scenario.vehicle, k) is not None}
    guess = {k: float(v) for k, v in given.items() if k in FITTED and k not in FROM_STATIC_LOADS}
    from mjcf.tires import REAR_FIELDS

    for every, rear in REAR_FIELDS.items():
        if every in guess and rear not in guess:  # an all-wheel value is the rear tires' too
            guess[rear] = guess[every]
    return guess, [k for k in given if k not in guess]


def cal_key(name: str) -> str:
    """The metadata key of the fitted field ``name``: ``cal_`` and the name, "progressive" shortened
    to "prog" so that every key fits RPC III's 32 bytes (``cal_tire_prog_onset_rear_m``: 26)."""
    return "cal_" + name.replace("progressive", "prog")


def _calibration_meta(cal) -> dict[str, str]:
    """The calibration in metadata: one key per fitted value (unit, 1-sigma, first guess), fit NRMSE per wheel."""
    from mjcf.names import CORNERS
    from scenarios.records.model.differential import EXCESS_NRMSE_LIMIT

    meta = {cal_key(n): f"{v:.6g} {u} +- {s:.2g} (robust {sr:.2g}; first guess {g:.6g})"
            for n, u, g, v, s, sr in zip(cal.names, cal.units, cal.initial, cal.fitted, cal.sigma, cal.sigma_robust)}
    meta["cal_fit_nrmse"] = ", ".join(f"{c} {v:.3f}" for c, v in zip(CORNERS, cal.fit_nrmse))
    meta["cal_model_error"] = (", ".join(f"{c} {v:.3f}" for c, v in zip(CORNERS, cal.excess_nrmse))
                               + f" (limit {EXCESS_NRMSE_LIMIT:g})")
    meta["cal_windows_s"] = ", ".join(f"{a:.3f}-{b:.3f}" for a, b in cal.windows_s)
    meta["cal_runs"] = f"{cal.evaluations} truck variants, {'converged' if cal.converged else 'not converged'}"
    return meta


def _metadata(args, pairs, force_cols, mc_result, fallback_source: str | None) -> dict[str, str]:
    """How the output was made; ``mc_result`` the ModelCorrection (None: every key, for the probe)."""
    from correction.io.measured import format_of
    from scenarios.records.output import fit_metadata, linear_metadata, rigsim_version
    from scenarios.records.model.differential import START_S

    method = "probe" if mc_result is None else mc_result.method
    meta = {"made_by": "rigsim correct --model", "rigsim_version": rigsim_version(), "input": str(args.input),
            "scenario_file": str(args.model), "method": method}
    rpc3 = format_of(args.out) == "rpc3"

    def sentence(key: str, text: str) -> None:  # RPC III values hold 96 bytes: there split over key, key_2...
        parts = textwrap.wrap(text, 96) if rpc3 else [text]
        meta.update({key + (f"_{i + 1}" if i else ""): p for i, p in enumerate(parts)})

    reason = "x " * 100 if mc_result is None else mc_result.reason
    if reason:
        sentence("fallback_reason", reason)
    meta.update({"corners": ",".join(f"{k}={c}" for k, c in zip(pairs, force_cols)),
                 "pairs": ",".join(f"{k}={d}:{x}" for k, (d, x) in pairs.items())})
    if method in ("model", "probe"):
        meta.update({"correction": "F_corrected = F_rig + F_model(x_ref) - F_model(x_a)", "force_unit": "N",
                     "start_up_s": f"{START_S:g} (model runs' start-up: not settled)", "transient": args.transient})
    if method in ("linear", "probe"):
        meta.update({"ta_source": fallback_source or "x", **linear_metadata(args)})
    cal = None if mc_result is None else mc_result.calibration
    if mc_result is None:
        from scenarios.records.model.calibrate import FITTED, UNITS

        meta.update({cal_key(n): f"0 {UNITS[n]}" for n in FITTED})
        meta.update({k: "x" for k in ("cal_fit_nrmse", "cal_model_error", "cal_windows_s", "cal_runs")})
        sentence("cal_cab", "x " * 150)
    elif cal is not None:
        meta.update(_calibration_meta(cal))
        if cal.cab_choice:
            sentence("cal_cab", cal.cab_choice)
    return fit_metadata(args.out, meta)


def _say(args, line: str) -> None:
    if not args.quiet:
        print(line, file=sys.stderr, flush=True)


def cmd_correct_model(args) -> int:
    """Run ``rigsim correct --model``; returns 0, raises ScenarioError (one sentence) for bad input."""
    from scenarios.records.output import (check_out_file, linear_correction, output_units, probe_output,
                                              write_corrected)

    inputs = [args.input, args.model, args.actuator, args.actuators]
    check_out_file(args.out, inputs, args.force)
    pairs, windows, max_nfev, workers = _check_options(args)
    mc, pairs, force_cols, fallback_tas, scenario = _plan(args, pairs, windows)
    probe_output(args.out, output_units(force_cols, args.transient), _metadata(args, pairs, force_cols, None, None))
    guess, unused = _first_guess(scenario)

    from scenarios.records.model.cab_choice import AUTO
    from scenarios.records.model.calibrate import WINDOW_LEAD_S, WINDOW_S
    from scenarios.records.model.differential import correct_with_model

    fs, forces = mc.fs_hz, mc.array(force_cols)
    if unused:
        _say(args, f"note: {str(args.model)!r} [vehicle] {', '.join(unused)} not used: the model is the project's "
                   "truck, its payload and position start from the record's static loads")
    _say(args, f"model correction of {str(args.input)!r} ({forces.shape[0] / fs:.4g} s at {fs:.6g} Hz): calibrating "
               f"the truck model on {windows} window(s) of {WINDOW_LEAD_S + WINDOW_S:g} s, at most {max_nfev} fit "
               f"evaluations, {workers} worker process(es); this takes minutes")
    res = correct_with_model(mc.time_s, mc.array([d for d, _ in pairs.values()]),
                             mc.array([x for _, x in pairs.values()]), forces, base_scenario=scenario,
                             workers=workers, windows=windows, max_nfev=max_nfev, fitted_guess=guess,
                             cab=args.cab or AUTO)
    cal = res.calibration
    if cal is not None:
        _say(args, f"calibrated in {cal.wall_time_s:.0f} s ({cal.evaluations} truck variants run, "
                   f"{'converged' if cal.converged else 'not converged'}, worst fit NRMSE {cal.worst_fit_nrmse:.3f})"
                   + (f"; corrected in {res.timings['correction_s']:.1f} s" if not res.use_linear else ""))
    if not res.use_linear:
        meta = _metadata(args, pairs, force_cols, res, None)
        corrected, settled = res.corrected_N, res.settled
        what = "by the truck model calibrated on the record (F_rig + F_model(drive) - F_model(LVDT))"
        kind = "start-up"
    else:
        if fallback_tas is not None:
            tas, source = fallback_tas, f"from {str(args.actuator or args.actuators)!r}"
        else:
            from scenarios.records.recorded import identify_recorded

            _say(args, "the model is not used; identifying T_a per corner from --pairs for the linear correction")
            fits = identify_recorded(args.input, args.pairs, time_col=args.time_col).fits
            tas, source = [fits[c] for c in pairs], "identified per corner from --pairs"
        lin = linear_correction(args, forces, tas, fs, force_cols, list(pairs))
        meta = _metadata(args, pairs, force_cols, res, source)
        corrected, settled = lin.corrected_N, lin.settled
        what = f"by the linear correction (T_a {source}, low-pass {lin.filters[0].lowpass.description}, {args.mode})"
        kind = "transient"
    if res.use_linear:
        print(f"linear correction used: {res.reason}")
    if cal is not None:
        print(cal.table())
        print(f"fit NRMSE per wheel (calibrated model against the measured force): {meta['cal_fit_nrmse']}; "
              f"{meta['cal_runs']}")
        print(f"model error per wheel (fit NRMSE beyond the load cells' noise): {meta['cal_model_error']}")
        if cal.cab_choice:
            print(cal.cab_choice[0].upper() + cal.cab_choice[1:])
    write_corrected(args, mc, force_cols, forces, corrected, settled, meta, inputs)
    print(f"corrected {len(force_cols)} channel(s) of {str(args.input)!r} at {fs:.6g} Hz {what}; "
          f"{forces.shape[0] - int(settled.sum())} {kind} samples {'dropped' if args.transient == 'drop' else 'kept'}; "
          f"wrote {args.out}")
    return 0
