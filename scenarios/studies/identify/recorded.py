"""T_a per corner from a recorded file of a real rig: the drive and the LVDT channel of each post.

No simulator: the file is read by :mod:`correction.measured` and each pair is fitted by
:func:`correction.actuator_fit.fit_actuator` (single-input H1, the project's one fitting policy).
For a clean identification the posts should be driven by independent random drives; a test drive
(front and rear the same profile delayed) lets each estimate absorb what the other posts do.
"""

from __future__ import annotations

import pathlib
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from correction.actuator_fit import ActuatorFitError, fit_actuator
from correction.measured import TIME_NAMES, MeasuredDataError, read_force_csv, sampling_rate
from scenarios.core.config import ScenarioError

__all__ = ["RecordedIdentification", "parse_pairs", "identify_recorded"]


@dataclass(frozen=True)
class RecordedIdentification:
    """T_a per corner fitted from a recorded file.

    Attributes
    ----------
    source : str
        The file.
    pairs : Mapping[str, tuple[str, str]]
        Per corner the (drive, LVDT) column names.
    fits : Mapping[str, correction.actuator_fit.ActuatorFit]
    fs_hz : float, Hz
    record_s : float, s
    """

    source: str
    pairs: Mapping
    fits: Mapping
    fs_hz: float
    record_s: float

    def actuators(self) -> tuple:
        return tuple(f.as_tf() for f in self.fits.values())

    def meta(self) -> dict:
        return {"source": f"rigsim identify --from-file {self.source}", "fs_hz": self.fs_hz,
                "record_s": self.record_s, "pairs": {c: f"{d}:{x}" for c, (d, x) in self.pairs.items()}}

    def to_dict(self) -> dict:
        return {**self.meta(), "corners": {c: f.to_dict() for c, f in self.fits.items()}}


def parse_pairs(text: str) -> dict[str, tuple[str, str]]:
    """``"fl=DRIVE:LVDT,fr=..."`` -> ``{"fl": ("DRIVE", "LVDT"), ...}``; one-sentence errors."""
    out: dict[str, tuple[str, str]] = {}
    for item in (p.strip() for p in text.split(",")):
        corner, sep, cols = item.partition("=")
        drive, sep2, lvdt = cols.partition(":")
        if not (sep and sep2 and corner.strip() and drive.strip() and lvdt.strip()):
            raise ScenarioError(f"--pairs entry {item!r} must read CORNER=DRIVE_COL:LVDT_COL, e.g. fl=drive_fl:lvdt_fl")
        corner = corner.strip()
        if corner in out:
            raise ScenarioError(f"--pairs names corner {corner!r} twice; give each corner once")
        out[corner] = (drive.strip(), lvdt.strip())
    return out


def identify_recorded(path, pairs_text: str) -> RecordedIdentification:
    """Fit T_a for each ``corner=DRIVE:LVDT`` pair of the recorded CSV file ``path`` (columns in m).

    Raises
    ------
    ScenarioError
        A file, column or pair problem, or a record that cannot support a fit (one sentence).
    """
    pairs = parse_pairs(pairs_text)
    try:
        names, _, data = read_force_csv(path)
        time_name = next(n for n in TIME_NAMES if n in names)
        fs = sampling_rate(data[:, names.index(time_name)], time_name)
    except MeasuredDataError as exc:
        raise ScenarioError(str(exc)) from None
    for corner, cols in pairs.items():
        for col in cols:
            if col not in names:
                raise ScenarioError(f"--pairs {corner}: column {col!r} is not in {str(path)!r}; "
                                    f"its columns are {', '.join(names)}")
    fits = {}
    for corner, (d, x) in pairs.items():
        drive, lvdt = data[:, names.index(d)], data[:, names.index(x)]
        if np.std(drive) == 0 or np.std(lvdt) == 0:
            raise ScenarioError(f"--pairs {corner}: columns {d!r} and {x!r} must vary to identify T_a")
        try:
            fits[corner] = fit_actuator(drive, lvdt, fs)
        except ActuatorFitError as exc:
            raise ScenarioError(f"--pairs {corner}: {exc}") from None
    return RecordedIdentification(source=str(pathlib.Path(path)), pairs=pairs, fits=fits, fs_hz=float(fs),
                                  record_s=float(data.shape[0] / fs))
