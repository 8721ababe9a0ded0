"""T_a per corner from a recorded file of a real rig: the drive and the LVDT channel of each post.

No simulator: the file is read by :func:`rigsim.scenarios.records.channels.read_record` (any CSV dialect,
RPC III, MDF4, TDMS; only the channels the pairs name: :func:`identify_recorded`), each channel in SI
(an LVDT in mm is fitted in m), and each pair of the record (:func:`identify_pairs`) is fitted
by :func:`rigsim.correction.identification.actuator_fit.fit_actuator` (single-input H1, the project's
one fitting policy). For a clean identification the posts should
be driven by independent random drives; a test drive (front and rear the same profile delayed)
lets each estimate absorb what the other posts do.

A pair wired wrongly is refused before anything is written, in one sentence naming the corner,
the likely cause and the fix: the same channel twice at once (:func:`parse_pairs`,
:func:`pairs_of`, and by the channels the names resolve to), then per corner what its data show
(:mod:`rigsim.correction.identification.plausibility`: swapped, inverted, another unit, another post's
LVDT); an LVDT that follows another corner's drive of ``pairs`` better than its own is named.
"""

from __future__ import annotations

import pathlib
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rigsim.correction.identification.actuator_fit import COHERENCE_BAND_HZ, ActuatorFitError, coherence_median, fit_actuator
from rigsim.correction.identification.actuator_fit_rules import TRUSTED_COHERENCE
from rigsim.correction.identification.plausibility import WiringError
from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.records.channels import read_record, resolver
from rigsim.scenarios.records.naming import KEYWORDS, Naming

__all__ = ["RecordedIdentification", "check_pair_channels", "parse_pairs", "pairs_of", "identify_pairs",
           "identify_recorded"]


@dataclass(frozen=True)
class RecordedIdentification:
    """T_a per corner fitted from a recorded file.

    Attributes
    ----------
    source : str
        The file.
    pairs : Mapping[str, tuple[str, str]]
        Per corner the (drive, LVDT) column names.
    fits : Mapping[str, rigsim.correction.identification.actuator_result.ActuatorFit]
    fs_hz : float, Hz
    record_s : float, s
    lvdt_filter : rigsim.correction.io.acquisition.ChannelFilter or None
        The LVDT channels' anti-alias filter and delay, undone before the fit (None: as recorded).

    Examples
    --------
    What :func:`~rigsim.scenarios.records.identify_record` returns, written as the per-corner actuator
    file that ``actuators=`` of :func:`~rigsim.scenarios.records.correct_record` reads:

    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> from scipy import signal
    >>> from rigsim.correction.io.actuator_file import read_actuators_file, write_actuators_file
    >>> from rigsim.correction.io.measured import MeasuredChannels
    >>> from rigsim import identify_record
    >>> t = np.arange(30_000) / 500.0
    >>> drive = 2e-3 * np.random.default_rng(1).standard_normal(t.size)
    >>> w = 2 * np.pi * 15.0
    >>> lvdt = signal.lsim(([w * w], [1.0, 1.4 * w, w * w]), drive, t)[1]
    >>> record = MeasuredChannels(time_s=t, data={"Soll_FL": drive, "Weg_FL": lvdt},
    ...                           units={"Soll_FL": "m", "Weg_FL": "m"},
    ...                           source_units={"Soll_FL": "m", "Weg_FL": "m"}, fs_hz=500.0,
    ...                           metadata={}, path="", format="csv")
    >>> found = identify_record(record, pairs={"fl": ("Soll_FL", "Weg_FL")})
    >>> list(found.fits), found.fs_hz, found.record_s
    (['fl'], 500.0, 60.0)
    >>> acts = pathlib.Path(tempfile.mkdtemp()) / "actuators.toml"
    >>> write_actuators_file(acts, found.fits, found.meta())
    >>> list(read_actuators_file(acts))
    ['fl']
    """

    source: str
    pairs: Mapping
    fits: Mapping
    fs_hz: float
    record_s: float
    lvdt_filter: object = None

    def actuators(self) -> tuple:
        return tuple(f.as_tf() for f in self.fits.values())

    def meta(self) -> dict:
        meta = {"source": f"rigsim identify --from-file {self.source}", "fs_hz": self.fs_hz,
                "record_s": self.record_s, "pairs": {c: f"{d}:{x}" for c, (d, x) in self.pairs.items()}}
        if self.lvdt_filter is not None:
            from rigsim.scenarios.records.timing import describe

            meta["lvdt_timing"] = f"{describe(self.lvdt_filter)}: phase and delay undone before the fit"
        return meta

    def to_dict(self) -> dict:
        return {**self.meta(), "corners": {c: f.to_dict() for c, f in self.fits.items()}}


