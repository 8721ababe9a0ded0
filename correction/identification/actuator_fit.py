"""The one identification of ``T_a = X_a / X_p``: a usable actuator transfer function from rig data.

A lab that does not know its hydraulic parameters can still correct: the H1 estimate of the
drive-to-pan frequency response (:func:`rigsim.correction.identification.identify.h1_estimate`) is fitted with a
stable rational function (:func:`rigsim.correction.identification.identify.fit_rational_coefficients`, Sanathanan-Koerner) and made
usable as an inverse. Every caller (``rigsim correct --identify``, ``rigsim identify``, the
studies' ``identified`` method) uses this one policy:

* **weights** ``sqrt(coh / (1 - coh)) / |H|``: the inverse standard deviation of the H1
  estimate, relative to its level, so the fit minimises the relative error and trusts the
  coherent points first (``coh`` clipped to [0, 0.999]);
* **static gain**: three points ``H = 1`` at 1, 2 and 5 % of the frequency resolution, with the
  largest weight, pin ``T_a(0)`` (an actuator with integral action follows its drive at steady
  state); the result is then scaled so that ``T_a(0) = 1`` exactly;
* **orders** chosen by held-out error (the rules and their constants live in
  :mod:`rigsim.correction.identification.actuator_fit_rules`): each candidate of ``CANDIDATE_ORDERS`` ((1, 4), (2, 5),
  (2, 6), (3, 6), (4, 7)) is fitted on the even-indexed frequency points of the band, made usable
  (below), and scored on the odd-indexed ones (relative rms error on the coherent points,
  ``held_out_error``); the smallest error wins unless a candidate of lower total order is within
  ``ORDER_TOLERANCE`` (5 %) of it; the chosen orders are then fitted on all points. Scoring the
  usable fit keeps a fit that fakes the spool's lag with a right-half-plane zero (which the
  reflection turns into a lead) from winning. If no usable fit comes within
  ``NON_MINIMUM_PHASE_RATIO`` (2) of the best raw fit, the data themselves are not minimum phase
  (a delay, a right-half-plane zero; no usable ``T_a`` has their phase): the orders are then
  chosen, by the same rule, on the usable fits' magnitude error, so ``T_a`` is the
  minimum-phase counterpart of the data (same magnitude) (``choose_orders``);
* **usable by construction** (``usable_actuator``): right-half-plane poles (done by
  ``fit_rational``) and zeros are reflected into the left half-plane (``r -> -conj(r)``, which
  keeps ``|T_a|``), so the fit is stable and minimum phase; slow pole-zero pairs, which the data
  do not locate (only the gain step between ``T_a(0)`` and the first bins), are removed when
  they nearly cancel (a zero below twice the frequency resolution with a pole within
  ``CANCEL_GAP``, 1 %, of it) or else, when entirely below half the lowest fitted frequency,
  moved up to it with their ratio kept (a shorter transient of the inverse);
* **refusal** only for data that cannot support a fit: fewer than :data:`MIN_COHERENT_FRACTION`
  (70 %) of the points in :data:`COHERENCE_BAND_HZ` (1-30 Hz, clipped to the fitted band) with
  coherence at or above ``coherence_min`` raises :class:`ActuatorFitError` (a
  :class:`~rigsim.correction.identification.plausibility.WiringError` naming the wrong corner when their
  median is below :data:`~rigsim.correction.identification.plausibility.UNRELATED_COHERENCE`: channels
  that do not follow each other at all). A fit whose error is poor in some band is not refused; it
  is reported (:attr:`~rigsim.correction.identification.actuator_result.ActuatorFit.band_errors`). :func:`fit_actuator`, which fits a drive and an
  LVDT channel, also refuses a pair whose data are not an actuator's
  (:func:`rigsim.correction.identification.plausibility.check_actuator`: swapped, inverted, another
  post's, another unit).

Frequencies at the interface are in Hz; ``s`` (and poles and zeros) in rad/s.
"""

from __future__ import annotations

import math

import numpy as np

from rigsim.correction.identification.actuator_result import ActuatorFit
from rigsim.correction.identification.actuator_fit_rules import (CANDIDATE_ORDERS, TRUSTED_COHERENCE, ActuatorFitError,
                                                                 choose_orders, held_out_error, rational_response,
                                                                 usable_actuator)
from rigsim.correction.identification.identify import fit_rational_coefficients, h1_estimate
from rigsim.correction.identification.plausibility import UNRELATED_COHERENCE, WiringError, check_actuator, check_signals
from rigsim.correction.output.lowpass import BAND_HZ
from rigsim.correction.output.transfer import transfer_bandwidth_hz

__all__ = ["ActuatorFitError", "fit_frequency_response", "fit_actuator", "default_nperseg",
           "coherence_median", "MIN_COHERENT_FRACTION", "COHERENCE_BAND_HZ", "REPORT_BANDS_HZ"]

