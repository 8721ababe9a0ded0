"""Reading measured channels of a rig test: time histories in a CSV file, their sampling rate.

The reader of measured data lives with the correction, which runs on real rig data without a
simulator: ``rigsim correct`` and ``rigsim identify --from-file`` read through it. Every problem
is one sentence naming the file, the column or the line, and the fix.
"""

from __future__ import annotations

import csv
import math

import numpy as np

__all__ = ["MeasuredDataError", "TIME_NAMES", "read_force_csv", "sampling_rate"]

#: Accepted names of the time column (seconds).
TIME_NAMES = ("time", "time_s")


class MeasuredDataError(ValueError):
    """A measured-data file that cannot be used as written; the message is one sentence."""


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
    MeasuredDataError
        Missing file, no header or data, duplicate or missing time column, a row with the wrong
        number of fields, a field that is not a number, NaN or infinity (naming column and line).
    """
    try:
        fh = open(path, newline="", encoding="utf-8")
    except FileNotFoundError:
        raise MeasuredDataError(f"input file {str(path)!r} does not exist") from None
    except OSError as exc:
        raise MeasuredDataError(f"cannot read input file {str(path)!r}: {exc.strerror}") from None
    with fh:
        reader = csv.reader(fh)
        try:
            header = next(reader, None)
            if header is None:
                raise MeasuredDataError(f"input file {str(path)!r} is empty; it needs a header line and data rows")
            names = [h.strip() for h in header]
            dup = sorted({n for n in names if names.count(n) > 1})
            if dup:
                raise MeasuredDataError(f"column {dup[0]!r} appears more than once in the header of {str(path)!r}")
            time_names = [n for n in TIME_NAMES if n in names]
            if not time_names:
                raise MeasuredDataError(f"input file {str(path)!r} has no 'time' column (seconds); add one")
            t_col = names.index(time_names[0])
            rows, time_text = [], []
            for row in reader:
                line = reader.line_num
                if not row or all(not f.strip() for f in row):
                    continue  # blank line
                if len(row) != len(names):
                    raise MeasuredDataError(f"line {line} of {str(path)!r} has {len(row)} fields but the header has "
                                 f"{len(names)}; fix the row")
                values = []
                for name, field in zip(names, row):
                    try:
                        v = float(field)
                    except ValueError:
                        raise MeasuredDataError(f"column {name!r} is not numeric at line {line} ({field.strip()!r}); "
                                     "fix: give numbers only (force in N, time in s)") from None
                    if not math.isfinite(v):
                        raise MeasuredDataError(f"column {name!r} has {field.strip()!r} at line {line}; fix: remove or "
                                     "interpolate the missing samples") from None
                    values.append(v)
                rows.append(values)
                time_text.append(row[t_col].strip())
        except UnicodeDecodeError:
            raise MeasuredDataError(f"input file {str(path)!r} is not UTF-8 text (a CSV file is needed)") from None
        except csv.Error as exc:
            raise MeasuredDataError(f"input file {str(path)!r} is not valid CSV at line {reader.line_num}: {exc}") from None
    if len(rows) < 2:
        raise MeasuredDataError(f"input file {str(path)!r} has {len(rows)} data rows; at least two are needed")
    return names, time_text, np.array(rows, dtype=float)


def sampling_rate(t: np.ndarray, time_name: str) -> float:
    """Sampling rate (Hz) of a uniform time column; errors name the first off-grid line."""
    n = t.size
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise MeasuredDataError(f"column {time_name!r} does not increase at line {i + 2} (t = {t[i]:.9g} s after "
                     f"{t[i - 1]:.9g} s); fix: sort the rows and remove duplicates")
    dt = float(np.median(steps))
    off = np.flatnonzero(np.abs(steps - dt) > 0.01 * dt)  # 1 % of a step: rounding passes, gaps do not
    if off.size:
        i = int(off[0]) + 1
        raise MeasuredDataError(f"column {time_name!r} is not uniform at line {i + 2} (step {steps[i - 1]:.6g} s from "
                     f"t = {t[i - 1]:.9g} s, the file's step is {dt:.6g} s); fix: resample the file to a "
                     "uniform grid")
    dt = (t[-1] - t[0]) / (n - 1)
    return 1.0 / dt
