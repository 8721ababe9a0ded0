"""``rigsim correct``: output correction of wheel forces measured on a real rig (a CSV file).

::

    rigsim correct IN.csv --actuator ACT.toml -o OUT.csv [--lowpass paper|regularized]
                   [--mode causal|zerophase] [--identify DRIVE_COL,DISP_COL] [--columns A,B]
                   [--transient drop|mark|keep]

``IN.csv`` has a header line, a ``time`` (or ``time_s``) column in seconds on a uniform grid,
and one or more force columns in N. ``OUT.csv`` gets the time column (as written in the input)
and the chosen force columns corrected by ``T_a^-1 T_F`` (:mod:`correction.filters`,
:mod:`correction.apply`). ``T_a`` comes from an actuator file (:mod:`correction.actuator_file`)
or, with ``--identify``, from two columns of the same file (the rig's drive and the measured pan
displacement: H1 estimate and an eq.-4-shaped rational fit, :mod:`correction.actuator_id`).

Rows inside the correction's start-up (and, zero-phase, run-out) transient are dropped by default
(``--transient mark`` keeps them and adds a ``settled`` column of 0/1; ``keep`` keeps them as they
are). Bad input raises :class:`scenarios.core.config.ScenarioError` (one sentence naming the column or
line and the fix); nothing is written then. The output is written atomically.
"""

from __future__ import annotations

import argparse
import csv
import math

import numpy as np

__all__ = ["add_parser", "cmd_correct", "read_force_csv"]

