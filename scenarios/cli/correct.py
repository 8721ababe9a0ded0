"""``rigsim correct``: output correction of wheel forces measured on a real rig (a CSV file).

::

    rigsim correct IN.csv (--actuator ACT.toml | --actuators ACTS.toml [--map fl=COL,...]
                   | --identify DRIVE_COL,DISP_COL) -o OUT.csv [--lowpass paper|regularized]
                   [--mode causal|zerophase] [--columns A,B] [--transient drop|mark|keep]

``IN.csv`` has a header line, a ``time`` (or ``time_s``) column in seconds on a uniform grid,
and one or more force columns in N. ``OUT.csv`` gets the time column (as written in the input)
and the chosen force columns corrected by ``T_a^-1 T_F``, named ``<column>_corrected`` so that
they cannot be mistaken for raw ones; everything goes through the one correction,
:func:`correction.pipeline.correct_forces`. ``T_a`` comes from

* ``--actuator``: one actuator file (:mod:`correction.actuator_file`) for every column;
* ``--actuators``: a per-corner actuator file (one ``T_a`` per corner table); each corner's
  column is the one whose name holds the corner's name as a token (``tire_force_fl_N``,
  ``Fz_FL``; case-insensitive), or is given by ``--map fl=Fz_FL,fr=Fz_FR``;
* ``--identify``: two columns of the same file (the rig's drive and the measured pan
  displacement), fitted by :func:`correction.actuator_fit.fit_actuator`, the project's one
  identification (stable and minimum phase by construction, so always usable).

A table of each column's DLC before and after the correction (on the settled samples) is printed.

Rows inside the correction's start-up (and, zero-phase, run-out) transient are dropped by default
(``--transient mark`` keeps them and adds a ``settled`` column of 0/1; ``keep`` keeps them as they
are). Bad input raises :class:`scenarios.core.config.ScenarioError` (one sentence naming the column or
line and the fix); nothing is written then. ``-o`` may not name the input (checked before any work);
the output is written atomically.
"""

from __future__ import annotations

import argparse
import math
import os
import pathlib
import re

__all__ = ["add_parser", "cmd_correct"]