#: Least fraction of the points in :data:`COHERENCE_BAND_HZ` with coherence >= coherence_min, 1.
MIN_COHERENT_FRACTION = 0.7
#: Band whose coherence decides whether the data support a fit, Hz (clipped to the fitted band).
COHERENCE_BAND_HZ = (1.0, BAND_HZ)
#: Bands of :attr:`~rigsim.correction.identification.actuator_result.ActuatorFit.band_errors`, Hz (clipped to the fitted band).
REPORT_BANDS_HZ = ((0.1, 1.0), (1.0, 10.0), (10.0, BAND_HZ), (BAND_HZ, 60.0))
#: Anchors ``H = 1`` at these fractions of the frequency resolution, 1.
_ANCHORS = (0.01, 0.02, 0.05)
#: Segments of the H1 estimate that a record needs for a usable coherence, 1.
_SEGMENTS = 16


def _band_label(lo: float, hi: float) -> str:
    return f"{lo:.3g}-{hi:.3g} Hz"


def _band_errors(num, den, f, h, coh, band, coherence_min) -> dict:
    out = {}
    for lo, hi in REPORT_BANDS_HZ:
        lo, hi = max(lo, band[0]), min(hi, band[1])
        sel = (f >= lo) & (f <= hi)
        if hi <= lo or not sel.any():
            continue
        good = sel & (coh >= coherence_min)
        ratio = rational_response(num, den, f[good]) / h[good]
        out[_band_label(lo, hi)] = {
            "max_db": float(np.max(np.abs(20.0 * np.log10(np.abs(ratio))))) if good.any() else math.nan,
            "max_deg": float(np.max(np.abs(np.degrees(np.angle(ratio))))) if good.any() else math.nan,
            "coherence_min": float(np.min(coh[sel])),
            "points": int(np.count_nonzero(sel)),
        }
    return out


def _coherence_band(f, band) -> tuple[np.ndarray, float, float]:
    """The points of :data:`COHERENCE_BAND_HZ` clipped to ``band`` (all of ``band`` if they do not
    overlap): (selection, low, high)."""
    lo, hi = max(COHERENCE_BAND_HZ[0], band[0]), min(COHERENCE_BAND_HZ[1], band[1])
    if hi <= lo:
        lo, hi = band
    return (f >= lo) & (f <= hi), lo, hi


def _check_coherence(f, coh, band, coherence_min, resolution) -> None:
    sel, lo, hi = _coherence_band(f, band)
    frac = float(np.mean(coh[sel] >= coherence_min)) if sel.any() else 0.0
    if frac < MIN_COHERENT_FRACTION:
        told = (f"the drive-to-displacement coherence is >= {coherence_min:g} at only {frac:.0%} of the points in "
                f"{_band_label(lo, hi)} ({MIN_COHERENT_FRACTION:.0%} needed")
        median = float(np.median(coh[sel])) if sel.any() else 0.0
        if sel.any() and median < UNRELATED_COHERENCE:
            raise WiringError("wrong corner", f"{told}, median {median:.2f}, what unrelated channels give): the LVDT "
                              "does not follow this drive (the wrong corner, or not an LVDT)",
                              "pair the drive with the LVDT of its own post")
        need_s = 10.0 * math.ceil((_SEGMENTS + 1) / 2.0 / resolution / 10.0)
        raise ActuatorFitError(f"{told}); record at least {need_s:.0f} s of independent random drive on every post "
                               "with an rms near the test drive's")


def _fit(f, h, w, orders, resolution, anchor_weight):
    """The raw stable fit (anchored) and its usable counterpart, both as (num, den)."""
    fa = resolution * np.array(_ANCHORS)
    ff = np.concatenate([fa, f])
    hh = np.concatenate([np.ones(fa.size, dtype=complex), h])
    ww = np.concatenate([np.full(fa.size, anchor_weight), w])
    raw = fit_rational_coefficients(ff, hh, orders[0], orders[1], weight=ww)
    return raw, usable_actuator(*raw, resolution, float(f[0]))


def _score(f, h, w, trusted, orders, resolution, anchor_weight) -> dict:
    """Held-out errors of one candidate: fitted on the even points, scored on the odd ones."""
    even, odd = slice(0, None, 2), slice(1, None, 2)
    try:
        raw, usable = _fit(f[even], h[even], w[even], orders, resolution, anchor_weight)
    except (ValueError, np.linalg.LinAlgError):
        return {"held_out_error": math.nan, "model_error": math.nan, "magnitude_error": math.nan}
    return {"held_out_error": held_out_error(*usable, f[odd], h[odd], trusted[odd]),
            "model_error": held_out_error(*raw, f[odd], h[odd], trusted[odd]),
            "magnitude_error": held_out_error(*usable, f[odd], h[odd], trusted[odd], magnitude_only=True)}


