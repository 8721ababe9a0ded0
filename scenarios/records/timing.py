"""The record's channel timing: the lab's anti-alias filters and converter skew, given, checked and undone.

A lab that knows its conditioners says so (``force_filter`` / ``lvdt_filter``: a
:class:`rigsim.correction.io.acquisition.ChannelFilter` or its text ``"HZ[:ORDER[:KIND][:DOMAIN]]"``;
``rigsim correct --force-filter 200:4 --force-delay 0.0002 --lvdt-filter 150:4``), and the
correction takes each filter's phase and delay out of the force and the LVDT channels before
anything else (:func:`aligned_record`): the force then no longer leads or lags the pan's motion,
which to a calibrated truck model would look like tire damping, and the corrected force is
aligned with the road it describes. The drive is the controller's own command and is never
filtered. Refusals name the option (:class:`~rigsim.scenarios.records.naming.Naming`). Imports nothing heavy.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from rigsim.scenarios.records.naming import KEYWORDS, Naming

__all__ = ["check_timing", "channel_filter", "check_rate", "check_rates", "aligned_record", "lvdt_columns", "describe",
           "timing_metadata"]


def _error(message: str):
    from rigsim.scenarios.core.config import ScenarioError

    return ScenarioError(message)


def channel_filter(spec, delay_s=None, *, option: str, delay_option: str | None = None):
    """A :class:`~rigsim.correction.io.acquisition.ChannelFilter` from a command's options: the filter's
    text ``spec`` (None: no filter) and a delay in s (None: 0); None when neither is given."""
    from rigsim.correction.io.acquisition import ChannelFilter, parse_channel_filter

    if spec is None and delay_s is None:
        return None
    try:
        if spec is None:
            return ChannelFilter(None, delay_s=float(delay_s))
        return parse_channel_filter(spec, 0.0 if delay_s is None else float(delay_s), option=option)
    except ValueError as exc:
        text = str(exc)
        if spec is None or "delay" in text:
            text = f"{delay_option or option} {delay_s!r}: {text}"
        raise _error(text) from None


def check_timing(value, key: str, naming: Naming = KEYWORDS):
    """``value`` (a ChannelFilter, its text, or None) as a ChannelFilter or None; one sentence naming ``key``."""
    from rigsim.correction.io.acquisition import ChannelFilter, parse_channel_filter

    if value is None or isinstance(value, ChannelFilter):
        return value
    if not isinstance(value, str):
        raise _error(f"{naming(key)} must be a ChannelFilter or its text HZ[:ORDER[:KIND][:DOMAIN]], got "
                     f"{type(value).__name__}")
    try:
        return parse_channel_filter(value, option=naming(key))
    except ValueError as exc:
        raise _error(str(exc)) from None


def describe(channel) -> str:
    """``channel`` in words: ``"4th-order digital butterworth at 200 Hz, 0.2 ms delay"``."""
    parts = []
    if channel.corner_hz is not None:
        suffix = {1: "st", 2: "nd", 3: "rd"}.get(int(channel.order), "th")
        parts.append(f"{channel.order}{suffix}-order {channel.domain} {channel.kind} at {channel.corner_hz:g} Hz")
    if channel.delay_s:
        parts.append(f"{1e3 * channel.delay_s:g} ms delay")
    return ", ".join(parts) or "none"


def timing_metadata(force_filter, lvdt_filter) -> dict[str, str]:
    """The output file's ``channel_timing`` key where a timing was given (else nothing)."""
    if force_filter is None and lvdt_filter is None:
        return {}
    said = [f"{what} {describe(ch)}" for what, ch in (("force", force_filter), ("LVDT", lvdt_filter))
            if ch is not None]
    return {"channel_timing": "; ".join(said) + ": phase and delay undone before correcting"}


def check_rate(channel, key: str, fs_hz: float, naming: Naming = KEYWORDS) -> None:
    """Refuse ``channel`` (a ChannelFilter or None), given as ``key``, whose corner is not below half
    the record's rate ``fs_hz`` (Hz): one sentence naming the option."""
    if channel is not None:
        try:
            channel.check_rate(fs_hz)
        except ValueError as exc:
            raise _error(f"{naming(key)}: {exc}") from None


def check_rates(settings, fs_hz: float) -> None:
    """:func:`check_rate` of both of ``settings``' channel filters (force and LVDT)."""
    for key in ("force_filter", "lvdt_filter"):
        check_rate(getattr(settings, key), key, fs_hz, settings.naming)


def aligned_record(record, fs_hz: float, groups: Sequence[tuple[Sequence[str], object]]):
    """``record`` with each group's channels' timing undone (their corners checked already:
    :func:`check_rates`).

    Parameters
    ----------
    record : rigsim.correction.io.measured.MeasuredChannels
    fs_hz : float, Hz
        Its rate.
    groups : sequence of (channel names, ChannelFilter or None)
        The channels each filter describes (None: left as recorded).

    Returns
    -------
    MeasuredChannels
        The same record (the same object where no group has a filter); channels with non-finite
        values are left as they are for the correction's own check to refuse.
    """
    import dataclasses
    from types import MappingProxyType

    import numpy as np

    from rigsim.correction.io.acquisition import undo_timing

    data = dict(record.data)
    changed = False
    for names, channel in groups:
        if channel is None or channel.none:
            continue
        for name in dict.fromkeys(names):
            x = np.asarray(data[name], dtype=float)
            if np.all(np.isfinite(x)):
                y = undo_timing(x, fs_hz, channel)
                y.setflags(write=False)
                data[name], changed = y, True
    return dataclasses.replace(record, data=MappingProxyType(data)) if changed else record


def lvdt_columns(pairs: Mapping | None, id_cols: Sequence[str]) -> list[str]:
    """The LVDT channels of a correction: each pair's second, or the identification's displacement."""
    if pairs:
        return [x for _, x in pairs.values()]
    return list(id_cols[1:2])
