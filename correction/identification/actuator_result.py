"""The identified actuator transfer function ``T_a = X_a / X_p`` and how well it fits: the result
of :func:`rigsim.correction.identification.actuator_fit.fit_actuator` and
:func:`~rigsim.correction.identification.actuator_fit.fit_frequency_response`, which the
correction takes (:meth:`ActuatorFit.as_tf`). Frequencies in Hz, ``s`` and roots in rad/s.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from rigsim.correction.output.transfer import describe_roots

__all__ = ["ActuatorFit"]


@dataclass(frozen=True)
class ActuatorFit:
    """An identified actuator transfer function ``T_a(s) = X_a / X_p`` and how well it fits.

    Attributes
    ----------
    num, den : numpy.ndarray
        ``T_a``'s coefficients in descending powers of s (s in rad/s): stable, minimum phase,
        ``num[-1] / den[-1] == 1`` exactly (``num[-1] == den[-1] == 1``).
    orders : (int, int)
        The chosen (numerator, denominator) orders of the fit (before clean-up; ``num`` and
        ``den`` may be shorter when a slow pole-zero pair was removed).
    f_hz : numpy.ndarray, Hz
        Frequencies of the estimate that was fitted.
    h : numpy.ndarray of complex, 1 (m/m)
        The estimate (H1) at ``f_hz``.
    coherence : numpy.ndarray, 1
        Its coherence at ``f_hz`` (NaN where the drive has no power).
    band_hz : (float, float), Hz
        The fitted band.
    held_out_error : float, 1
        Relative rms error of the chosen orders' fit on the held-out (odd-indexed) frequency
        points with coherence >= ``coherence_min`` (:func:`held_out_error`).
    band_errors : Mapping[str, dict]
        Per band of :data:`~rigsim.correction.identification.actuator_fit.REPORT_BANDS_HZ` clipped to ``band_hz`` (keys like ``"1-10 Hz"``):
        ``max_db`` (dB) and ``max_deg`` (deg), the largest magnitude and phase error of the
        fit against the estimate at the points with coherence >= ``coherence_min`` (NaN if
        none), ``coherence_min`` (1), the least coherence in the band, and ``points`` (count).
    bandwidth_hz : float, Hz
        -3 dB bandwidth of the fit (NaN if it never falls 3 dB below ``T_a(0)`` by 10 kHz).
    non_minimum_phase : bool
        True when no usable (minimum-phase) fit came within :data:`~rigsim.correction.identification.actuator_fit_rules.NON_MINIMUM_PHASE_RATIO` of
        the best raw fit on the held-out points: the data's phase lags more than their magnitude
        implies (a delay, a right-half-plane zero), so the orders were chosen on the usable fits'
        magnitude error and ``T_a`` is the minimum-phase counterpart (same magnitude, less lag).
    candidates : Mapping[str, dict]
        Per candidate ``"n/d"``, held-out errors (1; NaN for one that could not be fitted):
        ``held_out_error`` (the usable fit's), ``model_error`` (the raw fit's, before the
        clean-up) and ``magnitude_error`` (the usable fit's magnitude alone).

    Examples
    --------
    >>> import numpy as np
    >>> from scipy import signal
    >>> from rigsim.correction.identification.actuator_fit import fit_actuator
    >>> t = np.arange(30_000) / 500.0
    >>> drive = 2e-3 * np.random.default_rng(1).standard_normal(t.size)
    >>> w = 2 * np.pi * 15.0
    >>> fit = fit_actuator(drive, signal.lsim(([w * w], [1.0, 1.4 * w, w * w]), drive, t)[1], 500.0)
    >>> print(np.round(np.abs(fit.frequency_response([1.0, 10.0, 15.0])), 2))
    [1.   0.92 0.71]
    >>> num, den = fit.as_tf()
    >>> sorted(fit.band_errors)
    ['0.1-1 Hz', '1-10 Hz', '10-30 Hz', '30-60 Hz']
    """

    num: np.ndarray
    den: np.ndarray
    orders: tuple[int, int]
    f_hz: np.ndarray
    h: np.ndarray
    coherence: np.ndarray
    band_hz: tuple[float, float]
    held_out_error: float
    band_errors: Mapping[str, dict]
    bandwidth_hz: float
    non_minimum_phase: bool = False
    candidates: Mapping[str, dict] = field(default_factory=dict)

    def poles(self) -> np.ndarray:
        """Poles of ``T_a``, rad/s."""
        return np.roots(self.den)

    def zeros(self) -> np.ndarray:
        """Zeros of ``T_a``, rad/s."""
        return np.roots(self.num)

    def frequency_response(self, f_hz) -> np.ndarray:
        """Complex ``T_a(j 2 pi f)`` at ``f_hz`` (Hz), 1 (m/m)."""
        s = 2j * np.pi * np.asarray(f_hz, dtype=float)
        return np.polyval(self.num, s) / np.polyval(self.den, s)

    def as_tf(self) -> tuple[np.ndarray, np.ndarray]:
        """``(num, den)``, descending powers of s (s in rad/s): what the correction takes."""
        return self.num.copy(), self.den.copy()

    def to_dict(self) -> dict:
        """JSON-ready diagnostics (no estimate arrays): coefficients, roots, errors, bandwidth."""
        return {"num": self.num.tolist(), "den": self.den.tolist(), "orders": list(self.orders),
                "band_hz": list(self.band_hz), "held_out_error": self.held_out_error,
                "bandwidth_hz": self.bandwidth_hz, "band_errors": {k: dict(v) for k, v in self.band_errors.items()},
                "non_minimum_phase": self.non_minimum_phase,
                "candidates": {k: dict(v) for k, v in self.candidates.items()},
                "poles": describe_roots(self.poles()), "zeros": describe_roots(self.zeros())}
