"""T_a per corner from a recorded file of a real rig: the drive and the LVDT channel of each post.

No simulator: the file is read by :func:`correction.io.measured.read_channels` (any CSV dialect, RPC
III, MDF4, TDMS; only the channels the pairs name), each channel converted to SI (an LVDT in mm
is fitted in m), and each pair is fitted by :func:`correction.identification.actuator_fit.fit_actuator`
(single-input H1, the project's one fitting policy). For a clean identification the posts should
be driven by independent random drives; a test drive (front and rear the same profile delayed)
lets each estimate absorb what the other posts do.
"""

from __future__ import annotations

import pathlib
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from correction.identification.actuator_fit import ActuatorFitError, fit_actuator
from correction.io.measured import MeasuredDataError, read_channels
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
    fits : Mapping[str, correction.identification.actuator_fit.ActuatorFit]
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


def identify_recorded(path, pairs_text: str, time_col: str | None = None, *, decimal: str | None = None,
                      thousands: str | None = None) -> RecordedIdentification:
    """Fit T_a for each ``corner=DRIVE:LVDT`` pair of the recorded file ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        Any file :func:`correction.io.measured.read_channels` reads; drive and LVDT channels are
        lengths (m, mm...; converted to m) or carry no unit (taken as m).
    pairs_text : str
        ``"fl=DRIVE:LVDT,fr=..."``, channel names as the reader returns them (``Weg_FL`` for a
        header ``Weg_FL [mm]``).
    time_col : str, optional
        The time column (default: the one with a time name).
    decimal, thousands : str, optional
        A text file's decimal mark and thousands separator (``read_channels``); default: detected.

    Raises
    ------
    ScenarioError
        A file, channel, unit or pair problem, or a record that cannot support a fit (one sentence).
    """
    pairs = parse_pairs(pairs_text)
    wanted = list(dict.fromkeys(c for cols in pairs.values() for c in cols))
    try:
        mc = read_channels(path, time_col=time_col, channels=wanted, decimal=decimal, thousands=thousands)
    except MeasuredDataError as exc:
        raise ScenarioError(str(exc)) from None
    name = dict(zip(wanted, mc.names))  # as asked -> as read (a CSV header may match by case)
    pairs = {corner: (name[d], name[x]) for corner, (d, x) in pairs.items()}
    fits = {}
    for corner, (d, x) in pairs.items():
        for col in (d, x):
            if mc.units[col] not in ("m", ""):
                raise ScenarioError(f"--pairs {corner}: channel {col!r} is in {mc.source_units[col]}, not a length; "
                                    "give the drive and the LVDT (pan displacement) channels, in m or mm")
        drive, lvdt = mc.data[d], mc.data[x]
        if np.std(drive) == 0 or np.std(lvdt) == 0:
            raise ScenarioError(f"--pairs {corner}: columns {d!r} and {x!r} must vary to identify T_a")
        try:
            fits[corner] = fit_actuator(drive, lvdt, mc.fs_hz)
        except ActuatorFitError as exc:
            raise ScenarioError(f"--pairs {corner}: {exc}") from None
    return RecordedIdentification(source=str(pathlib.Path(path)), pairs=pairs, fits=fits, fs_hz=float(mc.fs_hz),
                                  record_s=float(mc.n_samples / mc.fs_hz))
