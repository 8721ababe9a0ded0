"""Design of the output-correction filter ``T_a^-1(s) T_F(s)`` (paper eq. 3-6) as discrete SOS.

The corrected force is the measured force filtered by the inverse of the actuator transfer
function ``T_a`` times a low-pass ``T_F`` (:mod:`rigsim.correction.output.lowpass`). ``T_a^-1`` alone is
improper (eq. 4 has four poles and one zero, so its inverse grows like ``s^3``) and is never
discretized on its own: the product is formed first as one rational transfer function, by
concatenating zeros and poles (the inverse's zeros are ``T_a``'s poles, its poles ``T_a``'s
zeros), then checked to be proper, then discretized by the bilinear transform (optionally
prewarped) in zeros-poles-gain form and stored as second-order sections
(``scipy.signal.bilinear_zpk`` then ``zpk2sos``; scipy.signal's convention: design returns
coefficients, :mod:`rigsim.correction.output.apply` applies them). The result, with its responses and
transients, is a :class:`~rigsim.correction.output.correction_filter.CorrectionFilter`.

Refusals (``ValueError``, one sentence naming the problem and the fix):

* ``T_a`` unstable (a pole in the closed right half-plane);
* ``T_a`` non-minimum-phase (a zero in the closed right half-plane: it would become an
  unstable pole of the inverse);
* no low-pass, or one too weak to make the product proper (relative degree < 0);
* ``T_a(0) != 1`` (the static load would not pass unchanged) unless ``normalize_dc=True``;
* a sampling rate too low: the discrete response must match the continuous one within
  ``max_band_error`` (default 1 %) of its peak from 0 Hz to the low-pass band;
* a discrete pole on or outside the unit circle (checked after discretization).

Frequencies at the interface are in Hz (``fs`` too); zeros and poles are in rad/s (s-plane) or
dimensionless (z-plane).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy import signal

from rigsim.correction.output.correction_filter import CorrectionFilter, transient_lengths
from rigsim.correction.output.lowpass import as_lowpass
from rigsim.correction.output.transfer import is_transfer_function

__all__ = ["actuator_coefficients", "design_correction", "reference_filter"]

_IDENTITY = (np.array([1.0]), np.array([1.0]))


def actuator_coefficients(ta) -> tuple[np.ndarray, np.ndarray]:
    """Numerator and denominator of ``T_a`` (descending powers of s), checked and tidied.

    Parameters
    ----------
    ta : (array_like, array_like) or control.TransferFunction
        ``(num, den)`` coefficients in descending powers of s (s in rad/s), or a continuous
        SISO ``control.TransferFunction``.

    Returns
    -------
    num, den : numpy.ndarray
        Float coefficients without leading zeros, with a common factor ``s^k`` cancelled.

    Raises
    ------
    ValueError
        If ``ta`` is not one of the accepted forms, is discrete-time or MIMO, has non-finite
        coefficients, or has a zero numerator or denominator.
    """
    if is_transfer_function(ta):
        if ta.ninputs != 1 or ta.noutputs != 1:
            raise ValueError(f"T_a must be single-input single-output, got a {ta.noutputs}x{ta.ninputs} "
                             "transfer function; pass one actuator at a time")
        if ta.dt not in (0, None):
            raise ValueError(f"T_a must be a continuous transfer function (dt = 0), got dt = {ta.dt!r}; "
                             "pass the continuous model, the discretization is done here")
        num, den = np.asarray(ta.num[0][0], dtype=float), np.asarray(ta.den[0][0], dtype=float)
    elif isinstance(ta, (tuple, list)) and len(ta) == 2:
        try:
            num = np.atleast_1d(np.asarray(ta[0], dtype=float))
            den = np.atleast_1d(np.asarray(ta[1], dtype=float))
        except (TypeError, ValueError):
            raise ValueError("T_a coefficients must be numbers (num, den in descending powers of s)") from None
        if num.ndim != 1 or den.ndim != 1:
            raise ValueError("T_a coefficients must be two 1-D sequences (num, den in descending powers of s)")
    else:
        raise ValueError(f"T_a must be (num, den) coefficient arrays or a control.TransferFunction, "
                         f"got {type(ta).__name__}")
    for name, c in (("numerator", num), ("denominator", den)):
        if c.size == 0 or not np.all(np.isfinite(c)):
            raise ValueError(f"T_a's {name} coefficients must be finite numbers, got {c.tolist()!r}")
        if not np.any(c != 0):
            raise ValueError(f"T_a's {name} is zero; give its coefficients in descending powers of s")
    num, den = np.trim_zeros(num, "f"), np.trim_zeros(den, "f")
    while num[-1] == 0 and den[-1] == 0:  # common factor s: cancel it
        num, den = num[:-1], den[:-1]
    return num, den


def _check_actuator(num: np.ndarray, den: np.ndarray, normalize_dc: bool) -> tuple[np.ndarray, np.ndarray]:
    poles, zeros = np.roots(den), np.roots(num)
    scale = max(1.0, float(np.max(np.abs(poles)))) if len(poles) else 1.0
    bad = [p for p in poles if p.real >= -1e-12 * scale]
    if bad:
        p = max(bad, key=lambda c: c.real)
        raise ValueError(f"T_a is unstable: it has a pole at {_fmt(p)} rad/s, not in the open left half-plane; "
                         "an actuator that follows its drive has a stable T_a, so fix its coefficients "
                         "(or identify it again) before correcting")
    bad = [z for z in zeros if z.real >= -1e-12 * max(1.0, abs(z))]
    if bad:
        z = max(bad, key=lambda c: c.real)
        raise ValueError(f"T_a is non-minimum-phase: its zero at {_fmt(z)} rad/s would be an unstable pole "
                         "of the inverse T_a^-1; fix: refit T_a with its zeros in the left half-plane "
                         "(e.g. fewer numerator terms) or use its minimum-phase counterpart")
    dc = num[-1] / den[-1]
    if not abs(dc - 1.0) <= 1e-6:
        if not normalize_dc:
            raise ValueError(f"T_a(0) = {dc:.6g}, but a position-controlled actuator follows its drive at "
                             "steady state (T_a(0) = 1) and the static wheel load must pass unchanged; fix: "
                             "correct the coefficients or pass normalize_dc=True")
        num = num / dc
    return num, den


def _fmt(c: complex) -> str:
    c = complex(c)
    if abs(c.imag) <= 1e-12 * max(1.0, abs(c)):
        return f"{c.real:.4g}"
    return f"{c.real:.4g}{c.imag:+.4g}j"


def _discretize(zeros, poles, gain, fs, prewarp_hz):
    fs_bilinear = fs
    if prewarp_hz is not None:
        w = 2.0 * np.pi * prewarp_hz
        fs_bilinear = w / (2.0 * math.tan(w / (2.0 * fs)))  # s = w/tan(w T/2) (z-1)/(z+1)
    zd, pd, kd = signal.bilinear_zpk(zeros, poles, gain, fs_bilinear)
    return zd, pd, kd


def _band_error(zeros, poles, gain, fs, prewarp_hz, band_hz, sos=None) -> float:
    f = np.linspace(0.0, band_hz, 257)
    s = 2j * np.pi * f
    hc = np.full(s.shape, complex(gain))
    for z in zeros:
        hc = hc * (s - z)
    for p in poles:
        hc = hc / (s - p)
    if sos is None:
        zd, pd, kd = _discretize(zeros, poles, gain, fs, prewarp_hz)
        sos = signal.zpk2sos(zd, pd, kd)
    _, hd = signal.sosfreqz(sos, worN=f, fs=fs)
    return float(np.max(np.abs(hd - hc)) / np.max(np.abs(hc)))


def _resolve_prewarp(request, band_hz: float, fs: float) -> float | None:
    """Prewarping frequency (Hz) for ``request`` ("band", a frequency in Hz, or None) at ``fs``."""
    if isinstance(request, str) and request == "band":
        return band_hz if band_hz < 0.45 * fs else None  # too near Nyquist: refused anyway
    return request


def _required_fs(zeros, poles, gain, fs, prewarp_request, band_hz, tol) -> float:
    """Smallest sampling rate (Hz, rounded up to two significant digits) meeting ``tol``."""
    trial = max(fs, 2.2 * band_hz)
    for _ in range(80):
        step = 10.0 ** (math.floor(math.log10(trial)) - 1)
        trial = math.ceil(trial / step) * step
        pw = _resolve_prewarp(prewarp_request, band_hz, trial)
        if pw is not None and not pw < 0.5 * trial:
            pw = None
        if _band_error(zeros, poles, gain, trial, pw, band_hz) <= tol:
            return trial
        trial *= 1.05
    return trial


def design_correction(ta, fs: float, lowpass="paper", *, prewarp_hz: float | str | None = "band",
                      normalize_dc: bool = False, max_band_error: float = 0.01,
                      settling_tolerance: float = 1e-3) -> CorrectionFilter:
    """Design the discrete correction filter ``T_a^-1(s) T_F(s)`` (paper eq. 6) for sampling rate ``fs``.

    Parameters
    ----------
    ta : (array_like, array_like) or control.TransferFunction
        The actuator transfer function ``X_a / X_p``: ``(num, den)`` in descending powers of s
        (s in rad/s, e.g. :func:`rigsim.correction.output.eq4.eq4_coefficients_from`) or a continuous SISO
        ``control.TransferFunction``. It must be stable and minimum-phase with ``T_a(0) = 1``.
    fs : float, Hz
        Sampling rate of the force record.
    lowpass : {"paper", "regularized"}, LowPass or None
        ``T_F``: the paper's eq. 5 (two critically damped sections at 16 and 24 Hz), this
        project's regularized low-pass (6th-order Butterworth at 30 Hz), or a
        :class:`~rigsim.correction.output.lowpass.LowPass` with other parameters
        (:func:`~rigsim.correction.output.lowpass.paper_lowpass`, :func:`~rigsim.correction.output.lowpass.regularized_lowpass`).
        None is refused (the inverse alone is improper). Note: the paper's two critically
        damped sections are already 3 dB down near 8 Hz, in the middle of the axle-hop band,
        so its correction also removes real dynamic load; the regularized one is within 0.4 %
        of the exact inverse up to 20 Hz. Compare either against the road force through the
        same band limit (:func:`rigsim.correction.output.apply.band_limit`).
    prewarp_hz : float (Hz), "band" or None
        Match the discrete and continuous responses exactly at this frequency (bilinear
        transform with prewarping); must lie below ``fs / 2``. "band" (default) prewarps at
        the low-pass's band ``lowpass.band_hz`` (its highest corner, as ``scipy.signal.butter``
        does for a digital design), which keeps the steep Butterworth accurate at 1 kHz;
        None: plain bilinear transform.
    normalize_dc : bool
        Scale ``T_a``'s numerator so that ``T_a(0) = 1`` (for an identified ``T_a`` whose static
        gain is off by estimation error) instead of refusing.
    max_band_error : float, 1
        Largest allowed deviation of the discrete from the continuous response between 0 Hz and
        the low-pass band (relative to the response's peak there); sets the lowest usable ``fs``.
    settling_tolerance : float, 1
        Tolerance of the start-up transient (see :attr:`CorrectionFilter.settling_time_s`).

    Returns
    -------
    CorrectionFilter

    Raises
    ------
    ValueError
        One sentence naming the problem and its fix: unstable or non-minimum-phase ``T_a``,
        ``T_a(0) != 1``, missing or insufficient low-pass, sampling rate too low, or a discrete
        pole on or outside the unit circle.
    """
    if isinstance(fs, bool) or not isinstance(fs, (int, float, np.integer, np.floating)) \
            or not (math.isfinite(fs) and fs > 0):
        raise ValueError(f"the sampling rate fs must be a positive number in Hz, got {fs!r}")
    fs = float(fs)
    num, den = _check_actuator(*actuator_coefficients(ta), normalize_dc)
    lp = as_lowpass(lowpass)
    rel_ta = len(den) - len(num)
    if lp is None:
        raise ValueError(f"no low-pass given: T_a^-1 alone is improper (relative degree {-rel_ta}) and cannot "
                         "be discretized; fix: pass lowpass='paper' or lowpass='regularized'")
    if abs(lp.response(0.0) - 1.0) > 1e-9:
        raise ValueError(f"the low-pass {lp.name!r} has static gain {abs(lp.response(0.0)):.6g}, not 1, so the "
                         "static wheel load would not pass unchanged; fix: scale its gain to 1")
    if lp.relative_degree < rel_ta:
        raise ValueError(f"the low-pass {lp.name!r} (relative degree {lp.relative_degree}) is too weak for "
                         f"T_a^-1 (relative degree {-rel_ta}): their product would be improper; fix: use a "
                         f"low-pass of order >= {rel_ta}")
    # One rational function: T_a^-1's zeros are T_a's poles and vice versa.
    zeros = np.concatenate([np.roots(den).astype(complex), lp.zeros])
    poles = np.concatenate([np.roots(num).astype(complex), lp.poles])
    gain = float(den[0] / num[0]) * lp.gain
    band = lp.band_hz
    prewarp_request = prewarp_hz
    prewarp_hz = _resolve_prewarp(prewarp_request, band, fs)
    if prewarp_hz is not None:
        if isinstance(prewarp_hz, bool) or not (isinstance(prewarp_hz, (int, float)) and 0 < prewarp_hz < fs / 2):
            raise ValueError(f"prewarp_hz must lie between 0 and fs/2 = {fs / 2:g} Hz, got {prewarp_hz!r}")
        prewarp_hz = float(prewarp_hz)
    if fs <= 2.0 * band:
        need = _required_fs(zeros, poles, gain, fs, prewarp_request, band, max_band_error)
        raise ValueError(f"sampling rate {fs:g} Hz is too low for this correction filter: its low-pass band "
                         f"({band:g} Hz) reaches the Nyquist frequency ({fs / 2:g} Hz); fix: record or "
                         f"resample the forces at >= {need:g} Hz")
    zd, pd, kd = _discretize(zeros, poles, gain, fs, prewarp_hz)
    if np.any(np.abs(pd) >= 1.0):
        raise ValueError(f"the discretized filter has a pole at |z| = {np.max(np.abs(pd)):.9g} (on or outside "
                         "the unit circle) and would diverge; fix: check T_a's slowest zero or raise fs")
    sos = signal.zpk2sos(zd, pd, kd)
    lowpass_sos = signal.zpk2sos(*_discretize(lp.zeros, lp.poles, lp.gain, fs, prewarp_hz))
    err = _band_error(zeros, poles, gain, fs, prewarp_hz, band, sos)
    if err > max_band_error:
        need = _required_fs(zeros, poles, gain, fs, prewarp_request, band, max_band_error)
        raise ValueError(f"sampling rate {fs:g} Hz is too low for this correction filter: its discrete response "
                         f"deviates by {err:.1%} from the continuous one below {band:g} Hz (limit "
                         f"{max_band_error:.1%}); fix: record or resample the forces at >= {need:g} Hz")
    filt = CorrectionFilter(fs=fs, sos=sos, zeros=zeros, poles=poles, gain=gain, ta_num=num, ta_den=den,
                            lowpass=lp, lowpass_sos=lowpass_sos, prewarp_hz=prewarp_hz, band_error=err,
                            settling_tolerance=float(settling_tolerance))
    settle, margins = transient_lengths(filt, float(settling_tolerance))
    return dataclasses.replace(filt, settling_time_s=settle, zero_phase_margins_s=margins)


def reference_filter(fs: float, lowpass="paper", *, prewarp_hz: float | str | None = "band",
                     settling_tolerance: float = 1e-3) -> CorrectionFilter:
    """The low-pass ``T_F`` alone, discretized like the correction filter (``T_a = 1``).

    Passing the road (reference) force through it, with the same ``mode`` as the correction,
    gives the signal the corrected force should equal: see :func:`rigsim.correction.output.apply.band_limit`.

    Parameters
    ----------
    fs : float, Hz
    lowpass : {"paper", "regularized"} or LowPass
    prewarp_hz : float (Hz), "band" or None
        As in :func:`design_correction` (use the correction's value).
    settling_tolerance : float, 1

    Returns
    -------
    CorrectionFilter
    """
    return design_correction(_IDENTITY, fs, lowpass, prewarp_hz=prewarp_hz,
                             settling_tolerance=settling_tolerance)