_TIME_NAMES = ("time", "time_s")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``correct`` on an ``argparse`` sub-parsers object; sets ``func=cmd_correct``."""
    c = subparsers.add_parser(
        "correct", help="correct wheel forces measured on a rig (CSV) for the actuator dynamics",
        description="Filter measured wheel forces by the inverse actuator transfer function times a "
                    "low-pass (the paper's output correction) and write them to a new CSV file.")
    c.add_argument("input", metavar="IN.csv", help="CSV with a 'time' column (s, uniform) and force columns (N)")
    c.add_argument("--actuator", metavar="ACT.toml",
                   help="actuator file: [transfer_function] num, den (descending powers of s) or [parameters] (eq. 4)")
    c.add_argument("-o", "--out", required=True, metavar="OUT.csv", help="output CSV file")
    c.add_argument("--lowpass", choices=("paper", "regularized"), default="regularized",
                   help="paper: eq. 5 (2 x 2nd order, 16/24 Hz, zeta 1; already -3 dB near 8 Hz); "
                        "regularized: 6th-order Butterworth at 30 Hz, inverse ~exact to 20 Hz (default)")
    c.add_argument("--mode", choices=("causal", "zerophase"), default="zerophase",
                   help="zerophase: |T_a^-1 T_F| with T_a^-1's phase, offline (default); causal: as a "
                        "real-time filter (adds T_F's phase lag)")
    c.add_argument("--identify", metavar="DRIVE_COL,DISP_COL",
                   help="identify T_a from these two columns (drive and pan displacement) instead of --actuator")
    c.add_argument("--columns", metavar="COL[,COL...]",
                   help="force columns to correct (default: all but time and the --identify columns)")
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


def read_force_csv(path) -> tuple[list[str], list[str], np.ndarray]:
    """Read a CSV of columns of numbers with a header line; check every field.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    names : list of str
        Column names (stripped).
    time_text : list of str
        The time column's fields as written (``names`` must contain "time" or "time_s").
    data : numpy.ndarray, shape (rows, columns)
        All columns as floats, in the units of the file.

    Raises
    ------
    ScenarioError
        Missing file, no header or data, duplicate or missing time column, a row with the wrong
        number of fields, a field that is not a number, NaN or infinity (naming column and line).
    """
    try:
        fh = open(path, newline="", encoding="utf-8")
    except FileNotFoundError:
        raise _error(f"input file {str(path)!r} does not exist") from None
    except OSError as exc:
        raise _error(f"cannot read input file {str(path)!r}: {exc.strerror}") from None
    with fh:
        reader = csv.reader(fh)
        try:
            header = next(reader, None)
            if header is None:
                raise _error(f"input file {str(path)!r} is empty; it needs a header line and data rows")
            names = [h.strip() for h in header]
            dup = sorted({n for n in names if names.count(n) > 1})
            if dup:
                raise _error(f"column {dup[0]!r} appears more than once in the header of {str(path)!r}")
            time_names = [n for n in _TIME_NAMES if n in names]
            if not time_names:
                raise _error(f"input file {str(path)!r} has no 'time' column (seconds); add one")
            t_col = names.index(time_names[0])
            rows, time_text = [], []
            for row in reader:
                line = reader.line_num
                if not row or all(not f.strip() for f in row):
                    continue  # blank line
                if len(row) != len(names):
                    raise _error(f"line {line} of {str(path)!r} has {len(row)} fields but the header has "
                                 f"{len(names)}; fix the row")
                values = []
                for name, field in zip(names, row):
                    try:
                        v = float(field)
                    except ValueError:
                        raise _error(f"column {name!r} is not numeric at line {line} ({field.strip()!r}); "
                                     "fix: give numbers only (force in N, time in s)") from None
                    if not math.isfinite(v):
                        raise _error(f"column {name!r} has {field.strip()!r} at line {line}; fix: remove or "
                                     "interpolate the missing samples") from None
                    values.append(v)
                rows.append(values)
                time_text.append(row[t_col].strip())
        except UnicodeDecodeError:
            raise _error(f"input file {str(path)!r} is not UTF-8 text (a CSV file is needed)") from None
        except csv.Error as exc:
            raise _error(f"input file {str(path)!r} is not valid CSV at line {reader.line_num}: {exc}") from None
    if len(rows) < 2:
        raise _error(f"input file {str(path)!r} has {len(rows)} data rows; at least two are needed")
    return names, time_text, np.array(rows, dtype=float)


def _sampling_rate(t: np.ndarray, time_name: str) -> float:
    """Sampling rate (Hz) of a uniform time column; errors name the first off-grid line."""
    n = t.size
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise _error(f"column {time_name!r} does not increase at line {i + 2} (t = {t[i]:.9g} s after "
                     f"{t[i - 1]:.9g} s); fix: sort the rows and remove duplicates")
    dt = float(np.median(steps))
    off = np.flatnonzero(np.abs(steps - dt) > 0.01 * dt)  # 1 % of a step: rounding passes, gaps do not
    if off.size:
        i = int(off[0]) + 1
        raise _error(f"column {time_name!r} is not uniform at line {i + 2} (step {steps[i - 1]:.6g} s from "
                     f"t = {t[i - 1]:.9g} s, the file's step is {dt:.6g} s); fix: resample the file to a "
                     "uniform grid")
    dt = (t[-1] - t[0]) / (n - 1)
    return 1.0 / dt


def _split_columns(text: str, option: str) -> list[str]:
    cols = [c.strip() for c in text.split(",")]
    if not all(cols):
        raise _error(f"{option} {text!r} has an empty column name; give names separated by commas")
    return cols


def cmd_correct(args) -> int:
    """Run ``rigsim correct``; returns 0, raises ScenarioError (one sentence) for bad input."""
    from correction.actuator_file import read_actuator_file
    from correction.actuator_id import identify_actuator  # imports correction.identify lazily
    from correction.apply import correct
    from correction.filters import design_correction
    from scenarios.core.files import atomic_write_text

    if (args.actuator is None) == (args.identify is None):
        raise _error("give exactly one of --actuator ACT.toml and --identify DRIVE_COL,DISP_COL")
    ta = None
    if args.actuator is not None:
        try:
            ta = read_actuator_file(args.actuator)
        except ValueError as exc:
            raise _error(str(exc)) from None
    names, time_text, data = read_force_csv(args.input)
    time_name = next(n for n in _TIME_NAMES if n in names)
    fs = _sampling_rate(data[:, names.index(time_name)], time_name)

    id_cols = _split_columns(args.identify, "--identify") if args.identify is not None else []
    if args.identify is not None and len(id_cols) != 2:
        raise _error(f"--identify needs two columns DRIVE_COL,DISP_COL, got {args.identify!r}")
    if args.columns is not None:
        force_cols = _split_columns(args.columns, "--columns")
    else:
        force_cols = [n for n in names if n != time_name and n not in id_cols]
    for col in id_cols + force_cols:
        if col not in names:
            raise _error(f"column {col!r} is not in {str(args.input)!r}; its columns are {', '.join(names)}")
        if col == time_name:
            raise _error(f"column {col!r} is the time column and cannot be corrected or used to identify")
    if not force_cols:
        raise _error(f"{str(args.input)!r} has no force column to correct besides {time_name!r}")

    if ta is None:
        drive, disp = (data[:, names.index(c)] for c in id_cols)
        if np.std(drive) == 0 or np.std(disp) == 0:
            raise _error(f"--identify columns {id_cols[0]!r} and {id_cols[1]!r} must vary to identify T_a")
        try:
            ta = identify_actuator(drive, disp, fs)
        except ValueError as exc:
            raise _error(f"cannot identify T_a from {id_cols[0]!r} and {id_cols[1]!r}: {exc}") from None
        normalize = True  # an identified static gain is off by estimation error only
    else:
        normalize = bool(args.normalize_dc)
    try:
        filt = design_correction(ta, fs, args.lowpass, normalize_dc=normalize)
    except ValueError as exc:
        raise _error(str(exc).replace("pass normalize_dc=True", "pass --normalize-dc")) from None

    forces = data[:, [names.index(c) for c in force_cols]]
    corrected = correct(forces, filt, args.mode)
    settled = filt.transient_mask(forces.shape[0], args.mode)
    if args.transient == "drop" and not settled.any():
        head, tail = filt.transient_samples(args.mode)
        raise _error(f"the record ({forces.shape[0] / fs:.3g} s) is not longer than the correction's transients "
                     f"({head / fs:.3g} s at the start, {tail / fs:.3g} s at the end); fix: give a longer record "
                     "or pass --transient keep")
    rows = np.flatnonzero(settled) if args.transient == "drop" else np.arange(forces.shape[0])
    out_names = [time_name] + force_cols + (["settled"] if args.transient == "mark" else [])
    lines = [",".join(out_names)]
    for i in rows:
        fields = [time_text[i]] + [f"{v:.10g}" for v in corrected[i]]
        if args.transient == "mark":
            fields.append("1" if settled[i] else "0")
        lines.append(",".join(fields))
    atomic_write_text(args.out, "\n".join(lines) + "\n")
    print(f"corrected {len(force_cols)} column(s) of {str(args.input)!r} at {fs:.6g} Hz "
          f"(T_a {'identified' if args.identify else 'from ' + repr(str(args.actuator))}, low-pass "
          f"{filt.lowpass.description}, {args.mode}); {forces.shape[0] - int(settled.sum())} transient rows "
          f"{'dropped' if args.transient == 'drop' else 'kept'}; wrote {args.out}")
    return 0
