"""A record's white noise taken out where it outweighs what the record carries (spectral subtraction).

A record ``x = s + n``, ``n`` white with one-sided power spectral density ``N0``: the zero-phase
gain ``G(f) = max(0, 1 - N0 / S_x(f))``, ``S_x`` the record's own Welch spectrum, is the Wiener
gain ``S_s / (S_s + N0)`` with the signal's spectrum estimated as ``S_x - N0`` (spectral
subtraction: S. F. Boll, "Suppression of acoustic noise in speech using spectral subtraction",
IEEE Trans. ASSP 27(2), 1979): ~1 where the signal outweighs the noise, 0 where the record is noise
alone. ``N0`` is read from the record over a band above its signal
(:func:`rigsim.correction.identification.noise.noise_rms` on each of :data:`SUB_BANDS` parts of it, the
least of them), ``S_x`` with Hann windows of :data:`SEGMENT_S` (50 % overlap). Where the parts'
levels differ by more than :data:`FLAT_RATIO` the band holds more than white noise (a rough road's
force reaching far above the truck's modes), the noise cannot be read, and the gain is 1 there: the
column passes unchanged. The record's mean passes untouched: a static offset is not noise.

With ``drift_hz``, the record's slow part is taken out too, as far as it is drift: the gain is
multiplied by ``h(f) + (1 - h(f)) k``, ``h(f) = (f / f_d)^4 / (1 + (f / f_d)^4)`` the magnitude of a
second-order Butterworth high-pass at ``f_d`` run forward and backward (zero-phase), the mean still
kept, and ``k`` the share of the slow part kept (:func:`drift_keep`). That is for a record whose slow
part may be the load cells' drift rather than anything the caller wants (:data:`DRIFT_HZ`). The
drift's level, ``drift_rms``, is subtracted from the slow part's as the white noise's is from each
frequency's: ``k = max(0, 1 - drift_rms^2 / P_slow)``, ``P_slow`` the record's power the high-pass
would take out. A slow part at the drift's level is cut (k = 0); one far above it is more than any
drift and is kept (k -> 1). Without ``drift_rms`` the slow part is cut whatever its level.

Made for a residual that is mostly noise with a narrow-band remainder: the model correction's
``F_rig - F_model(x_a)`` (:mod:`rigsim.scenarios.records.model.differential`), whose truck force the
model has taken out, leaving the model's error (where the truck's force is) and the load cells'
noise (everywhere). On a record whose signal fills the band (a wheel force itself) the gain is ~1
wherever the noise matters little and changes little. Only the white part is estimated: a load
cell's low-frequency drift shares its band with the truck's slow force and cannot be told apart
from a model's error there by the record alone; ``drift_hz`` is for a caller who has the slow force
from elsewhere (the model correction, whose model gives it).

:func:`design_noise_gain` returns the gain (:class:`NoiseGain`); :meth:`NoiseGain.apply` applies it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rigsim.correction.identification.noise import noise_rms
from rigsim.correction.output.spectral import through_gain

__all__ = ["NOISE_BAND", "SUB_BANDS", "FLAT_RATIO", "SEGMENT_S", "DRIFT_HZ", "DRIFT_RMS_N", "NoiseGain", "design_noise_gain",
           "drift_cut", "drift_keep", "check_drift_hz"]

#: The band the white noise is read over, fractions of the sampling rate (60-150 Hz at 1 kHz): above
#: the wheel forces' band (the correction keeps 30 Hz) where a residual holds noise only, and below a
#: lab's anti-alias corner (fs / 5 and up), which attenuates the noise above it.
NOISE_BAND = (0.06, 0.15)
#: Parts of :data:`NOISE_BAND` whose noise levels are compared, 1.
SUB_BANDS = 4
#: Largest ratio of the parts' rms levels (1) at which the band is taken for white noise: the
#: noise levels of a white record's parts agree within a few percent (their Welch estimates average
#: hundreds of values); the model correction's residuals on the mismatch suite's plants 0, 8 and 12
#: (class A roads, 30-100 km/h, 100 N load cells) spread 1.1-1.5 times over 60-150 Hz, on its
#: plants 3 and 15 (class D, 75 and 100 km/h: the rig force itself reaches past 150 Hz) 2.6-3.5 times.
FLAT_RATIO = 2.0
#: Welch segment of the record's spectrum, s (0.24 Hz resolution): fine enough for the wheel-hop
#: peaks (~10 Hz, a few Hz wide), with ~13 averaged segments on a 30 s record.
SEGMENT_S = 4.096
#: Corner of the drift cut, Hz (``drift_hz``): a strain-gauge load cell's zero drifts with its
#: temperature and its amplifier's offset over seconds to minutes; 0.7 Hz is below the truck's body
#: modes (bounce and pitch at 1.5-3 Hz, a cab on soft mounts at 1.5-2.5 Hz), where the gain is
#: already 0.95 at 1.5 Hz and 0.98 at 2 Hz. Chosen on the model correction's residuals of the
#: mismatch suite (``benchmarks/mismatch_suite.py --drift-cut-hz F``, the lab's 50 N of drift below
#: 1 Hz): a higher corner gives the loaded trucks on smooth roads a little more, but the heavy truck
#: on a rough road at low speed (gen14, class C, 30 km/h, 8000 kg) loses more of its slow force than
#: the drift it sheds (a rear wheel's DLC error grows with the corner).
DRIFT_HZ = 0.7
#: N: the load cells' drift level the drift cut subtracts (``drift_rms``): the slow part of a
#: residual at this level is cut as drift, one far above it is kept as the model's error (a body
#: roll mode at 0.3-0.7 Hz on soft air springs or worn dampers that the model misses, hundreds of
#: newtons: the road's cross-slope excites it, the pans follow the drive there, and the measured
#: force holds what the model lacks). **Estimate**: a strain-gauge cell's zero drifts by some 0.05 %
#: of its span per 10 K (the temperature effect on the zero signal that load-cell data sheets
#: quote), 50 N on a 100 kN wheel-force cell for 10 K over a test, and its amplifier's 1/f noise
#: adds tens of newtons: 100 N is the top of what a working cell drifts.
DRIFT_RMS_N = 100.0


def check_drift_hz(drift_hz: float | None, fs_hz: float) -> None:
    """Refuse a drift-cut corner that is not None (no cut) or a frequency in Hz strictly between 0
    and half the rate ``fs_hz`` (Hz).

    Raises
    ------
    ValueError
        Naming ``drift_hz``, the band it must lie in and the value given (one sentence).
    """
    if drift_hz is not None and not (np.isfinite(drift_hz) and 0 < drift_hz < fs_hz / 2):
        raise ValueError(f"drift_hz must be None (no drift cut) or a corner in Hz between 0 and fs / 2 "
                         f"({fs_hz / 2:g} Hz), got {drift_hz!r}")


def drift_cut(freq_hz, drift_hz: float) -> np.ndarray:
    """The drift cut's gain (1) at ``freq_hz`` (Hz): ``(f / f_d)^4 / (1 + (f / f_d)^4)``, a
    second-order Butterworth high-pass at ``drift_hz`` (Hz) forward and backward."""
    r = (np.asarray(freq_hz, dtype=float) / drift_hz) ** 4
    return r / (1.0 + r)


def drift_keep(slow_power, drift_rms: float | None) -> np.ndarray:
    """The share of each column's slow part kept by the drift cut (1, (k,), in [0, 1]).

    Parameters
    ----------
    slow_power : array_like, (k,), the record's unit squared
        Each column's power that the cut would take out (its mean square through ``1 - h(f)``,
        :func:`drift_cut`'s complement).
    drift_rms : float or None, the record's unit
        The drift's rms; None: no level known, every slow part cut (0).

    Returns
    -------
    numpy.ndarray
        ``max(0, 1 - drift_rms^2 / slow_power)``: the slow part's power beyond the drift's, as a share.
    """
    p = np.asarray(slow_power, dtype=float)
    if drift_rms is None:
        return np.zeros(p.shape)
    return np.clip(1.0 - float(drift_rms) ** 2 / np.maximum(p, np.finfo(float).tiny), 0.0, 1.0)


@dataclass(frozen=True)
class NoiseGain:
    """The zero-phase gain per frequency and column that takes a record's white noise out.

    Attributes
    ----------
    freq_hz : numpy.ndarray, (m,), Hz
        Frequencies, 0 to ``fs_hz / 2``.
    gain : numpy.ndarray, (m, k), 1
        ``max(0, 1 - N0 / S_x(f))`` per column (times :func:`drift_cut` where designed with
        ``drift_hz``), in [0, 1].
    noise_rms : numpy.ndarray, (k,), the record's unit
        The white noise's rms over the whole band (0 to ``fs_hz / 2``) per column: the least of the
        noise band's parts.
    measured : numpy.ndarray, (k,), bool
        Whether the noise band held white noise (its parts' levels within :data:`FLAT_RATIO`);
        where not, the column's gain is 1.
    fs_hz : float, Hz
        The record's rate.
    drift_kept : numpy.ndarray or None, (k,), 1
        Designed with ``drift_hz``: the share of each column's slow part kept (:func:`drift_keep`;
        0: cut as drift); None without a drift cut.
    """

    freq_hz: np.ndarray
    gain: np.ndarray
    noise_rms: np.ndarray
    measured: np.ndarray
    fs_hz: float
    drift_kept: np.ndarray | None = None

    def apply(self, x) -> np.ndarray:
        """``x`` ((n, k), the designed record's columns and rate, its unit) through the gain,
        zero-phase, each column's mean kept."""
        a = np.asarray(x, dtype=float)
        if a.ndim != 2 or a.shape[1] != self.gain.shape[1]:
            raise ValueError(f"x must be (n, {self.gain.shape[1]}) like the designed record, got {a.shape}")
        mean = a.mean(axis=0)

        def gain(f):
            return np.column_stack([np.interp(f, self.freq_hz, g) for g in self.gain.T])

        y = through_gain(a - mean, self.fs_hz, gain, self.pad_s)
        return mean + (y - y.mean(axis=0))

    @property
    def pad_s(self) -> float:
        """Reflection padded at each end when applied, s: the gain's impulse response spans about one
        over its frequency resolution."""
        return 1.0 / float(self.freq_hz[1] - self.freq_hz[0])

    def share_kept(self) -> np.ndarray:
        """The white noise's power kept per column (1): the mean of ``gain**2`` over the band."""
        return np.mean(self.gain ** 2, axis=0)


def design_noise_gain(x, fs_hz: float, *, band_hz: tuple[float, float] | None = None,
                      segment_s: float = SEGMENT_S, drift_hz: float | None = None,
                      drift_rms: float | None = None) -> NoiseGain:
    """The gain that takes the white noise out of the record ``x``.

    Parameters
    ----------
    x : array_like, (n, k)
        The record, time along axis 0, any unit (N for forces); finite.
    fs_hz : float, Hz
        Its rate.
    band_hz : (float, float), Hz, optional
        Where the record holds noise only (default :data:`NOISE_BAND` times ``fs_hz``), read in
        :data:`SUB_BANDS` equal parts.
    segment_s : float, s
        Welch segment of the record's spectrum (at most the record's length is used).
    drift_hz : float, Hz, optional
        Take the record's slow part out too (:func:`drift_cut` at this corner, every column,
        whether or not its white noise was read), as far as it is drift (``drift_rms``); None: only
        the white noise.
    drift_rms : float, the record's unit, optional
        The drift's rms (with ``drift_hz``): a column's slow part is cut where it is at that level and
        kept where it is far above it (:func:`drift_keep`); None: cut whatever its level.

    Returns
    -------
    NoiseGain

    Raises
    ------
    ValueError
        A record that is not (n, k), too short (fewer than two segments of 64 samples), not finite,
        or a band outside (0, fs / 2), or a ``drift_hz`` that is not positive and below fs / 2, or a
        ``drift_rms`` that is not a finite level of at least 0.
    """
    from scipy.signal import welch

    a = np.asarray(x, dtype=float)
    if a.ndim != 2:
        raise ValueError(f"x must be (n, k) samples by columns, got shape {a.shape}")
    if not (np.isfinite(fs_hz) and fs_hz > 0):
        raise ValueError(f"fs_hz must be a positive rate in Hz, got {fs_hz!r}")
    if not (np.isfinite(segment_s) and segment_s > 0):
        raise ValueError(f"segment_s must be a positive length in s, got {segment_s!r}")
    check_drift_hz(drift_hz, fs_hz)
    if drift_rms is not None and not (np.isfinite(drift_rms) and drift_rms >= 0):
        raise ValueError(f"drift_rms must be None (cut every slow part) or the drift's rms, at least 0, got {drift_rms!r}")
    lo, hi = (NOISE_BAND[0] * fs_hz, NOISE_BAND[1] * fs_hz) if band_hz is None else band_hz
    edges = np.linspace(lo, hi, SUB_BANDS + 1)  # noise_rms refuses non-finite records and bands outside (0, fs / 2)
    parts = np.array([noise_rms(a, fs_hz, (edges[j], edges[j + 1])) for j in range(SUB_BANDS)])
    rms = parts.min(axis=0)
    measured = parts.max(axis=0) <= FLAT_RATIO * rms
    nperseg = min(int(math.ceil(segment_s * fs_hz)), a.shape[0] // 2)
    if nperseg < 64:
        raise ValueError(f"the record has {a.shape[0]} samples; the noise gain needs at least 128")
    f, s = welch(a - a.mean(axis=0), fs=fs_hz, nperseg=nperseg, axis=0)
    n0 = rms ** 2 / (fs_hz / 2.0)  # one-sided density of white noise of that rms
    gain = np.where(measured, np.clip(1.0 - n0 / np.maximum(s, np.finfo(float).tiny), 0.0, 1.0), 1.0)
    kept = None
    if drift_hz is not None:
        high = drift_cut(f, drift_hz)[:, None]
        slow = through_gain(a - a.mean(axis=0), fs_hz, lambda fr: 1.0 - drift_cut(fr, drift_hz), 1.0 / f[1])
        kept = drift_keep(np.mean(slow ** 2, axis=0), drift_rms)
        gain = gain * (high + (1.0 - high) * kept[None, :])
    return NoiseGain(freq_hz=f, gain=gain, noise_rms=np.asarray(rms, dtype=float), measured=measured,
                     fs_hz=float(fs_hz), drift_kept=kept)
