"""What a lab's script passes to the records API, checked: values, paths, T_a, the record and its length.

:mod:`rigsim.scenarios.records.api` and :mod:`rigsim.scenarios.records.settings` take their arguments from a
script as well as from ``rigsim correct``'s parser: a value of the wrong type, NaN, infinite,
negative or huge, a path as ``bytes``, something else than a record. Each is refused here in one
:class:`~rigsim.scenarios.core.config.ScenarioError` sentence naming the argument (by its keyword, or the
command's flag: :class:`~rigsim.scenarios.records.naming.Naming`) and the fix, before any work:

* numbers and names: :func:`finite`, :func:`count`, :func:`flag`, :func:`checked_names`,
  :func:`checked_corner_map`, :func:`checked_pairs`, :func:`shown` (a value in a message);
* files and T_a: :func:`file_path` (``str``, ``bytes`` or ``os.PathLike``), :func:`ta_form`;
* the record: :func:`checked_record` (a MeasuredChannels, a unit for each channel);
* what the record's length allows: :func:`check_corner` (the low-pass's transients) and
  :func:`check_windows` (the calibration windows it holds side by side).

Imports nothing heavy at module level.
"""

from __future__ import annotations

import functools
import math
import numbers
from collections.abc import Mapping, Sequence

from rigsim.scenarios.records.naming import KEYWORDS, Naming

__all__ = ["refusal", "is_path", "shown", "finite", "count", "flag", "checked_names", "checked_corner_map", "checked_pairs", "file_path",
           "ta_form", "checked_record", "SETTLED_SHARE", "lowest_corner_hz", "check_corner", "check_windows"]


def refusal(message: str):
    """The :class:`~rigsim.scenarios.core.config.ScenarioError` of one sentence that refuses an option."""
    from rigsim.scenarios.core.config import ScenarioError

    return ScenarioError(message)


def is_path(value) -> bool:
    """Whether ``value`` names a file (``str``, ``bytes`` or ``os.PathLike``)."""
    import os

    return isinstance(value, (str, bytes, os.PathLike))


def shown(value) -> str:
    """``value`` for a message: its repr when a short number or text, "nothing" when an empty
    container, else its type's name."""
    if isinstance(value, (Sequence, Mapping)) and not isinstance(value, (str, bytes)) and not len(value):
        return "nothing"
    text = repr(value) if isinstance(value, (str, bytes, numbers.Number)) else ""
    return text if text and len(text) <= 40 and "\n" not in text else type(value).__name__