def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``correct`` on an ``argparse`` sub-parsers object; sets ``func=cmd_correct``."""
    c = subparsers.add_parser(
        "correct", help="correct wheel forces measured on a rig (CSV) for the actuator dynamics",
        description="Filter measured wheel forces by the inverse actuator transfer function times a "
                    "low-pass (the paper's output correction) and write them to a new CSV file.")
    c.add_argument("input", metavar="IN.csv", help="CSV with a 'time' column (s, uniform) and force columns (N)")
    c.add_argument("--actuator", metavar="ACT.toml",
                   help="actuator file for every column: [transfer_function] num, den (descending powers of s) "
                        "or [parameters] (eq. 4)")
    c.add_argument("--actuators", metavar="ACTS.toml",
                   help="per-corner actuator file: one table per corner ([fl], [fr], ...) with num, den; each "
                        "corner corrects the column whose name holds the corner as a token (or see --map)")
    c.add_argument("--map", metavar="CORNER=COL[,...]",
                   help="with --actuators: which column each corner corrects, e.g. fl=Fz_FL,fr=Fz_FR")
    c.add_argument("-o", "--out", required=True, metavar="OUT.csv", help="output CSV file (corrected columns named <column>_corrected)")
    c.add_argument("--lowpass", choices=("paper", "regularized"), default="regularized",
                   help="paper: eq. 5 (2 x 2nd order, 16/24 Hz, zeta 1; already -3 dB near 8 Hz); "
                        "regularized: 6th-order Butterworth at 30 Hz, inverse ~exact to 20 Hz (default)")
    c.add_argument("--mode", choices=("causal", "zerophase"), default="zerophase",
                   help="zerophase: |T_a^-1 T_F| with T_a^-1's phase, offline (default); causal: as a "
                        "real-time filter (adds T_F's phase lag)")
    c.add_argument("--identify", metavar="DRIVE_COL,DISP_COL",
                   help="identify T_a from these two columns (drive and pan displacement) instead of --actuator")
    c.add_argument("--columns", metavar="COL[,COL...]",
                   help="force columns to correct (default: all but time and the --identify columns; with "
                        "--actuators, the columns of the file's corners)")
    c.add_argument("--transient", choices=("drop", "mark", "keep"), default="drop",
                   help="rows inside the start-up transient: drop them (default), mark them in a 'settled' "
                        "column, or keep them")
    c.add_argument("--normalize-dc", action="store_true",
                   help="scale T_a so that T_a(0) = 1 instead of refusing one that is off")
    c.set_defaults(func=cmd_correct)
    return c


def _error(message: str):
    from scenarios.core.config import ScenarioError

    return ScenarioError(message)


def _split_columns(text: str, option: str) -> list[str]:
    cols = [c.strip() for c in text.split(",")]
    if not all(cols):
        raise _error(f"{option} {text!r} has an empty column name; give names separated by commas")
    return cols


def _check_output(out, inputs) -> None:
    """Refuse an output path that names one of the input files (before any work)."""
    o = pathlib.Path(out)
    for path in inputs:
        if path is None:
            continue
        p = pathlib.Path(path)
        try:
            same = o.exists() and p.exists() and os.path.samefile(o, p)
        except OSError:
            same = False
        if same or o.resolve() == p.resolve():
            raise _error(f"-o {str(out)!r} is the input file {str(path)!r}; write the corrected forces to a new file")


def _tokens(name: str) -> list[str]:
    return [t for t in re.split(r"[^0-9a-z]+", name.lower()) if t]


def _names_corner(column: str, corner: str) -> bool:
    """True when ``corner``'s tokens appear consecutively among ``column``'s (case-insensitive)."""
    col, cor = _tokens(column), _tokens(corner)
    return bool(cor) and any(col[i:i + len(cor)] == cor for i in range(len(col) - len(cor) + 1))


def _parse_map(text: str, corners, names) -> dict[str, str]:
    out = {}
    for item in _split_columns(text, "--map"):
        corner, sep, col = (x.strip() for x in item.partition("="))
        if not sep or not corner or not col:
            raise _error(f"--map item {item!r} must be CORNER=COLUMN, e.g. fl=Fz_FL")
        if corner not in corners:
            raise _error(f"--map names corner {corner!r}, which is not in the actuator file (its corners are "
                         f"{', '.join(corners)})")
        if col not in names:
            raise _error(f"--map names column {col!r}, which is not in the input (its columns are {', '.join(names)})")
        if corner in out:
            raise _error(f"--map gives corner {corner!r} twice; give each corner one column")
        out[corner] = col
    return out


def _auto_map(corners, pool, restricted: bool) -> dict[str, str]:
    """Corner -> column by name tokens; one sentence naming the corner (or column) and the fix."""
    out = {}
    if restricted:  # every asked column needs exactly one corner
        for col in pool:
            hits = [c for c in corners if _names_corner(col, c)]
            if len(hits) != 1:
                what = "no corner" if not hits else f"several corners ({', '.join(hits)})"
                raise _error(f"column {col!r} names {what} of the actuator file (corners {', '.join(corners)}); "
                             f"fix: --map CORNER={col}")
            if hits[0] in out:
                raise _error(f"columns {out[hits[0]]!r} and {col!r} both name corner {hits[0]!r}; fix: --map "
                             f"{hits[0]}=COLUMN")
            out[hits[0]] = col
        return out
    for corner in corners:
        hits = [col for col in pool if _names_corner(col, corner)]
        if len(hits) != 1:
            what = "no column" if not hits else f"several columns ({', '.join(hits)})"
            raise _error(f"corner {corner!r} of the actuator file matches {what} of the input; fix: "
                         f"--map {corner}=COLUMN (or --columns naming the force columns)")
        out[corner] = hits[0]
    return out


def _plan(args, names, time_name, corners):
    """(columns to correct, --identify columns, corner of each column or None); checks only.

    ``corners``: the corner names of the ``--actuators`` file (None without it).
    """
    id_cols = _split_columns(args.identify, "--identify") if args.identify is not None else []
    if args.identify is not None and len(id_cols) != 2:
        raise _error(f"--identify needs two columns DRIVE_COL,DISP_COL, got {args.identify!r}")
    asked = _split_columns(args.columns, "--columns") if args.columns is not None else None
    if asked is not None and len(set(asked)) != len(asked):
        raise _error(f"--columns {args.columns!r} names a column twice; name each column once")
    for col in id_cols + (asked or []):
        if col not in names:
            raise _error(f"column {col!r} is not in {str(args.input)!r}; its columns are {', '.join(names)}")
        if col == time_name:
            raise _error(f"column {col!r} is the time column and cannot be corrected or used to identify")
    pool = asked if asked is not None else [n for n in names if n != time_name and n not in id_cols]
    if args.actuators is None:
        return pool, id_cols, None
    if args.map is not None:
        mapping = _parse_map(args.map, corners, names)
        if asked is not None:
            missing = [c for c in asked if c not in mapping.values()]
            if missing:
                raise _error(f"column {missing[0]!r} is not mapped to a corner; fix: add CORNER={missing[0]} to --map")
            mapping = {k: v for k, v in mapping.items() if v in asked}
    else:
        mapping = _auto_map(corners, pool, asked is not None)
    cols = list(mapping.values())
    dup = sorted({c for c in cols if cols.count(c) > 1})
    if dup:
        raise _error(f"column {dup[0]!r} is mapped to several corners; fix: --map each corner to its own column")
    if time_name in cols:
        raise _error(f"column {time_name!r} is the time column and cannot be corrected; fix: --map")
    return cols, id_cols, list(mapping)


def _read_actuators(args):
    from correction.actuator_file import read_actuator_file, read_actuators_file

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


def _dlc_table(cols, before_N, after_N, fs: float) -> str:
    """Per column, before and after correction (the settled rows): DLC (1) with its change in %,
    the stress factor E[(F/F_static)^4] (1) and the damage-equivalent load for m = 5 at 1 Hz (kN)."""
    from correction.damage import damage_equivalent_load, stress_factor
    from correction.dlc import dlc

    lines = [f"{'column':<24} {'DLC before':>10} {'DLC after':>10} {'change':>8}   "
             f"{'SF4 before':>10} {'SF4 after':>10}   {'DEL5 before':>11} {'DEL5 after':>11}"]
    for j, col in enumerate(cols):
        try:
            b, a = float(dlc(before_N[:, j])), float(dlc(after_N[:, j]))
        except ValueError:  # not a compressive load (mean <= 0): no DLC
            lines.append(f"{col:<24} {'-':>10} {'-':>10} {'-':>8}")
            continue
        sf = [float(stress_factor(x[:, j])) for x in (before_N, after_N)]
        dl = [float(damage_equivalent_load(x[:, j], 5, duration_s=x.shape[0] / fs)) / 1e3 for x in (before_N, after_N)]
        lines.append(f"{col:<24} {b:>10.4f} {a:>10.4f} {100.0 * (a / b - 1.0) if b > 0 else math.nan:>7.1f}%   "
                     f"{sf[0]:>10.4f} {sf[1]:>10.4f}   {dl[0]:>8.2f} kN {dl[1]:>8.2f} kN")
    return "\n".join(lines)


def cmd_correct(args) -> int:
    """Run ``rigsim correct``; returns 0, raises ScenarioError (one sentence) for bad input."""
    import numpy as np

    from correction.actuator_fit import fit_actuator
    from correction.measured import TIME_NAMES, MeasuredDataError, read_force_csv, sampling_rate
    from correction.pipeline import CorrectionError, correct_forces
    from scenarios.core.files import atomic_write_text

    _check_output(args.out, [args.input, args.actuator, args.actuators])
    ta_file = _read_actuators(args)
    try:
        names, time_text, data = read_force_csv(args.input)
        time_name = next(n for n in TIME_NAMES if n in names)
        fs = sampling_rate(data[:, names.index(time_name)], time_name)
    except MeasuredDataError as exc:
        raise _error(str(exc)) from None
    force_cols, id_cols, corners = _plan(args, names, time_name,
                                         list(ta_file) if args.actuators is not None else None)
    if not force_cols:
        raise _error(f"{str(args.input)!r} has no force column to correct besides {time_name!r}")
    source = f"from {str(args.actuator or args.actuators)!r}"
    if args.identify is not None:
        drive, disp = (data[:, names.index(c)] for c in id_cols)
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
    forces = data[:, [names.index(c) for c in force_cols]]
    try:
        res = correct_forces(forces, tas, fs, lowpass=args.lowpass, mode=args.mode, normalize_dc=args.normalize_dc)
    except CorrectionError as exc:
        msg = str(exc).replace("pass normalize_dc=True", "pass --normalize-dc")
        if exc.column is not None and corners is not None:
            msg = f"corner {corners[exc.column]!r} (column {force_cols[exc.column]!r}): {msg}"
        raise _error(msg) from None
    settled = res.settled
    if args.transient == "drop" and not settled.any():
        head = max(f.transient_samples(args.mode)[0] for f in res.filters)
        tail = max(f.transient_samples(args.mode)[1] for f in res.filters)
        raise _error(f"the record ({forces.shape[0] / fs:.3g} s) is not longer than the correction's transients "
                     f"({head / fs:.3g} s at the start, {tail / fs:.3g} s at the end); fix: give a longer record "
                     "or pass --transient keep")
    rows = np.flatnonzero(settled) if args.transient == "drop" else np.arange(forces.shape[0])
    out_names = [time_name] + [f"{c}_corrected" for c in force_cols] + (["settled"] if args.transient == "mark" else [])
    lines = [",".join(out_names)]
    corrected = res.corrected_N
    for i in rows:
        fields = [time_text[i]] + [f"{v:.10g}" for v in corrected[i]]
        if args.transient == "mark":
            fields.append("1" if settled[i] else "0")
        lines.append(",".join(fields))
    atomic_write_text(args.out, "\n".join(lines) + "\n")
    if settled.any():
        print(_dlc_table(force_cols, forces[settled], corrected[settled], fs))
    print(f"corrected {len(force_cols)} column(s) of {str(args.input)!r} at {fs:.6g} Hz (T_a {source}, low-pass "
          f"{res.filters[0].lowpass.description}, {args.mode}); {forces.shape[0] - int(settled.sum())} transient "
          f"rows {'dropped' if args.transient == 'drop' else 'kept'}; wrote {args.out}")
    return 0
