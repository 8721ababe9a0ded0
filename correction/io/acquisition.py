"""What a lab's acquisition does to a channel's timing: its anti-alias filter and its delay, and how to undo them.

A rig record's channels are not sampled alike: each passes its own anti-alias filter (the load
cell's bridge amplifier, the LVDT's demodulator) and the converter may sample them one after the
other. A 4th-order Butterworth at 200 Hz delays a 10 Hz wheel force by about 2 ms, one at 150 Hz
the LVDT by about 2.8 ms: the force then leads the pan's motion by a fraction of a millisecond,
which to a truck model fitted between the two looks like tire damping. A lab knows its filters
(the conditioner's data sheet, the DAQ's settings); :class:`ChannelFilter` describes one channel's,
:meth:`ChannelFilter.apply` does to a signal what the acquisition did (the simulated lab) and
:func:`undo_timing` takes the filter's phase and the delay back out of a record, leaving the
filter's magnitude (within 0.01 % of 1 below a tenth of the corner) so that every channel is
aligned with the instant it was measured.

``analog`` filters are the conditioner's (continuous time, the response of the analog prototype
at each frequency); ``digital`` ones are a DAQ's decimation filter designed at the record's rate
(``scipy.signal.butter``/``bessel`` with ``fs``, applied by ``sosfilt`` from rest at the first
sample). Frequencies in Hz, times in s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rigsim.correction.output.spectral import through_gain

__all__ = ["KINDS", "DOMAINS", "MIN_CORNER_HZ", "ChannelFilter", "parse_channel_filter", "undo_timing"]

KINDS = ("butterworth", "bessel")
DOMAINS = ("analog", "digital")
#: Lowest corner of a channel filter, Hz: an anti-alias filter sits between the band a rig test
#: measures (its wheel forces and pan motions reach tens of Hz) and half the sampling rate. A
#: corner far below it leaves nothing of the record, and its phase is lost to round-off (at
#: 1e-300 Hz the response underflows to 0 and no phase is undone at all).
MIN_CORNER_HZ = 1.0
#: The corners a channel filter may have, in words.
CORNER_RANGE = f"from {MIN_CORNER_HZ:g} Hz to below half the record's rate"
#: Most delay a channel is given, s: a multiplexer's or conditioner's skew is below a millisecond;
#: 10 ms is a misconfigured channel.
MAX_DELAY_S = 0.01
#: Seconds of odd reflection padded to each end of a record before its timing is undone in the
#: frequency domain: the filters' responses (a few ms) end well inside it.
PAD_S = 0.5


@dataclass(frozen=True)
class ChannelFilter:
    """One measured channel's anti-alias filter and delay.

    Parameters
    ----------
    corner_hz : float, Hz, optional
        The filter's -3 dB corner (``None``: no filter, the delay only), :data:`MIN_CORNER_HZ` or
        more (and below half the rate of the record it describes: :meth:`check_rate`).
    order : int
        The filter's order, 1 to 8.
    kind : {"butterworth", "bessel"}
        Its family (a Bessel's corner is its -3 dB frequency, ``norm="mag"``).
    domain : {"analog", "digital"}
        An analog conditioner's filter, or a digital one designed at the record's rate.
    delay_s : float, s
        The channel's delay beyond the filter (a multiplexed converter's skew), 0 to 10 ms.

    Examples
    --------
    A 4th-order Butterworth anti-alias filter at 200 Hz and a 0.2 ms converter skew, as given to
    ``force_filter`` of :func:`~rigsim.scenarios.records.correct_record` (or as the text ``"200:4"``
    with the delay apart):

    >>> import numpy as np
    >>> from rigsim.correction.io.acquisition import ChannelFilter
    >>> acq = ChannelFilter(200.0, 4, delay_s=2e-4)
    >>> print(f"{abs(acq.response([200.0], 2000.0)[0]):.3f}")
    0.707
    >>> acq.none, ChannelFilter().none
    (False, True)
    """

    corner_hz: float | None = None
    order: int = 4
    kind: str = "butterworth"
    domain: str = "analog"
    delay_s: float = 0.0

    def __post_init__(self) -> None:
        if self.corner_hz is not None and (isinstance(self.corner_hz, bool)
                                           or not isinstance(self.corner_hz, (int, float))
                                           or not math.isfinite(self.corner_hz) or self.corner_hz < MIN_CORNER_HZ):
            raise ValueError(f"the channel filter's corner must be a number of Hz {CORNER_RANGE}, got "
                             f"{self.corner_hz!r}")
        if isinstance(self.order, bool) or not isinstance(self.order, (int, np.integer)) or not 1 <= self.order <= 8:
            raise ValueError(f"the channel filter's order must be an integer from 1 to 8, got {self.order!r}")
        if self.kind not in KINDS:
            raise ValueError(f"the channel filter's kind must be one of {', '.join(KINDS)}, got {self.kind!r}")
        if self.domain not in DOMAINS:
            raise ValueError(f"the channel filter's domain must be one of {', '.join(DOMAINS)}, got {self.domain!r}")
        if (isinstance(self.delay_s, bool) or not isinstance(self.delay_s, (int, float))
                or not math.isfinite(self.delay_s) or not 0 <= self.delay_s <= MAX_DELAY_S):
            raise ValueError(f"the channel's delay must be 0 to {MAX_DELAY_S:g} s (a converter's skew is below 1 ms), "
                             f"got {self.delay_s!r}")

    @property
    def none(self) -> bool:
        """True when the channel is neither filtered nor delayed."""
        return self.corner_hz is None and self.delay_s == 0

    def check_rate(self, fs_hz: float) -> None:
        """Refuse a corner at or above half the rate ``fs_hz`` (Hz) of the record it describes."""
        if self.corner_hz is not None and self.corner_hz >= 0.5 * fs_hz:
            raise ValueError(f"the channel filter's corner {self.corner_hz:g} Hz must lie {CORNER_RANGE} "
                             f"({0.5 * fs_hz:g} Hz): an anti-alias filter sits below the Nyquist frequency")

    def _design(self, fs_hz: float | None, output: str):
        from scipy import signal

        kw = {"output": output}
        if self.domain == "digital":
            kw["fs"] = fs_hz
            wn = self.corner_hz
        else:
            kw["analog"] = True
            wn = 2.0 * math.pi * self.corner_hz
        if self.kind == "bessel":
            return signal.bessel(int(self.order), wn, norm="mag", **kw)
        return signal.butter(int(self.order), wn, **kw)

    def sos(self, fs_hz: float) -> np.ndarray:
        """The digital filter's second-order sections at ``fs_hz`` (Hz) (a ``digital`` filter only)."""
        if self.domain != "digital" or self.corner_hz is None:
            raise ValueError("only a digital channel filter with a corner has second-order sections")
        self.check_rate(fs_hz)
        return self._design(fs_hz, "sos")

    def response(self, f_hz, fs_hz: float) -> np.ndarray:
        """The channel's complex response (1) at ``f_hz`` (Hz) in a record at ``fs_hz`` (Hz): filter and delay."""
        f = np.asarray(f_hz, dtype=float)
        h = np.exp(-2j * math.pi * f * self.delay_s)
        return h if self.corner_hz is None else h * self._filter_response(f, fs_hz)

    def _filter_response(self, f: np.ndarray, fs_hz: float) -> np.ndarray:
        """The filter's complex response alone (no delay) at ``f`` (Hz); a filter with a corner."""
        from scipy import signal

        if self.domain == "digital":
            return signal.sosfreqz(self.sos(fs_hz), worN=f, fs=fs_hz)[1]
        self.check_rate(fs_hz)
        b, a = self._design(None, "ba")
        return signal.freqs(b, a, worN=2.0 * math.pi * f)[1]

    def apply(self, x, fs_hz: float) -> np.ndarray:
        """What the acquisition does to ``x`` (samples along axis 0) at ``fs_hz`` (Hz): the filter
        (a digital one by ``sosfilt`` from rest at the first sample; an analog one by its response
        on the padded record's spectrum), then the delay (linear interpolation between samples)."""
        x = np.asarray(x, dtype=float)
        if self.corner_hz is not None:  # sos() and _filter_response() check the rate
            if self.domain == "digital":
                from scipy import signal

                sos = self.sos(fs_hz)
                zi = signal.sosfilt_zi(sos).reshape(sos.shape[0], 2, *([1] * (x.ndim - 1))) * x[0]
                x = signal.sosfilt(sos, x, axis=0, zi=zi)[0]
            else:
                x = through_gain(x, fs_hz, lambda f: self._filter_response(f, fs_hz), PAD_S)
        if self.delay_s == 0:
            return x
        t = np.arange(x.shape[0]) / fs_hz
        flat = x.reshape(x.shape[0], -1)
        out = np.column_stack([np.interp(t - self.delay_s, t, flat[:, i]) for i in range(flat.shape[1])])
        return out.reshape(x.shape)