def finite(value) -> float | None:
    """``value`` as a finite float, or None when it is not a finite real number (a bool is not a number)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return None
    try:
        v = float(value)
    except OverflowError:  # an int beyond the float range
        return None
    return v if math.isfinite(v) else None


def count(naming: Naming, key: str, value, most: tuple[int, str] | None = None) -> int | None:
    """``value`` as a whole number >= 1 (an int, or a float without a fraction); None when not given.
    ``most``: (the largest allowed, why), e.g. ``(8, "4 per core; this machine has 2")``."""
    if value is None:
        return None
    whole = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    v = None if whole else finite(value)
    if not (whole or (v is not None and v.is_integer())) or value < 1:
        raise refusal(f"{naming(key)} must be a whole number >= 1, got {shown(value)}")
    if most is not None and value > most[0]:
        raise refusal(f"{naming(key)} must be a whole number from 1 to {most[0]} ({most[1]}), got {shown(value)}")
    return int(value)


def flag(naming: Naming, key: str, value) -> bool:
    """``value`` as a bool: True or False (numpy's too); anything else refused."""
    if not isinstance(value, bool):
        import numpy as np

        if not isinstance(value, np.bool_):
            raise refusal(f"{naming(key)} must be True or False, got {shown(value)}")
    return bool(value)


def _strs(values) -> bool:
    """True when ``values`` is a sequence (not a text) of str."""
    return (isinstance(values, Sequence) and not isinstance(values, (str, bytes))
            and all(isinstance(v, str) for v in values))


def checked_names(naming: Naming, key: str, value, form: str):
    """``value`` unchanged when None, a text or a sequence of channel names (str); else one sentence
    naming ``key`` and its ``form`` (``"'A,B' or a sequence of channel names"``)."""
    if value is None or isinstance(value, str) or (_strs(value) and len(value)):
        return value
    raise refusal(f"{naming(key)} must be {form}, got {shown(value)}")


def checked_corner_map(naming: Naming, value):
    """``corner_map`` unchanged when None, a text, a corner -> channel mapping or (corner, channel) pairs of str."""
    if value is None or isinstance(value, str):
        return value
    items = [tuple(i) for i in value.items()] if isinstance(value, Mapping) else value
    if isinstance(items, Sequence) and not isinstance(items, bytes) and len(items) and all(_strs(i) for i in items):
        return value
    raise refusal(f"{naming('corner_map')} must be 'fl=COLUMN,...', a mapping of corner -> channel or (corner, "
                 f"channel) pairs, got {shown(value)}")


def checked_pairs(pairs, naming: Naming = KEYWORDS):
    """``pairs`` unchanged when the text ``"fl=DRIVE:LVDT,..."`` or a mapping of corner -> channel names (str)."""
    if isinstance(pairs, str) or (isinstance(pairs, Mapping) and all(
            isinstance(c, str) and _strs(cols) for c, cols in pairs.items())):
        return pairs
    raise refusal(f"{naming('pairs')} must be 'fl=DRIVE:LVDT,...' or a mapping of corner -> (DRIVE, LVDT) channel "
                 f"names, got {shown(pairs)}")


def file_path(value, what: str) -> str:
    """A path argument (``str``, ``bytes`` or ``os.PathLike``) as text
    (:func:`rigsim.correction.io.tomlfile.path_text`), refused naming ``what``."""
    from rigsim.correction.io.tomlfile import path_text
    from rigsim.scenarios.core.config import ScenarioError

    return path_text(value, what, ScenarioError)


def ta_form(value, where: str):
    """``value`` when a T_a of a form the correction takes: ``(num, den)``, an ActuatorFit or a
    ``control.TransferFunction`` (:func:`rigsim.correction.output.filters.actuator_coefficients`); else one
    sentence naming ``where``."""
    from rigsim.correction.identification.actuator_result import ActuatorFit
    from rigsim.correction.output.filters import actuator_coefficients

    if not isinstance(value, ActuatorFit):
        try:
            actuator_coefficients(value)
        except ValueError as exc:
            raise refusal(f"{where}: {exc}, or an actuator file") from None
    return value


def checked_record(record):
    """``record`` when a :class:`~rigsim.correction.io.measured.MeasuredChannels` (whose own checks hold its
    time axis, rate and values as a reader's) with a unit for every channel; one sentence otherwise."""
    from rigsim.correction.io.measured import MeasuredChannels

    if not isinstance(record, MeasuredChannels):
        raise refusal(f"record must be a MeasuredChannels (read_record's, or make_channels') or a record file's path, "
                     f"got {shown(record)}")
    for name in record.data:
        if name not in record.units:
            raise refusal(f"record channel {name!r} has no unit in record.units; give it its SI unit ('N', 'm', or '' "
                         "for none)")
    return record


#: Least share of a record, 1, that the regularized low-pass's transients must leave settled: room
#: for T_a^-1's own transients (the actuator's, tenths of a second) and samples to correct.
SETTLED_SHARE = 0.1


@functools.lru_cache(maxsize=4)
def _transient_s_hz(mode: str) -> float:
    """Seconds times Hz of the regularized low-pass's transients in ``mode`` (start and end together):
    a Butterworth's transients scale as 1 / its corner, measured once at ``BAND_HZ`` sampled at
    40 times that (where the discrete filter is the continuous one)."""
    from rigsim.correction.output.filters import reference_filter
    from rigsim.correction.output.lowpass import BAND_HZ, regularized_lowpass

    filt = reference_filter(40.0 * BAND_HZ, regularized_lowpass(BAND_HZ))
    return sum(filt.transient_samples(mode)) / filt.fs * BAND_HZ


def lowest_corner_hz(record_s: float, mode: str) -> float:
    """The lowest corner (Hz) of the regularized low-pass whose transients in ``mode`` (``"zerophase"``:
    start and end, ``"causal"``: start) leave :data:`SETTLED_SHARE` of a record of ``record_s`` (s)
    settled, rounded up to 3 digits."""
    hz = _transient_s_hz(mode) / ((1.0 - SETTLED_SHARE) * record_s)
    step = 10.0 ** (math.floor(math.log10(hz)) - 2)
    return math.ceil(hz / step) * step


def check_corner(settings, record) -> None:
    """Refuse the settings' low-pass corner (``lowpass_hz``) whose transients leave less than
    :data:`SETTLED_SHARE` of ``record`` settled: at a lower corner no sample settles, and the
    zero-phase filter's padding grows as 1 / corner (121 GiB at 1e-6 Hz)."""
    hz = settings.lowpass_hz
    if hz is None:
        return
    record_s = record.n_samples / record.fs_hz
    lowest = lowest_corner_hz(record_s, settings.mode)
    if hz < lowest:
        opt = settings.naming("lowpass_hz")
        fix = (f"{opt} of at least {lowest:.3g} Hz, or a longer record" if lowest < record.fs_hz / 2 else
               f"a longer record (no corner below its Nyquist frequency, {record.fs_hz / 2:g} Hz, settles in it)")
        raise refusal(f"{opt} {hz:g} Hz: the low-pass's transients ({_transient_s_hz(settings.mode) / hz:.3g} s) "
                     f"leave less than {SETTLED_SHARE:.0%} of {str(record.path)!r} ({record_s:.3g} s) settled; give "
                     f"{fix}")


def check_windows(settings, record) -> None:
    """Refuse a model correction's ``calibration_windows`` that ``record`` cannot hold side by side (the
    windows of :func:`rigsim.scenarios.records.model.calibrate.fit_windows` whose fitted spans overlap fit the
    same samples twice, at the cost of another model run each)."""
    asked = settings.calibration_windows
    if settings.method != "model" or asked is None or asked == 1:
        return
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.records.model.calibrate import WINDOW_LEAD_S, WINDOW_S, fit_windows

    def holds(k: int) -> bool:
        spans = fit_windows(record.time_s, k, WINDOW_S, WINDOW_LEAD_S)
        return all(a[2] <= b[1] for a, b in zip(spans, spans[1:]))

    top = min(asked, record.n_samples)  # a window per sample at the most: fit_windows' arrays stay the record's size
    try:
        if top == asked and holds(top):
            return
    except ScenarioError:  # shorter than one window: the plan says so
        return
    lo, hi = 1, top if top == asked else top + 1  # holds(lo); not holds(hi), or hi is past the record's samples
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if holds(mid) else (lo, mid)
    opt = settings.naming("calibration_windows")
    raise refusal(f"{opt} {asked}: {str(record.path)!r} ({record.n_samples / record.fs_hz:.3g} s) holds {lo} "
                 f"calibration window(s) of {WINDOW_LEAD_S:g} s lead-in + {WINDOW_S:g} s side by side; give {opt} "
                 f"of at most {lo}")
