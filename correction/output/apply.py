"""Applying the correction filter to measured wheel forces: causal, streaming, and offline "zero-phase".

Time runs along axis 0; a 2-D array holds one force channel per column (N).

Causal (:func:`correct_causal`, :class:`StreamingCorrector`)
    ``scipy.signal.sosfilt`` of the discrete ``T_a^-1 T_F`` with its initial state at the
    static level: ``sosfilt_zi`` (the state of a filter that has seen a constant 1 forever) times
    the first sample (or the record's mean, or a given level). The static load therefore starts
    settled; what remains is the unknown dynamic history before the record, whose effect has
    died out after :attr:`~rigsim.correction.output.correction_filter.CorrectionFilter.settling_time_s` (``T_a^-1`` has a
    slow pole at ``T_a``'s zero, about 1 rad/s for eq. 4 -- mostly cancelled by a nearby pole, so
    the transient is small but long). The corrected force carries ``T_F``'s phase lag.

Offline "zero-phase" (:func:`correct_zero_phase`)
    The response ``T_a^-1(j w) |T_F(j w)|``: the magnitude of the whole filter with the phase of
    ``T_a^-1`` kept, so the actuator's phase lag is removed and the low-pass adds none.
    ``sosfiltfilt`` of the whole filter is *not* this: it squares the magnitude and cancels the
    phase of ``T_a^-1`` that the correction exists to restore. Implementation: in the frequency
    domain, by FFT of the record padded circularly with its first value before and its last value
    after (the constant extensions a causal filter started at the first sample would also assume),
    multiplied at the FFT bins by ``|H| e^{j (arg H - arg T_F)}`` (``H`` the discrete correction
    filter, ``T_F`` the discrete low-pass: see
    :meth:`~rigsim.correction.output.correction_filter.CorrectionFilter.zero_phase_response`), and transformed
    back. Chosen over "causal ``T_a^-1 T_F`` then remove ``T_F``'s phase" because
    that second step is itself a non-causal all-pass with no finite rational form. The kernel is
    two-sided: both ends of the record have a transient,
    :attr:`~rigsim.correction.output.correction_filter.CorrectionFilter.zero_phase_margins_s`.

Both preserve the mean (the static load): ``T_a(0) = 1`` and ``T_F(0) = 1``, checked at design.
"""

from __future__ import annotations

import numpy as np
from scipy import fft as sp_fft
from scipy import signal

from rigsim.correction.output.correction_filter import CorrectionFilter
from rigsim.correction.output.filters import reference_filter

__all__ = ["correct", "correct_causal", "correct_zero_phase", "StreamingCorrector", "band_limit"]

MODES = ("causal", "zerophase")


