"""The designed correction filter ``T_a^-1 T_F`` as an object: its responses and its transients.

:class:`CorrectionFilter` holds what :func:`rigsim.correction.output.filters.design_correction` produced
(discrete second-order sections, the continuous zeros, poles and gain, ``T_a`` and ``T_F``) and
answers the questions of applying it (:mod:`rigsim.correction.output.apply`): its continuous, discrete and
offline "zero-phase" frequency responses, its white-noise gain, and which samples at the start
(causal) or at both ends (zero-phase) of a record lie within its transients
(:meth:`CorrectionFilter.transient_samples`, :meth:`CorrectionFilter.transient_mask`).

The settling time and zero-phase margins those masks use are computed once, at design, from
the filter's impulse responses (:func:`transient_lengths`): the time after which the summed magnitude
of the remaining impulse response is at most the settling tolerance.

Frequencies at the interface are in Hz (``fs`` too); zeros and poles are in rad/s (s-plane).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from scipy import signal

from rigsim.correction.output.lowpass import LowPass

if TYPE_CHECKING:  # python-control is imported where it is used (it loads matplotlib)
    import control

__all__ = ["CorrectionFilter", "SETTLING_TOLERANCE"]

#: Default tolerance (1) of a correction filter's start-up and run-out transients: the samples
#: whose filter output may still differ from the steady state by more than this fraction are not
#: settled. The one value every correction uses (``rigsim correct``, the studies' scoring).
SETTLING_TOLERANCE = 1e-3


@dataclass(frozen=True, eq=False)
class CorrectionFilter:
    """The discretized correction filter ``T_a^-1 T_F`` and what is needed to apply it.

    Build it with :func:`design_correction`; apply it with :mod:`rigsim.correction.output.apply`.

    Attributes
    ----------
    fs : float, Hz
        Sampling rate the filter was designed for.
    sos : numpy.ndarray, shape (n_sections, 6)
        Second-order sections of the discrete filter (scipy.signal's ``sos`` layout).
    zeros, poles : numpy.ndarray, rad/s
        Zeros and poles of the continuous product ``T_a^-1(s) T_F(s)``.
    gain : float
        Its gain ``k`` in ``k prod(s - z) / prod(s - p)``.
    ta_num, ta_den : numpy.ndarray
        ``T_a``'s coefficients, descending powers of s (after ``normalize_dc`` if used).
    lowpass : LowPass
        The low-pass ``T_F``.
    lowpass_sos : numpy.ndarray
        ``T_F`` alone, discretized the same way (for the zero-phase response).
    prewarp_hz : float or None, Hz
        Frequency at which the bilinear transform was prewarped (None: not prewarped).
    band_error : float, 1
        Largest deviation of the discrete from the continuous response from 0 Hz to
        ``lowpass.band_hz``, relative to the continuous response's peak there.
    settling_time_s : float, s
        Causal start-up transient: after this time the effect of the unknown history before
        the record (the filter starts at the static level of the first sample) is at most
        ``settling_tolerance`` times the largest deviation of that history from the first sample.
    zero_phase_margins_s : (float, float), s
        The same for the offline zero-phase filter at the start and at the end of a record.
    settling_tolerance : float, 1
        Tolerance used for the two items above.
    """

    fs: float
    sos: np.ndarray
    zeros: np.ndarray
    poles: np.ndarray
    gain: float
    ta_num: np.ndarray
    ta_den: np.ndarray
    lowpass: LowPass
    lowpass_sos: np.ndarray
    prewarp_hz: float | None
    band_error: float
    settling_time_s: float = field(default=0.0)
    zero_phase_margins_s: tuple[float, float] = field(default=(0.0, 0.0))
    settling_tolerance: float = field(default=SETTLING_TOLERANCE)

    # ------------------------------------------------------------------ transfer functions
    def tf(self) -> control.TransferFunction:
        """The continuous product ``T_a^-1(s) T_F(s)`` as one proper ``control.TransferFunction``."""
        import control

        num = np.real_if_close(self.gain * np.poly(self.zeros)) if len(self.zeros) else np.array([self.gain])
        den = np.real_if_close(np.poly(self.poles))
        return control.tf(np.real(num), np.real(den))

    def response(self, f_hz) -> np.ndarray:
        """Continuous complex response of ``T_a^-1 T_F`` at ``f_hz`` (Hz)."""
        s = 2j * np.pi * np.asarray(f_hz, dtype=float)
        out = np.full(s.shape, complex(self.gain))
        for z in self.zeros:
            out = out * (s - z)
        for p in self.poles:
            out = out / (s - p)
        return out

    def inverse_phase(self, f_hz) -> np.ndarray:
        """Phase (rad) of the continuous ``T_a^-1(j 2 pi f)`` at ``f_hz`` (Hz): ``arg den_a - arg num_a``."""
        s = 2j * np.pi * np.asarray(f_hz, dtype=float)
        return np.angle(np.polyval(self.ta_den, s)) - np.angle(np.polyval(self.ta_num, s))

    def zero_phase_response(self, f_hz) -> np.ndarray:
        """Response of the offline "zero-phase" filter at ``f_hz`` (Hz): the whole filter's magnitude
        with ``T_a^-1``'s phase.

        Computed from the discrete filters: ``H(f) conj(T_F(f)) / |T_F(f)|`` with ``H`` the SOS
        correction filter and ``T_F`` the low-pass discretized the same way
        (:attr:`lowpass_sos`), i.e. ``|H|`` with ``T_F``'s phase taken out, which leaves the
        (bilinear) phase of ``T_a^-1``. Using the discrete magnitude (zero at Nyquist) rather
        than the continuous one keeps the kernel short: the continuous product still has a
        magnitude of order 1e-2 at Nyquist, and cutting it there rings through the whole record.
        """
        f = np.atleast_1d(np.asarray(f_hz, dtype=float))
        _, hd = signal.sosfreqz(self.sos, worN=f, fs=self.fs)
        _, hf = signal.sosfreqz(self.lowpass_sos, worN=f, fs=self.fs)
        mag = np.abs(hf)
        out = np.zeros_like(hd)
        ok = mag > 1e-300
        out[ok] = hd[ok] * np.conj(hf[ok]) / mag[ok]
        out[f == 0.0] = 1.0  # exact static gain: T_a(0) = 1 and T_F(0) = 1
        return out

    def discrete_inverse_phase(self, f_hz) -> np.ndarray:
        """Phase (rad) of the discretized ``T_a^-1`` at ``f_hz`` (Hz): ``arg H - arg T_F``."""
        f = np.atleast_1d(np.asarray(f_hz, dtype=float))
        _, hd = signal.sosfreqz(self.sos, worN=f, fs=self.fs)
        _, hf = signal.sosfreqz(self.lowpass_sos, worN=f, fs=self.fs)
        return np.angle(hd * np.conj(hf))

    def discrete_response(self, f_hz) -> np.ndarray:
        """Complex response of the discrete SOS filter at ``f_hz`` (Hz)."""
        _, h = signal.sosfreqz(self.sos, worN=np.atleast_1d(np.asarray(f_hz, dtype=float)), fs=self.fs)
        return h

    def noise_gain(self) -> float:
        """RMS gain of the discrete filter for white noise (1): ``sqrt(sum h[n]^2)``.

        Measurement noise of standard deviation ``sigma`` (N), white up to ``fs / 2``, leaves the
        correction with standard deviation ``noise_gain() * sigma``.
        """
        n = int(min(max(self.fs * 4.0, 16), 2_000_000))
        imp = np.zeros(n)
        imp[0] = 1.0
        return float(np.sqrt(np.sum(signal.sosfilt(self.sos, imp) ** 2)))

    # ------------------------------------------------------------------ transients
    def transient_samples(self, mode: str = "causal") -> tuple[int, int]:
        """Samples to discard (or mark) at the start and end of a record, for ``mode``.

        Parameters
        ----------
        mode : {"causal", "zerophase"}

        Returns
        -------
        (int, int)
            Number of samples at the start and at the end that lie within the start-up (or, for
            the zero-phase filter, run-out) transient.
        """
        if mode == "causal":
            return int(math.ceil(self.settling_time_s * self.fs)), 0
        if mode == "zerophase":
            a, b = self.zero_phase_margins_s
            return int(math.ceil(a * self.fs)), int(math.ceil(b * self.fs))
        raise ValueError(f"unknown mode {mode!r}; use 'causal' or 'zerophase'")

    def transient_mask(self, n: int, mode: str = "causal") -> np.ndarray:
        """Boolean mask of length ``n``: True where the corrected force is settled (usable)."""
        head, tail = self.transient_samples(mode)
        mask = np.zeros(int(n), dtype=bool)
        mask[head:max(head, int(n) - tail)] = True
        return mask


#: Most samples of the impulse responses that give the transients' lengths (32 MiB each; the
#: zero-phase kernel's transforms take a few times that). Past them the responses' tails are the
#: slowest pole's geometric series: a slow pole at a high sampling rate costs no more memory.
MAX_RESPONSE_SAMPLES = 2**22


def _tail_time(h: np.ndarray, fs: float, tol: float, slow: float | None = None) -> float:
    """Time (s) after which ``sum |h[n:]|`` plus the tail beyond ``h`` is at most ``tol``.

    The tail beyond ``h`` (given ``slow``) is the slowest pole's geometric series (decay rate
    ``slow``, 1/s, from ``|h[-1]|``); where it alone still exceeds ``tol``, the time is extended
    along it: ``len(h) / fs + ln(tail / tol) / slow``.
    """
    beyond = 0.0 if slow is None else abs(float(h[-1])) / (1.0 - math.exp(-slow / fs))
    if beyond > tol:
        return h.size / fs + math.log(beyond / tol) / slow
    tail = np.cumsum(np.abs(h)[::-1])[::-1] + beyond
    idx = np.flatnonzero(tail > tol)
    return 0.0 if idx.size == 0 else float(idx[-1] + 1) / fs


def transient_lengths(filt: CorrectionFilter, tol: float) -> tuple[float, tuple[float, float]]:
    """Causal settling time and zero-phase start/end margins (s), from the impulse responses over
    a horizon of 20 time constants of the slowest pole (2 to 600 s).

    At most :data:`MAX_RESPONSE_SAMPLES` samples of each response are computed; where the horizon
    needs more, the tails beyond them are the slowest pole's geometric series
    (:func:`_tail_time`), and the zero-phase kernel's positive tail, which its circular window
    then wraps onto the negative times, is taken out of them as that series.
    """
    fs = filt.fs
    slow = float(np.min(-filt.poles.real))  # slowest decay rate, 1/s (> 0: checked stable)
    horizon_s = min(max(20.0 / slow, 2.0), 600.0)
    n = int(min(math.ceil(horizon_s * fs), MAX_RESPONSE_SAMPLES))
    capped = math.ceil(horizon_s * fs) > n
    imp = np.zeros(n)
    imp[0] = 1.0
    h = signal.sosfilt(filt.sos, imp)
    del imp
    settle = _tail_time(h, fs, tol, slow)
    del h
    # zero-phase kernel: inverse FFT of T_a^-1 |T_F| over a circular window of 2 n samples
    m = 2 * n
    f = np.fft.rfftfreq(m, 1.0 / fs)
    k = np.fft.irfft(filt.zero_phase_response(f), m)  # (a Nyquist bin's imaginary part is ignored)
    del f
    start = _tail_time(k[:n], fs, tol, slow)  # positive times (T_a^-1's poles): what the start of a record lacks
    negative = k[n:]
    if capped:  # the positive tail past n samples lies on k[n:]: its geometric continuation out
        ratio = k[n - 1] / k[n - 2] if k[n - 2] != 0 else 0.0
        ratio = ratio if 0.0 < ratio < 1.0 else math.exp(-slow / fs)
        negative = negative - k[n - 1] * ratio ** np.arange(1, n + 1)
    end = _tail_time(negative[::-1], fs, tol)  # negative times (T_F's mirror, fast): what the end lacks
    return settle, (start, end)
