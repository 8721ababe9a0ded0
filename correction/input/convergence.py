"""When drive iteration converges: the error measure and the stability of the relaxation gain.

The rules by which :func:`rigsim.correction.input.iterate.iterate_drive` refuses a gain before any run and
judges its runs:

- the error measure of a run, :func:`dynamic_error` (per response channel: the NRMSE of
  :func:`rigsim.correction.metrics.dlc.nrmse` with the error's mean left out);
- stability of the relaxation gain: with the true rig ``H`` and the estimate ``H_e``, the error
  obeys ``e_{k+1} = (I - g H H_e^-1) e_k`` per frequency in the band. Its spectral radius must
  stay below 1. :func:`error_map_spectral_radius` computes it for a known ``H``; from the
  identification alone :func:`predicted_spectral_radius` bounds it by ``|1 - g| + g delta(f)``,
  ``delta`` the relative random error of the H1 estimate (Bendat & Piersol, eq. 9.90:
  ``sqrt((1 - gamma^2) / (2 n_d gamma^2))`` with ``n_d`` the number of averages). A gain whose
  bound reaches 1 is refused (:class:`IterationStabilityError`) unless asked to run anyway; in
  any case two growing errors in a row stop the iteration with ``status = "diverged"`` and the
  best drive so far (the run-by-run stops -- converged, stalled, diverged, drive limit -- are
  decided in the loop, :func:`rigsim.correction.input.iterate.iterate_drive`).

numpy only (no simulator): works on data of a real rig. Units SI (m, N, s, Hz).
"""

from __future__ import annotations

import numpy as np

from rigsim.correction.input.frf import FRF, as_columns
from rigsim.correction.metrics.dlc import nrmse
from rigsim.errors import RigsimError

__all__ = ["IterationStabilityError", "error_map_spectral_radius", "predicted_spectral_radius", "dynamic_error"]


class IterationStabilityError(RigsimError, ValueError):
    """The relaxation gain makes the iteration's error map expand (spectral radius >= 1)."""


def error_map_spectral_radius(h_true, h_est_inv, gain: float) -> np.ndarray:
    """Spectral radius per frequency of the iteration's error map ``I - g H_true H_est^-1``.

    Parameters
    ----------
    h_true : (nf, p, m) complex
    h_est_inv : (nf, m, p) complex
        The inverse used by the iteration (already weighted: 0 where no update is made).
    gain : float
    """
    ht = np.asarray(h_true, dtype=complex)
    hi = np.asarray(h_est_inv, dtype=complex)
    p = ht.shape[1]
    e = np.eye(p)[None] - float(gain) * (ht @ hi)
    rho = np.full(ht.shape[0], np.nan)
    ok = np.all(np.isfinite(e.reshape(e.shape[0], -1)), axis=1)
    rho[ok] = np.max(np.abs(np.linalg.eigvals(e[ok])), axis=1)
    return rho


def predicted_spectral_radius(frf: FRF, gain: float, weight) -> np.ndarray:
    """Bound of the error map's spectral radius from the identification alone, per frequency of ``frf``.

    With ``H_true = H_est (I + D)`` and ``|D| <= delta``: ``rho(I - g w H_true H_est^-1) <=
    |1 - g w| + g w delta``, where ``w`` in [0, 1] is the update weight (band and coherence) and
    ``delta = sqrt((1 - gamma^2) / (2 n_d gamma^2))`` the relative random error of H1 with the
    lowest coherence ``gamma^2`` of the outputs (Bendat & Piersol, Random Data, eq. 9.90),
    doubled as a margin for bias (leakage, nonlinearity).
    """
    g = float(gain)
    w = np.asarray(weight, dtype=float)
    c = np.clip(np.nan_to_num(np.min(frf.coherence, axis=1), nan=0.0), 1e-6, 1.0)
    delta = 2.0 * np.sqrt((1.0 - c) / (2.0 * frf.averages * c))
    return np.abs(1.0 - g * w) + g * w * delta


def dynamic_error(target, response) -> np.ndarray:
    """The drive iteration's error measure, per response channel (1): how far ``response`` is from
    ``target``, the static level left out (it is not what a drive iteration controls).

    The NRMSE of the response against the target with the error's mean left out,
    :func:`rigsim.correction.metrics.dlc.nrmse` ``(response, target, mean_free=True)``: the error's
    standard deviation over the target's. A constant target column (std 0), where the NRMSE is
    undefined, scores the error's standard deviation itself (in the target's unit).

    Parameters
    ----------
    target, response : array_like, (N,) or (N, p)
        The desired and the measured response, time along the first axis, finite.

    Returns
    -------
    numpy.ndarray, (p,), 1
    """
    t = as_columns(target, "target")
    y = as_columns(response, "response")
    s = t.std(axis=0)
    if np.all(s > 0):
        return nrmse(y, t, mean_free=True)
    return (t - y).std(axis=0) / np.where(s > 0, s, 1.0)