def _check_orders(orders) -> tuple[int, int]:
    try:
        nb, na = (int(o) for o in orders)
        if (nb, na) != tuple(orders):
            raise TypeError
    except (TypeError, ValueError):
        raise ValueError(f"orders must be two integers (numerator, denominator), got {orders!r}") from None
    if not (na >= 1 and 0 <= nb <= na):
        raise ValueError(f"orders must satisfy 0 <= numerator <= denominator >= 1, got {orders!r}")
    return nb, na


def fit_frequency_response(f_hz, h, coherence, *, band_hz=(0.1, 60.0), orders=None,
                           coherence_min: float = TRUSTED_COHERENCE) -> ActuatorFit:
    """Fit a usable ``T_a`` to a measured frequency response (see the module notes for the policy).

    Parameters
    ----------
    f_hz : array_like, Hz
        Frequencies of the estimate, increasing, evenly spaced (e.g. an H1 estimate's).
    h : array_like of complex, 1 (m/m)
        The drive-to-pan-displacement response at ``f_hz``.
    coherence : array_like, 1
        Its coherence (NaN counts as 0).
    band_hz : (float, float), Hz
        Band fitted (default 0.1-60 Hz).
    orders : (int, int), optional
        Force these (numerator, denominator) orders instead of choosing among
        :data:`~rigsim.correction.identification.actuator_fit_rules.CANDIDATE_ORDERS` by held-out error.
    coherence_min : float, 1
        Coherence from which a point is trusted (refusal rule, errors).

    Returns
    -------
    ActuatorFit

    Raises
    ------
    ActuatorFitError
        Too little coherence in 1-30 Hz (one sentence naming the band and what to record).
    ValueError
        Mismatched or non-finite inputs, a bad band, bad orders, or too few points in the band.
    """
    f = np.asarray(f_hz, dtype=float).ravel()
    hv = np.asarray(h, dtype=complex).ravel()
    coh = np.nan_to_num(np.asarray(coherence, dtype=float).ravel(), nan=0.0)
    if not (f.shape == hv.shape == coh.shape) or f.size < 4:
        raise ValueError("f_hz, h and coherence must be 1-D of the same length (at least 4 points)")
    if not np.all(np.isfinite(f)) or np.any(np.diff(f) <= 0):
        raise ValueError("f_hz must be finite and increasing (Hz)")
    try:
        band = (float(band_hz[0]), float(band_hz[1]))
    except (TypeError, ValueError, IndexError):
        raise ValueError(f"band_hz must be two frequencies (low, high) in Hz, got {band_hz!r}") from None
    if not (0 <= band[0] < band[1] and math.isfinite(band[1])):
        raise ValueError(f"band_hz must satisfy 0 <= low < high (Hz), got {band_hz!r}")
    if not 0 < coherence_min < 1:
        raise ValueError(f"coherence_min must lie in (0, 1), got {coherence_min!r}")
    forced = None if orders is None else _check_orders(orders)
    resolution = float(np.median(np.diff(f)))
    in_band = (f >= band[0]) & (f <= band[1]) & (f > 0) & np.isfinite(hv) & (np.abs(hv) > 0)
    _check_coherence(f, coh, band, coherence_min, resolution)
    fb, hb, cb = f[in_band], hv[in_band], coh[in_band]
    c = np.clip(cb, 0.0, 0.999)
    w = np.sqrt(c / (1.0 - c)) / np.abs(hb)
    anchor_weight = float(np.max(w)) if np.any(w > 0) else 1.0
    trusted = cb >= coherence_min
    todo = CANDIDATE_ORDERS if forced is None else (forced,)
    scores = {o: _score(fb, hb, w, trusted, o, resolution, anchor_weight) for o in todo}
    if not any(math.isfinite(v["held_out_error"]) for v in scores.values()):
        raise ActuatorFitError(f"no fit of orders {', '.join(f'{a}/{b}' for a, b in todo)} could be made from the "
                               f"{fb.size} points in {_band_label(*band)}; record a longer drive on every post")
    chosen, non_minimum_phase = choose_orders(scores)
    _, (num, den) = _fit(fb, hb, w, chosen, resolution, anchor_weight)
    bandwidth = transfer_bandwidth_hz((num, den))
    return ActuatorFit(num=num, den=den, orders=tuple(chosen), f_hz=f, h=hv, coherence=coh, band_hz=band,
                       held_out_error=float(scores[chosen]["held_out_error"]),
                       band_errors=_band_errors(num, den, fb, hb, cb, band, coherence_min),
                       bandwidth_hz=float(bandwidth), non_minimum_phase=non_minimum_phase,
                       candidates={f"{a}/{b}": v for (a, b), v in scores.items()})