def check_pair_channels(corner: str, drive: str, lvdt: str, naming: Naming = KEYWORDS) -> None:
    """Refuse ``corner``'s pair when it names one channel as both its drive and its LVDT, by name or
    by case (the readers match a name to a channel regardless of case); one sentence naming ``pairs``
    as ``naming`` says."""
    if drive.lower() == lvdt.lower():
        raise ScenarioError(f"{naming('pairs')} {corner}: channel {drive!r} is both the drive and the LVDT (the same "
                            f"channel twice); give {corner}=DRIVE:LVDT, the post's drive and its LVDT (pan "
                            "displacement)")


def parse_pairs(text: str, naming: Naming = KEYWORDS) -> dict[str, tuple[str, str]]:
    """``"fl=DRIVE:LVDT,fr=..."`` -> ``{"fl": ("DRIVE", "LVDT"), ...}``; one-sentence errors (a corner
    given twice, a channel given as both drive and LVDT)."""
    out: dict[str, tuple[str, str]] = {}
    for item in (p.strip() for p in text.split(",")):
        corner, sep, cols = item.partition("=")
        drive, sep2, lvdt = cols.partition(":")
        if not (sep and sep2 and corner.strip() and drive.strip() and lvdt.strip()):
            raise ScenarioError(f"{naming('pairs')} entry {item!r} must read CORNER=DRIVE_COL:LVDT_COL, e.g. "
                                "fl=drive_fl:lvdt_fl")
        corner = corner.strip()
        if corner in out:
            raise ScenarioError(f"{naming('pairs')} names corner {corner!r} twice; give each corner once")
        check_pair_channels(corner, drive.strip(), lvdt.strip(), naming)
        out[corner] = (drive.strip(), lvdt.strip())
    return out


def pairs_of(pairs, naming: Naming = KEYWORDS) -> dict[str, tuple[str, str]]:
    """``pairs`` as ``{corner: (drive, LVDT)}``: the text ``"fl=DRIVE:LVDT,..."`` (:func:`parse_pairs`)
    or a mapping of corner -> (drive, LVDT) channel names."""
    if isinstance(pairs, str):
        return parse_pairs(pairs, naming)
    out = {}
    for corner, cols in dict(pairs).items():
        if isinstance(cols, str) or len(cols) != 2 or not all(str(c).strip() for c in cols):
            raise ScenarioError(f"{naming('pairs')} gives corner {corner!r} {cols!r}; give (DRIVE_COL, LVDT_COL)")
        check_pair_channels(str(corner), str(cols[0]).strip(), str(cols[1]).strip(), naming)
        out[str(corner)] = (str(cols[0]).strip(), str(cols[1]).strip())
    return out


def identify_pairs(record, *, pairs, naming: Naming = KEYWORDS, as_read=None,
                   lvdt_filter=None) -> RecordedIdentification:
    """Fit T_a for each corner's (drive, LVDT) pair of channels of a record.

    Parameters
    ----------
    record : rigsim.correction.io.measured.MeasuredChannels
        The record (:func:`rigsim.scenarios.records.api.read_record`); drive and LVDT channels are
        lengths in m (a file's mm are read as m) or carry no unit (taken as m).
    pairs : Mapping[str, tuple[str, str]] or str
        Per corner the drive and LVDT channel names, ``{"fl": ("Soll_FL", "Weg_FL"), ...}`` or
        ``"fl=Soll_FL:Weg_FL,..."``; a name may differ from the record's by case.
    naming : Naming
        How messages name ``pairs`` (a command passes its flag).
    as_read : Mapping[str, str], optional
        Channel name as given -> as the reader returned it (it may match a header as written).
    lvdt_filter : rigsim.correction.io.acquisition.ChannelFilter or str, optional
        The LVDT channels' anti-alias filter and delay as the lab's acquisition applied them
        (``"150:4"``: :func:`rigsim.correction.io.acquisition.parse_channel_filter`): taken out before
        the fit, so that T_a is the actuator's and not the actuator's times the LVDT filter's.

    Returns
    -------
    RecordedIdentification

    Raises
    ------
    ScenarioError
        A channel, unit or pair problem, a record that cannot support a fit, or a pair whose data
        are not an actuator's drive and LVDT (one sentence naming the corner, the cause and the fix).
    """
    from rigsim.correction.io.acquisition import undo_timing
    from rigsim.scenarios.records.timing import check_rate, check_timing

    opt, name = naming("pairs"), resolver(record, as_read)
    lvdt_filter = check_timing(lvdt_filter, "lvdt_filter", naming)
    check_rate(lvdt_filter, "lvdt_filter", record.fs_hz, naming)
    pairs = {corner: (name(d), name(x)) for corner, (d, x) in pairs_of(pairs, naming).items()}
    for corner, (d, x) in pairs.items():  # every pair's channels before any fit
        check_pair_channels(corner, d, x, naming)
        for col in (d, x):
            if col not in record.data:
                raise ScenarioError(f"{opt} {corner}: channel {col!r} is not in {str(record.path)!r}; its channels "
                                    f"are {', '.join(record.names)}")
            if record.units[col] not in ("m", ""):
                raise ScenarioError(f"{opt} {corner}: channel {col!r} is in {record.source_units[col]}, not a length; "
                                    "give the drive and the LVDT (pan displacement) channels, in m or mm")
        if np.std(record.data[d]) == 0 or np.std(record.data[x]) == 0:
            raise ScenarioError(f"{opt} {corner}: columns {d!r} and {x!r} must vary to identify T_a")
    fits = {}
    for corner, (d, x) in pairs.items():
        drive, lvdt = record.data[d], record.data[x]
        if lvdt_filter is not None and np.all(np.isfinite(lvdt)):
            lvdt = undo_timing(lvdt, record.fs_hz, lvdt_filter)
        try:
            fits[corner] = fit_actuator(drive, lvdt, record.fs_hz)
        except ActuatorFitError as exc:
            raise ScenarioError(_refusal(record, pairs, corner, exc, opt)) from None
    return RecordedIdentification(source=str(pathlib.Path(record.path)), pairs=pairs, fits=fits,
                                  fs_hz=float(record.fs_hz), record_s=float(record.n_samples / record.fs_hz),
                                  lvdt_filter=lvdt_filter)