def undo_timing(x, fs_hz: float, channel: ChannelFilter) -> np.ndarray:
    """``x`` (samples along axis 0, at ``fs_hz`` Hz) with ``channel``'s filter phase and delay taken out.

    The spectrum of the record (padded by :data:`PAD_S` of odd reflection at each end) is multiplied
    by ``conj(H) / |H|`` (H: :meth:`ChannelFilter.response`, the delay included): what remains is
    the zero-phase magnitude ``|H|`` of the filter, aligned with the instant each sample describes.
    Offline (non-causal); a channel with no filter and no delay is returned as given.

    Parameters
    ----------
    x : array_like, (n,) or (n, k)
        The channel(s) as recorded, in their unit.
    fs_hz : float, Hz
        The record's rate.
    channel : ChannelFilter

    Returns
    -------
    numpy.ndarray
        Same shape and unit as ``x``.
    """
    x = np.asarray(x, dtype=float)
    if channel.none:
        return x
    channel.check_rate(fs_hz)

    def unphase(f):
        h = channel.response(f, fs_hz)
        mag = np.abs(h)
        return np.where(mag > 0, np.conj(h) / np.where(mag > 0, mag, 1.0), 1.0)

    return through_gain(x, fs_hz, unphase, PAD_S)


def _number(text: str, kind, what: str, unit: str):
    try:
        return kind(text)
    except ValueError:
        raise ValueError(f"{what} {text!r} is not a number {unit}") from None