def default_nperseg(n: int, fs: float) -> int:
    """Welch segment length for ``n`` samples at ``fs`` (Hz): about 8 s, at least 8 segments, >= 256."""
    return int(min(2 ** round(math.log2(8.0 * fs)), max(256, n // 8), n))


def fit_actuator(drive_m, displacement_m, fs: float, *, band_hz=(0.1, 60.0), orders=None,
                 coherence_min: float = TRUSTED_COHERENCE, nperseg: int | None = None) -> ActuatorFit:
    """Identify ``T_a = X_a / X_p`` from a drive record and the measured pan displacement.

    Parameters
    ----------
    drive_m : array_like, m
        The drive ``x_p`` sent to one actuator, shape (n,) (independent random drive is best).
    displacement_m : array_like, m
        That actuator's measured pan displacement ``x_a``, sampled with ``drive_m``.
    fs : float, Hz
        Sampling rate.
    band_hz : (float, float), Hz
        Band fitted (default 0.1-60 Hz; the top is clipped to 0.45 fs).
    orders : (int, int), optional
        Force these orders (default: chosen by held-out error).
    coherence_min : float, 1
        Coherence from which a point is trusted.
    nperseg : int, optional
        Welch segment length (default :func:`default_nperseg`: about 8 s, at least 8 segments).

    Returns
    -------
    ActuatorFit

    Raises
    ------
    ActuatorFitError
        Too little coherence (one sentence naming the band and what to record).
    rigsim.correction.identification.plausibility.WiringError
        An ActuatorFitError naming the likely cause: data that are not an actuator's drive and
        pan displacement (the same samples twice, swapped, another post's, inverted, another
        unit; :func:`rigsim.correction.identification.plausibility.check_actuator`).
    ValueError
        Records of different lengths, non-finite samples, a record too short.

    Examples
    --------
    60 s of random drive and the pan displacement of a second-order actuator at 15 Hz, 0.7 of
    critical damping:

    >>> import numpy as np
    >>> from scipy import signal
    >>> from rigsim.correction.identification.actuator_fit import fit_actuator
    >>> fs = 500.0
    >>> t = np.arange(30_000) / fs
    >>> drive = 2e-3 * np.random.default_rng(1).standard_normal(t.size)
    >>> w = 2 * np.pi * 15.0
    >>> lvdt = signal.lsim(([w * w], [1.0, 1.4 * w, w * w]), drive, t)[1]
    >>> fit = fit_actuator(drive, lvdt, fs)
    >>> print(f"-3 dB at {fit.bandwidth_hz:.0f} Hz, T_a(0) = {fit.num[-1] / fit.den[-1]:g}")
    -3 dB at 15 Hz, T_a(0) = 1
    >>> bool(np.all(fit.poles().real < 0)), bool(np.all(fit.zeros().real < 0))
    (True, True)
    """
    u, y, fs = _pair(drive_m, displacement_m, fs)
    check_signals(u, y)
    if nperseg is None:
        nperseg = default_nperseg(u.size, fs)
    f, h, coh = h1_estimate(u, y, fs, nperseg)
    try:
        band = (float(band_hz[0]), min(float(band_hz[1]), 0.45 * fs))
    except (TypeError, ValueError, IndexError):
        raise ValueError(f"band_hz must be two frequencies (low, high) in Hz, got {band_hz!r}") from None
    fit = fit_frequency_response(f, h, coh, band_hz=band, orders=orders, coherence_min=coherence_min)
    check_actuator(fit, coherence_min)
    return fit


def _pair(drive_m, displacement_m, fs) -> tuple[np.ndarray, np.ndarray, float]:
    u = np.asarray(drive_m, dtype=float)
    y = np.asarray(displacement_m, dtype=float)
    if u.ndim != 1 or y.shape != u.shape:
        raise ValueError(f"drive_m and displacement_m must be 1-D of the same length, got {u.shape} and {y.shape}")
    if not (isinstance(fs, (int, float, np.integer, np.floating)) and math.isfinite(fs) and fs > 0):
        raise ValueError(f"fs must be a positive sampling rate in Hz, got {fs!r}")
    return u, y, float(fs)


def coherence_median(drive_m, displacement_m, fs: float) -> float:
    """Median coherence (1) of a drive and a displacement (array_like, m, (n,) each, sampled together at
    ``fs``, Hz) in :data:`COHERENCE_BAND_HZ` (its top clipped to 0.45 ``fs``), from
    :func:`fit_actuator`'s estimate (default segments)."""
    u, y, fs = _pair(drive_m, displacement_m, fs)
    f, _, coh = h1_estimate(u, y, fs, default_nperseg(u.size, fs))
    sel, _, _ = _coherence_band(f, (0.0, 0.45 * fs))
    return float(np.median(np.nan_to_num(coh[sel], nan=0.0))) if sel.any() else 0.0