def _refusal(record, pairs, corner: str, exc: ActuatorFitError, opt: str) -> str:
    """The sentence refusing ``corner``'s pair: the fit's, with the fix in the pair's own channel names;
    another corner's drive of ``pairs`` that the LVDT follows (median coherence at least the trusted
    one, above its own drive's) named as the wrong corner."""
    d, x = pairs[corner]
    cause = exc.cause if isinstance(exc, WiringError) else None
    if cause in (None, "wrong corner"):
        lvdt, fs = record.data[x], record.fs_hz
        others = {c: coherence_median(record.data[d2], lvdt, fs) for c, (d2, _) in pairs.items()
                  if d2 not in (d, x) and np.all(np.isfinite(record.data[d2]))}
        if others:
            best = max(others, key=others.get)
            own = coherence_median(record.data[d], lvdt, fs)
            if others[best] >= TRUSTED_COHERENCE and others[best] > own:
                band = f"{COHERENCE_BAND_HZ[0]:g}-{COHERENCE_BAND_HZ[1]:g} Hz"
                return (f"{opt} {corner}: LVDT {x!r} follows {best}'s drive {pairs[best][0]!r} (median coherence "
                        f"{others[best]:.2f} in {band}), not {d!r} ({own:.2f}): the wrong corner; give {corner} the "
                        f"LVDT of its own post, {corner}={d}:LVDT")
    if cause == "swapped":
        return f"{opt} {corner}: {exc.finding}; give {corner}={x}:{d}"
    return f"{opt} {corner}: {exc}"


def identify_recorded(path, pairs, time_col: str | None = None, *, decimal: str | None = None,
                      thousands: str | None = None, naming: Naming = KEYWORDS,
                      lvdt_filter=None) -> RecordedIdentification:
    """Fit T_a for each corner's pair of the recorded file ``path``, reading only the pairs' channels.

    Parameters
    ----------
    path : str or os.PathLike
        Any file :func:`rigsim.correction.io.measured.read_channels` reads.
    pairs : str or Mapping[str, tuple[str, str]]
        ``"fl=DRIVE:LVDT,fr=..."`` or ``{"fl": (DRIVE, LVDT), ...}``, channel names as the reader
        returns them (``Weg_FL`` for a header ``Weg_FL [mm]``).
    time_col : str, optional
        The time column (default: the one with a time name).
    decimal, thousands : str, optional
        A text file's decimal mark and thousands separator (``read_channels``); default: detected.
    naming : Naming
        How messages name ``pairs`` (a command passes its flag).
    lvdt_filter : rigsim.correction.io.acquisition.ChannelFilter or str, optional
        As :func:`identify_pairs`'s.

    Raises
    ------
    ScenarioError
        A file, channel, unit or pair problem, or a record that cannot support a fit (one sentence).
    """
    pairs = pairs_of(pairs, naming)
    wanted = list(dict.fromkeys(c for cols in pairs.values() for c in cols))
    mc = read_record(path, time_col=time_col, channels=wanted, decimal=decimal, thousands=thousands)
    return identify_pairs(mc, pairs=pairs, naming=naming, as_read=dict(zip(wanted, mc.names)),
                          lvdt_filter=lvdt_filter)