def _as_force(force_N, name: str = "force_N") -> np.ndarray:
    x = np.asarray(force_N, dtype=float)
    if x.ndim not in (1, 2) or x.shape[0] < 1:
        raise ValueError(f"{name} must be a 1-D record or a 2-D array (time, channel), got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        row = int(np.flatnonzero(~np.all(np.isfinite(x.reshape(x.shape[0], -1)), axis=1))[0])
        raise ValueError(f"{name} has a NaN or infinite value at sample {row}; fix: remove or interpolate it")
    return x


def _initial_level(x: np.ndarray, initial) -> np.ndarray:
    if isinstance(initial, str):
        if initial == "first":
            return x[0]
        if initial == "mean":
            return x.mean(axis=0)
        raise ValueError(f"unknown initial {initial!r}; use 'first', 'mean' or a level in N")
    level = np.broadcast_to(np.asarray(initial, dtype=float), x.shape[1:])
    if not np.all(np.isfinite(level)):
        raise ValueError("the initial level must be finite (N)")
    return level


def _zi(filt: CorrectionFilter, level: np.ndarray) -> np.ndarray:
    zi = signal.sosfilt_zi(filt.sos)  # (n_sections, 2): the state after a constant 1 forever
    return zi.reshape(zi.shape + (1,) * np.ndim(level)) * level


def correct_causal(force_N, filt: CorrectionFilter, *, initial="first") -> np.ndarray:
    """Correct forces with the causal filter, starting from the static level.

    Parameters
    ----------
    force_N : array_like, N
        Measured wheel forces, shape (n,) or (n, channels), sampled at ``filt.fs``.
    filt : CorrectionFilter
        From :func:`rigsim.correction.output.filters.design_correction`.
    initial : {"first", "mean"} or float or array_like
        Level (N) the filter is assumed to have seen forever before the record: the first
        sample (default), the record's mean, or a given static load per channel.

    Returns
    -------
    numpy.ndarray, N
        Corrected forces, same shape; samples inside ``filt.transient_mask(n, "causal") == False``
        are within the start-up transient.
    """
    x = _as_force(force_N)
    y, _ = signal.sosfilt(filt.sos, x, axis=0, zi=_zi(filt, _initial_level(x, initial)))
    return y


def correct_zero_phase(force_N, filt: CorrectionFilter) -> np.ndarray:
    """Correct forces offline with ``T_a^-1(j w) |T_F(j w)|`` (see the module notes).

    Parameters
    ----------
    force_N : array_like, N
        Measured wheel forces, shape (n,) or (n, channels), sampled at ``filt.fs``.
    filt : CorrectionFilter

    Returns
    -------
    numpy.ndarray, N
        Corrected forces, same shape; the first and last samples given by
        ``filt.transient_samples("zerophase")`` are within the transients.
    """
    x = _as_force(force_N)
    n = x.shape[0]
    head, tail = filt.transient_samples("zerophase")
    head, tail = 2 * head + 16, 2 * tail + 16  # padding: twice the kernel's support to tolerance
    m = sp_fft.next_fast_len(n + head + tail, real=True)
    tail = m - n - head
    xp = np.concatenate([x, np.broadcast_to(x[-1], (tail,) + x.shape[1:]),
                         np.broadcast_to(x[0], (head,) + x.shape[1:])], axis=0)
    # circular: the first-value pad (at the end of xp) precedes x[0]
    f = np.fft.rfftfreq(m, 1.0 / filt.fs)
    h = filt.zero_phase_response(f)  # irfft ignores the imaginary part of a Nyquist bin
    spec = sp_fft.rfft(xp, axis=0) * h.reshape((-1,) + (1,) * (x.ndim - 1))
    return sp_fft.irfft(spec, m, axis=0)[:n]


def correct(force_N, filt: CorrectionFilter, mode: str = "causal", *, initial="first") -> np.ndarray:
    """Correct forces in ``mode`` "causal" (:func:`correct_causal`) or "zerophase" (:func:`correct_zero_phase`).

    Parameters
    ----------
    force_N : array_like, N
        Shape (n,) or (n, channels), sampled at ``filt.fs``.
    filt : CorrectionFilter
    mode : {"causal", "zerophase"}
    initial : {"first", "mean"} or float or array_like
        Causal mode only: the static level the filter starts from (N).

    Returns
    -------
    numpy.ndarray, N
    """
    if mode == "causal":
        return correct_causal(force_N, filt, initial=initial)
    if mode == "zerophase":
        return correct_zero_phase(force_N, filt)
    raise ValueError(f"unknown mode {mode!r}; use 'causal' or 'zerophase'")


class StreamingCorrector:
    """Causal correction of a long record chunk by chunk, with the filter state carried over.

    The result of feeding consecutive chunks equals :func:`correct_causal` of the whole record
    (same ``initial``, with ``"first"`` taken from the first chunk's first sample).

    Parameters
    ----------
    filt : CorrectionFilter
    initial_level : float or array_like, N, optional
        Static level per channel the filter starts from; default: the first sample.

    Examples
    --------
    >>> sc = StreamingCorrector(filt)                         # doctest: +SKIP
    >>> out = np.concatenate([sc.process(c) for c in chunks])  # doctest: +SKIP
    """

    def __init__(self, filt: CorrectionFilter, *, initial_level=None):
        if isinstance(initial_level, str):
            raise ValueError(f"initial_level must be a level in N or None (the first sample), got {initial_level!r}")
        self.filt = filt
        self._initial = initial_level
        self._state: np.ndarray | None = None
        self.samples_done = 0

    def process(self, chunk_N) -> np.ndarray:
        """Correct the next chunk (N), shape (k,) or (k, channels); returns the same shape."""
        x = _as_force(chunk_N, "chunk_N")
        if self._state is None:
            level = x[0] if self._initial is None else _initial_level(x, self._initial)
            self._state = _zi(self.filt, level)
        y, self._state = signal.sosfilt(self.filt.sos, x, axis=0, zi=self._state)
        self.samples_done += x.shape[0]
        return y

    def settled(self, k: int) -> np.ndarray:
        """Mask for the next ``k`` output samples: True where past the start-up transient."""
        head, _ = self.filt.transient_samples("causal")
        return np.arange(self.samples_done, self.samples_done + int(k)) >= head


def band_limit(force_N, fs: float, lowpass="paper", mode: str = "causal", *, prewarp_hz="band",
               initial="first") -> np.ndarray:
    """Pass a reference (road) force through the same band limit the correction applies.

    A corrected rig force is the road force through ``T_F`` (causal mode) or ``|T_F|`` (zero-phase
    mode), not the raw road force: compare DLC and errors against this signal.

    Parameters
    ----------
    force_N : array_like, N
        Reference forces, shape (n,) or (n, channels).
    fs : float, Hz
    lowpass : {"paper", "regularized"} or LowPass
        The same low-pass as the correction.
    mode : {"causal", "zerophase"}
        The same mode as the correction.
    prewarp_hz : float (Hz), "band" or None
        The same prewarping as the correction.
    initial : {"first", "mean"} or float or array_like
        Causal mode: the static level the filter starts from (N).

    Returns
    -------
    numpy.ndarray, N
    """
    filt = reference_filter(fs, lowpass, prewarp_hz=prewarp_hz)
    return correct(force_N, filt, mode, initial=initial)
