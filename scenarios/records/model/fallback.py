"""The fallback derived: on which wheels the hybrid model correction beats the linear one.

Write ``E[G] = L(G(x_a)) - B G(x_ref)`` for the error the record's linear correction L (``T_a^-1
T_F`` per wheel, linear in its input) makes on the wheel force of a truck G, B the correction's band
limit. On the truck on the rig P the linear correction's error is ``E[P]``; the hybrid model
correction, ``F_model(x_ref) + L(W(F_rig - F_model(x_a)))`` with M the calibrated model, makes
``E[P - M]`` (the load cells' noise apart). E is linear in G, so

    E[P] = E[M] + E[P - M].

``E[M]`` is known exactly: both model runs are at hand (:func:`hybrid_outlook`). ``E[P - M]`` is
not, but the residual r the hybrid corrects tells two parts of it apart. The part of r that a linear
time-invariant filter of the four pans' motion explains (:func:`linear_part`: least squares over
:data:`LAGS_S` of each pan's motion) commutes with L (L is one filter on the pan motion as on the
force) and costs nothing; the rest, ``r_nl``, behaves at worst as a residual that does not depend on
the pan motion (the same on the road as on the rig), which costs ``(L - B) r_nl``. So the hybrid's
error is estimated as ``e_H = (L - B) r_nl`` and the linear correction's as ``E[M] + e_H``, both as
time series: the two add as they point, and where ``|e_H| < |E[M] + e_H|`` the hybrid is the better
one in NRMSE; elsewhere the wheel is corrected linearly. (The hybrid loses only where the model's
residual undoes the linear correction's own error on the model: ``e_H`` against ``E[M]`` and at
least half as large.) The model error
(:attr:`~rigsim.scenarios.records.model.result.Calibration.excess_nrmse`) enters through r: a model that
explains less leaves a larger residual for L to move.

The DLC goal is guarded apart, on the road force the estimates imply, ``R = H - e_H`` (H the
hybrid): the hybrid's DLC error ``DLC(H) - DLC(R)`` and the linear correction's ``DLC(H - e_H +
E[M] + e_H) - DLC(R)``, i.e. with the linear correction's estimated error in place of the
hybrid's; where the hybrid's exceeds both the DLC goal (:data:`DLC_GOAL`) and the linear
correction's, the wheel is corrected linearly too.

Every figure is per wheel over the samples where both corrections have settled, relative to the
standard deviation of the model's band-limited road force ``B F_model(x_ref)`` (NRMSE) or over its
mean (DLC).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigsim.correction.output.apply import band_limit
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE
from rigsim.mjcf.names import CORNERS

__all__ = ["LAGS_S", "FIT_RATE_HZ", "RIDGE", "DLC_GOAL", "HybridOutlook", "linear_part", "hybrid_outlook"]

#: s: the pans' motion lags (from, to) the residual's linear part is fitted over (:func:`linear_part`):
#: 50 ms ahead (a channel's skew or filter) to 0.6 s behind, six periods of the body's 10 Hz wheel hop
#: and beyond the 2-8 Hz modes' decay at 5-10 % damping; where L departs from the band limit (the
#: actuators' lag, a few hertz up) that memory is the truck's. Slower parts of the residual stay in
#: ``r_nl``, where L and B agree and ``(L - B)`` leaves them.
LAGS_S = (-0.05, 0.6)
#: Hz: the rate the linear part is fitted at (the record decimated to it; the band limit keeps 30 Hz).
FIT_RATE_HZ = 100.0
#: 1: ridge of the least squares, a share of the regressors' mean power (keeps the 264 lags of four
#: pans, 2700 rows on 27 s, from fitting the noise: unexplained white noise leaves ~10 % to chance).
RIDGE = 1e-3

#: 1: the DLC error the correction aims within (the paper's figure of merit; the suites' goal, 1 %):
#: the hybrid's bound may reach it before it is weighed against the linear correction's.
DLC_GOAL = 0.01


@dataclass(frozen=True)
class HybridOutlook:
    """Per wheel (``fl fr rl rr``), the hybrid's and the linear correction's errors as the model bounds them.

    Attributes
    ----------
    linear_error : numpy.ndarray, (4,), 1
        ``|E[M] + e_H|``: the linear correction's estimated NRMSE.
    hybrid_bound : numpy.ndarray, (4,), 1
        ``|e_H| = |(L - B) r_nl|``: the hybrid's estimated NRMSE.
    linear_dlc_error : numpy.ndarray, (4,), 1
        The linear correction's estimated DLC error.
    hybrid_dlc_bound : numpy.ndarray, (4,), 1
        The hybrid's estimated DLC error, its size.
    holds : numpy.ndarray of bool, (4,)
        The wheels the hybrid keeps: ``|e_H| < |E[M] + e_H|`` and the DLC guard.
    """

    linear_error: np.ndarray
    hybrid_bound: np.ndarray
    linear_dlc_error: np.ndarray
    hybrid_dlc_bound: np.ndarray
    holds: np.ndarray

    def reason(self, among=None, model_error=None) -> str:
        """One sentence naming the wheels corrected linearly and why, "" where the hybrid holds on all
        (of ``among``, bool (4,), default every wheel); ``model_error`` (1, (4,)), the calibration's
        per wheel, is quoted beside each."""
        among = np.ones(len(self.holds), bool) if among is None else np.asarray(among, dtype=bool)
        bad = [i for i, ok in enumerate(self.holds) if not ok and among[i]]
        if not bad:
            return ""
        parts = []
        for i in bad:
            err = "" if model_error is None else f"model error {float(model_error[i]):.3f}: "
            if not self.hybrid_bound[i] < self.linear_error[i]:
                parts.append(f"{CORNERS[i]} ({err}its residual costs the hybrid an NRMSE of about {self.hybrid_bound[i]:.3f}, "
                             f"the linear correction {self.linear_error[i]:.3f})")
            else:
                parts.append(f"{CORNERS[i]} ({err}its residual moves the hybrid's DLC by about {100 * self.hybrid_dlc_bound[i]:.2f} %, "
                             f"the linear correction's by {100 * abs(self.linear_dlc_error[i]):.2f} %)")
        which = "that wheel is" if len(bad) == 1 else "those wheels are"
        return (f"the calibrated truck model leaves a residual on {', '.join(parts)} that the linear correction "
                f"turns against the hybrid, so {which} corrected linearly.")

    def text(self) -> str:
        """The figures per wheel in one line (a file's metadata): the estimated NRMSE and DLC error of the
        linear correction and of the hybrid, and the method kept."""
        return "; ".join(f"{c}: linear {self.linear_error[i]:.3f} hybrid {self.hybrid_bound[i]:.3f}, DLC linear "
                         f"{100 * self.linear_dlc_error[i]:+.2f} % hybrid {100 * self.hybrid_dlc_bound[i]:.2f} %, "
                         f"{'model' if self.holds[i] else 'linear'}" for i, c in enumerate(CORNERS))

    def to_dict(self) -> dict:
        """Per corner, the four figures and the decision (plain floats and bools, for JSON)."""
        return {c: {"linear_error": float(self.linear_error[i]), "hybrid_bound": float(self.hybrid_bound[i]),
                    "linear_dlc_error": float(self.linear_dlc_error[i]),
                    "hybrid_dlc_bound": float(self.hybrid_dlc_bound[i]), "model": bool(self.holds[i])}
                for i, c in enumerate(CORNERS)}


def linear_part(residual_N, pans_m, fs_hz: float) -> np.ndarray:
    """The part of ``residual_N`` (N, (n, k)) a linear time-invariant filter of ``pans_m`` (m, (n, 4))
    explains: least squares of each column on every pan's motion over :data:`LAGS_S`, fitted on both
    decimated to :data:`FIT_RATE_HZ`, ridge :data:`RIDGE`; returned at ``fs_hz`` (N, (n, k))."""
    from scipy.signal import decimate, resample_poly

    r, x = np.asarray(residual_N, dtype=float), np.asarray(pans_m, dtype=float)
    q = max(1, int(round(fs_hz / FIT_RATE_HZ)))
    rd = decimate(r - r.mean(axis=0), q, axis=0, zero_phase=True) if q > 1 else r - r.mean(axis=0)
    xd = decimate(x - x.mean(axis=0), q, axis=0, zero_phase=True) if q > 1 else x - x.mean(axis=0)
    fs = fs_hz / q
    ahead, behind = int(round(-LAGS_S[0] * fs)), int(round(LAGS_S[1] * fs))
    n = rd.shape[0]
    padded = np.pad(xd, ((behind, ahead), (0, 0)))
    # column j * (ahead + behind + 1) + m: pan j delayed by (behind - m) samples
    cols = [padded[m:m + n, j] for j in range(xd.shape[1]) for m in range(ahead + behind + 1)]
    design = np.column_stack(cols)
    gram = design.T @ design
    gram[np.diag_indices_from(gram)] += RIDGE * np.trace(gram) / gram.shape[0]
    weights = np.linalg.solve(gram, design.T @ rd)
    fitted = design @ weights
    full = resample_poly(fitted, q, 1, axis=0)[:r.shape[0]] if q > 1 else fitted
    if full.shape[0] < r.shape[0]:
        full = np.pad(full, ((0, r.shape[0] - full.shape[0]), (0, 0)))
    return full


def _dlc(x: np.ndarray, mean: np.ndarray) -> np.ndarray:
    return x.std(axis=0) / np.abs(mean)


def hybrid_outlook(f_ref_N, f_a_N, residual_N, hybrid_N, linear, fs_hz: float, rows, pans_m=None) -> HybridOutlook:
    """The derived fallback's figures (see the module's description).

    Parameters
    ----------
    f_ref_N, f_a_N : array_like, N, (n, 4)
        The calibrated model's forces on pans following the drive and the measured pans.
    residual_N : array_like, N, (n, 4)
        The residual the hybrid passes through L: ``W(F_rig - F_model(x_a))``.
    hybrid_N : array_like, N, (n, 4)
        The hybrid model correction ``F_model(x_ref) + L(residual)``.
    linear : callable
        The record's linear correction: ``linear(forces)`` -> ``(corrected (N), settled (bool, (n,)))``.
    fs_hz : float, Hz
        The record's rate.
    rows : array_like of bool, (n,)
        The samples scored: both corrections settled.
    pans_m : array_like, m, (n, 4), optional
        The measured pan motion x_a: the residual's part linear in it is taken out before L moves
        it (:func:`linear_part`); None: the whole residual is weighed (the worst case).

    Returns
    -------
    HybridOutlook
    """
    rows = np.asarray(rows, dtype=bool)
    f_ref, f_a = np.asarray(f_ref_N, dtype=float), np.asarray(f_a_N, dtype=float)
    r, hybrid = np.asarray(residual_N, dtype=float), np.asarray(hybrid_N, dtype=float)
    road = band_limit(f_ref, fs_hz, BAND_LOWPASS, BAND_MODE)[rows]
    lin_model = linear(f_a)[0][rows]
    first = int(np.argmax(rows))  # the residual's part linear in the pans fitted where it has settled
    if pans_m is not None and rows.any():
        r = r.copy()
        r[first:] = r[first:] - linear_part(r[first:], np.asarray(pans_m, dtype=float)[first:], fs_hz)
    moved = (linear(r)[0] - band_limit(r, fs_hz, BAND_LOWPASS, BAND_MODE))[rows]  # (L - B) r_nl
    scale = road.std(axis=0)
    mean = road.mean(axis=0)
    h = hybrid[rows]
    with np.errstate(divide="ignore", invalid="ignore"):  # a model force without dynamics or load: nan, not kept
        e_lin = lin_model - road + moved  # E[M] + e_H
        linear_error = np.sqrt(np.mean(e_lin ** 2, axis=0)) / scale
        bound = np.sqrt(np.mean(moved ** 2, axis=0)) / scale
        implied = h - moved  # the road force the estimates imply
        lin_dlc = _dlc(implied + e_lin, mean) - _dlc(implied, mean)
        dlc_bound = np.abs(_dlc(h, mean) - _dlc(implied, mean))
    dlc_ok = (dlc_bound <= DLC_GOAL) | (dlc_bound <= np.abs(lin_dlc))
    return HybridOutlook(linear_error=linear_error, hybrid_bound=bound, linear_dlc_error=lin_dlc,
                         hybrid_dlc_bound=dlc_bound, holds=(bound < linear_error) & dlc_ok)
