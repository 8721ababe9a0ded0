"""The rules of the one ``T_a`` fit (:mod:`rigsim.correction.identification.actuator_fit`): clean-up, scoring, order choice.

* :func:`usable_actuator`: a fitted ``(num, den)`` made usable as an inverse (stable, minimum
  phase, slow pole-zero pairs the data do not locate removed or moved up, ``T_a(0) = 1``);
* :func:`held_out_error`: the relative rms error of a fit at frequency points it was not fitted on;
* :func:`choose_orders`: the order-selection rule on the candidates' held-out errors.

Frequencies at the interface are in Hz; ``s`` (and poles and zeros) in rad/s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from rigsim.errors import RigsimError

__all__ = ["ActuatorFitError", "usable_actuator", "held_out_error", "choose_orders", "rational_response",
           "CANDIDATE_ORDERS", "ORDER_TOLERANCE", "NON_MINIMUM_PHASE_RATIO", "CANCEL_GAP", "TRUSTED_COHERENCE"]

#: Coherence from which a point of the estimate is trusted by default (the fit's ``coherence_min``), 1:
#: the output is then at least 90 % a linear function of the drive there.
TRUSTED_COHERENCE = 0.9
#: Candidate (numerator, denominator) orders: eq. 4's shape (1, 4), plus the spool's second order
#: and the truck's loading.
CANDIDATE_ORDERS = ((1, 4), (2, 5), (2, 6), (3, 6), (4, 7))
#: A candidate of lower total order is preferred when its held-out error is within this fraction
#: of the smallest one, 1.
ORDER_TOLERANCE = 0.05
#: When the best usable fit's held-out error exceeds the best raw fit's by more than this factor,
#: the data are not minimum phase and the orders are chosen on the usable fits' magnitude error, 1.
NON_MINIMUM_PHASE_RATIO = 2.0
#: A slow zero and pole cancel when their distance is below this fraction of the zero's modulus, 1:
#: removing them then changes the gain above them by less than 1 % (0.09 dB) once ``T_a(0) = 1``.
CANCEL_GAP = 0.01


class ActuatorFitError(RigsimError, ValueError):
    """Data that cannot support a fit of ``T_a``; the message is one sentence naming the band and the fix.

    Examples
    --------
    A displacement that does not follow the drive (here: another random signal) cannot support a
    fit:

    >>> import numpy as np
    >>> from rigsim.correction.identification.actuator_fit import ActuatorFitError, fit_actuator
    >>> rng = np.random.default_rng(1)
    >>> drive, other = 2e-3 * rng.standard_normal((2, 30_000))
    >>> try:  # doctest: +ELLIPSIS, +NORMALIZE_WHITESPACE
    ...     fit_actuator(drive, other, 500.0)
    ... except ActuatorFitError as exc:
    ...     print(exc)
    the drive-to-displacement coherence is >= 0.9 at only 0% of the points in 1-30 Hz (...): the LVDT
    does not follow this drive (the wrong corner, or not an LVDT); pair the drive with the LVDT of its own post
    """


def _lhp(roots: np.ndarray) -> np.ndarray:
    """Roots reflected into the open left half-plane (``r -> -conj(r)``; same magnitude response)."""
    r = np.asarray(roots, dtype=complex)
    r = np.where(r.real > 0, -np.conj(r), r)
    on_axis = r.real > -1e-9 * np.abs(r)
    return np.where(on_axis, r - 1e-9 * np.abs(r), r)


def usable_actuator(num, den, resolution_hz: float, f_low_hz: float | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """A fitted ``(num, den)`` made usable as an inverse: stable, minimum phase, ``T_a(0) = 1``.

    Parameters
    ----------
    num, den : array_like
        Coefficients, descending powers of s (s in rad/s).
    resolution_hz : float, Hz
        Frequency resolution of the estimate that was fitted.
    f_low_hz : float, Hz, optional
        Lowest frequency of the estimate that was fitted (default ``resolution_hz``).

    Returns
    -------
    num, den : numpy.ndarray
        Right-half-plane zeros and poles reflected (``|T_a|`` kept). Then the slow pole-zero
        pairs, which the estimate does not locate (only the gain step between the anchored
        ``T_a(0)`` and its first bins): a zero slower than ``2 pi * 2 resolution_hz`` rad/s with
        a pole within :data:`CANCEL_GAP` of it is removed with that pole (a gain change below
        1 %, whose inverse would ring for tens of seconds); a real pair (zero and nearest real
        pole) entirely below half the lowest fitted frequency, ``pi f_low_hz`` rad/s, is moved
        up to it with its ratio kept (the same gain step; a shorter transient of the inverse).
        Last, scaled so that ``num[-1] == den[-1] == 1``.

    Raises
    ------
    ActuatorFitError
        A zero or pole at ``s = 0`` (no finite static gain to scale to 1).
    """
    num = np.trim_zeros(np.asarray(num, dtype=float), "f")
    den = np.trim_zeros(np.asarray(den, dtype=float), "f")
    zeros, poles = _lhp(np.roots(num)), _lhp(np.roots(den))
    slow = 2.0 * np.pi * 2.0 * float(resolution_hz)
    floor = np.pi * float(resolution_hz if f_low_hz is None else f_low_hz)
    keep_p = np.ones(poles.size, dtype=bool)
    keep_z = np.ones(zeros.size, dtype=bool)
    for iz, z in enumerate(zeros):
        if abs(z) > slow or not keep_p.any():
            continue
        gap = np.where(keep_p, np.abs(poles - z), np.inf)
        ip = int(np.argmin(gap))
        if gap[ip] < CANCEL_GAP * abs(z):
            keep_p[ip] = keep_z[iz] = False
        elif z.imag == 0 and poles[ip].imag == 0 and max(abs(z), abs(poles[ip])) < floor:
            scale = floor / max(abs(z), abs(poles[ip]))
            zeros[iz], poles[ip] = z * scale, poles[ip] * scale
    num = np.atleast_1d(np.real(np.poly(zeros[keep_z])))
    den = np.atleast_1d(np.real(np.poly(poles[keep_p])))
    if not (num[-1] != 0 and den[-1] != 0 and np.all(np.isfinite(num)) and np.all(np.isfinite(den))):
        raise ActuatorFitError("the fitted T_a has a zero or pole at s = 0 and no finite static gain; "
                               "record a longer drive with content down to 0.1 Hz")
    num, den = num / num[-1], den / den[-1]
    num[-1] = den[-1] = 1.0
    return num, den


def rational_response(num, den, f_hz) -> np.ndarray:
    """``num(s) / den(s)`` at ``s = j 2 pi f_hz`` (``f_hz`` in Hz; coefficients descending in s, rad/s)."""
    s = 2j * np.pi * np.asarray(f_hz, dtype=float)
    return np.polyval(num, s) / np.polyval(den, s)


def held_out_error(num, den, f_hz, h, trusted, *, magnitude_only: bool = False) -> float:
    """Relative rms error ``sqrt(mean |T(f)/H(f) - 1|^2)`` over the ``trusted`` points (1).

    Parameters
    ----------
    num, den : array_like
        ``T`` in descending powers of s (rad/s).
    f_hz : array_like, Hz
    h : array_like of complex
        The estimate at ``f_hz``.
    trusted : array_like of bool
        The points scored (e.g. coherence >= coherence_min); all points when none is.
    magnitude_only : bool
        Score ``|T(f)| / |H(f)| - 1`` instead (the phase left out).
    """
    f, hv, ok = np.asarray(f_hz, float), np.asarray(h, complex), np.asarray(trusted, bool)
    if not ok.any():
        ok = np.ones_like(ok)
    ratio = rational_response(num, den, f[ok]) / hv[ok]
    rel = (np.abs(ratio) if magnitude_only else ratio) - 1.0
    return float(np.sqrt(np.mean(np.abs(rel) ** 2)))


def choose_orders(candidates: Mapping) -> tuple[tuple[int, int], bool]:
    """The order-selection rule: the chosen orders, and whether the data are not minimum phase.

    Parameters
    ----------
    candidates : Mapping of (int, int) to dict
        Per candidate orders, held-out errors (1; NaN for a candidate that could not be fitted,
        at least one finite): ``held_out_error`` (the usable fit's), ``model_error`` (the raw
        fit's) and ``magnitude_error`` (the usable fit's magnitude alone).

    Returns
    -------
    orders : (int, int)
        The least ``held_out_error``, unless a candidate of lower total order is within
        :data:`ORDER_TOLERANCE` of it (ties: the smaller error). When the least
        ``held_out_error`` exceeds :data:`NON_MINIMUM_PHASE_RATIO` times the least
        ``model_error`` (the data are not minimum phase), the same rule on ``magnitude_error``:
        the minimum-phase counterpart whose magnitude is closest.
    non_minimum_phase : bool
        True in the second case.
    """
    def pick(key):
        scored = [(v[key], o) for o, v in candidates.items() if math.isfinite(v[key])]
        best = min(e for e, _ in scored)
        return min((sum(o), e, o) for e, o in scored if e <= (1.0 + ORDER_TOLERANCE) * best)[2], best

    chosen, best_usable = pick("held_out_error")
    _, best_model = pick("model_error")
    if best_usable > NON_MINIMUM_PHASE_RATIO * best_model:
        return pick("magnitude_error")[0], True
    return chosen, False