def parse_channel_filter(text: str, delay_s: float = 0.0, option: str = "the channel filter") -> ChannelFilter:
    """``"HZ[:ORDER[:KIND][:DOMAIN]]"`` (``"200"``, ``"200:4"``, ``"150:4:bessel:digital"``; ``"none"``:
    no filter) and a delay (s) as a :class:`ChannelFilter`; a ``ValueError`` naming ``option`` otherwise:
    a word that is no kind nor domain, a kind or a domain given twice (``"200:4:bessel:butterworth"``),
    a corner out of :data:`CORNER_RANGE`."""
    parts = [p.strip().lower() for p in str(text).split(":")]
    try:
        corner = None if parts[0] == "none" else _number(parts[0], float, "the corner", "of Hz")
        order = _number(parts[1], int, "the order", "from 1 to 8") if len(parts) > 1 and parts[1] else 4
        words = parts[2:]
        unknown = [p for p in words if p not in KINDS + DOMAINS]
        if unknown or (corner is None and len(parts) > 1):
            raise ValueError(f"{unknown[0]!r} is neither a kind ({', '.join(KINDS)}) nor a domain "
                             f"({', '.join(DOMAINS)})" if unknown else "'none' takes no order")
        for what, names in (("kind", KINDS), ("domain", DOMAINS)):
            given = [p for p in words if p in names]
            if len(given) > 1:
                raise ValueError(f"{len(given)} {what}s given ({', '.join(given)}) where one goes")
        kind = next((p for p in words if p in KINDS), "butterworth")
        domain = next((p for p in words if p in DOMAINS), "analog")
        return ChannelFilter(corner, order, kind, domain, float(delay_s))
    except ValueError as exc:
        raise ValueError(f"{option} {text!r}: {exc}; give HZ[:ORDER[:KIND][:DOMAIN]], e.g. 200:4 or "
                         "150:4:bessel:digital, or none") from None
