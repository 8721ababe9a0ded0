"""Input correction: iterative drive-file correction of a road simulator (RPC-style and Moran's).

The input-correction family the paper sets its output correction against: the drive of the rig
is changed, run after run, until a measured response matches a target. Two targets:

- pan displacement = road profile (Moran et al.: the pans reproduce the road);
- a remote response, e.g. tire force = the road test's tire force (Remote Parameter Control).

The method (all in the frequency domain, FFT of the whole record)::

    identify   H(f)  (p x m) from a broadband drive: H1 with multiple coherence
    iterate    d_{k+1} = d_k + g  W(f) H^-1(f) (target - y_k)

with a relaxation gain ``g``, a weight ``W`` that is 1 inside the frequency band (cosine edges)
and 0 where the identification's coherence is below a threshold, and a stop when the error
meets a tolerance or stops improving. The four wheels couple through the truck, so ``H`` is the
full matrix (MIMO H1 from four independent drives), inverted per frequency.

The pieces: :mod:`rigsim.correction.input.frf` (identification of ``H`` and its inverse),
:mod:`rigsim.correction.input.update` (the update ``g W H^-1 e``), :mod:`rigsim.correction.input.convergence` (the error
measure and the stability bound of the gain: a gain whose bound reaches 1 is refused with
:class:`~rigsim.correction.input.convergence.IterationStabilityError` unless asked to run anyway). This
module runs the loop and decides when it stops: the error meets the tolerance ("converged"),
stops improving ("stalled"), grows in two runs in a row ("diverged", with the best drive so
far), or the next drive would leave its limit ("drive_limit").

numpy and scipy only (no simulator): works on data of a real rig. Units SI (m, N, s, Hz).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from rigsim.correction.input.convergence import IterationStabilityError, dynamic_error, predicted_spectral_radius
from rigsim.correction.input.frf import FRF, as_columns, frf_on_grid, inverse_frf
from rigsim.correction.input.update import band_weight, end_taper, drive_update
from rigsim.correction.output.lowpass import BAND_HZ

__all__ = ["IterationStep", "IterationResult", "iterate_drive"]


@dataclass(frozen=True)
class IterationStep:
    """One rig run of the iteration: the drive ``k`` and how well its response met the target."""

    index: int
    nrmse: np.ndarray  # per response channel, 1: the dynamic error (convergence.dynamic_error)
    nrmse_mean: float
    drive_rms: np.ndarray  # per drive channel, unit of the drive


@dataclass
class IterationResult:
    """Outcome of :func:`iterate_drive`.

    Attributes
    ----------
    drive : numpy.ndarray, (N, m)
        The best drive found (lowest mean NRMSE).
    response : numpy.ndarray, (N, p)
        Its response.
    steps : list of IterationStep
        One per rig run (step 0 is the starting drive).
    status : str
        "converged" (tolerance met), "stalled" (error stopped improving), "diverged" (error grew
        in two consecutive runs: the gain is too high or the rig too nonlinear),
        "drive_limit" (the next drive would leave ``drive_limit``), "max_iterations".
    message : str
        One sentence explaining the status.
    gain : float
    spectral_radius_bound : float
        Largest predicted spectral radius of the error map where the full update acts (inside
        the band and above the coherence threshold; :func:`predicted_spectral_radius`); >= 1
        means the gain is not safe. The measured contraction is the ratio of successive errors.
    best_index : int
        Step of :attr:`drive`.
    runs : int
        Number of calls of the system (rig runs) made by the iteration.
    """

    drive: np.ndarray
    response: np.ndarray
    steps: list
    status: str
    message: str
    gain: float
    spectral_radius_bound: float
    best_index: int
    runs: int
    extras: dict = field(default_factory=dict)

    @property
    def errors(self) -> list[float]:
        """Mean NRMSE per step."""
        return [s.nrmse_mean for s in self.steps]

    def summary(self) -> dict:
        """JSON-friendly summary (error per iteration)."""
        return {
            "status": self.status,
            "message": self.message,
            "gain": self.gain,
            "spectral_radius_bound": self.spectral_radius_bound,
            "best_index": self.best_index,
            "runs": self.runs,
            "steps": [
                {"index": s.index, "nrmse_mean": s.nrmse_mean, "nrmse": [float(v) for v in s.nrmse],
                 "drive_rms": [float(v) for v in s.drive_rms]}
                for s in self.steps
            ],
        }


def iterate_drive(
    system: Callable[[np.ndarray], np.ndarray],
    target,
    frf: FRF,
    fs: float,
    *,
    drive0=None,
    response0=None,
    gain: float = 0.8,
    band_hz: tuple[float, float] = (0.3, BAND_HZ),
    coherence_min: float = 0.8,
    max_iterations: int = 8,
    tolerance: float = 0.01,
    min_improvement: float = 0.02,
    regularization: float = 1e-3,
    drive_limit: float | None = None,
    taper_s: float = 0.5,
    on_unstable: str = "raise",
    callback: Callable[[IterationStep], None] | None = None,
) -> IterationResult:
    """Iterate a drive until ``system(drive)`` matches ``target``.

    Parameters
    ----------
    system : callable
        ``system(drive (N, m)) -> response (N, p)``: one rig run (same sampling as ``target``).
    target : array_like, (N, p)
        Desired response (road profile for Moran's displacement target, road tire force for RPC).
    frf : FRF
        Identified rig FRF from drive to the response (:func:`identify_frf`).
    fs : float, Hz
        Sampling rate of drive, response and target.
    drive0 : array_like, (N, m), optional
        Starting drive (Moran: the road profile itself); default ``W H^-1 target``, the
        first-guess inverse (band-limited: nothing outside the band).
    response0 : array_like, (N, p), optional
        ``system(drive0)`` if already measured (saves one run).
    gain : float
        Relaxation gain ``g`` (0 < g; the exact-model stability limit is g < 2).
    band_hz : (float, float), Hz
        Band of the update (cosine edges 15 % wide outside it).
    coherence_min : float
        No update at frequencies where any output's identification coherence is below this.
    max_iterations : int
        Most updates (rig runs after the first).
    tolerance : float
        Stop when the mean NRMSE falls below this. The NRMSE is scored on the samples outside the
        two end tapers (where the update acts).
    min_improvement : float
        Stop ("stalled") when an update lowers the mean NRMSE by less than this fraction.
    regularization : float
        Tikhonov factor of the inverse (:func:`inverse_frf`).
    drive_limit : float, optional
        Largest allowed ``|drive|`` (e.g. the actuator's half-stroke, m).
    taper_s : float, s
        Cosine taper of error and update at both ends of the record.
    on_unstable : {"raise", "run"}
        What to do when :func:`predicted_spectral_radius` reaches 1 in the band: refuse with
        :class:`IterationStabilityError` (default), or run and let the divergence check stop it.
    callback : callable, optional
        ``callback(step)`` after each rig run.

    Raises
    ------
    IterationStabilityError
        The gain is not stable by the identification's bound (``on_unstable="raise"``).
    ValueError
        On bad shapes, non-finite data or bad parameters.
    """
    tgt = as_columns(target, "target")
    n, p = tgt.shape
    if frf.h.shape[1] != p:
        raise ValueError(f"the FRF has {frf.h.shape[1]} outputs but the target has {p} channels")
    m = frf.h.shape[2]
    if not (np.isfinite(gain) and gain > 0):
        raise ValueError(f"gain must be > 0, got {gain!r}")
    if on_unstable not in ("raise", "run"):
        raise ValueError(f"on_unstable must be 'raise' or 'run', got {on_unstable!r}")
    if not 0 <= coherence_min < 1:
        raise ValueError(f"coherence_min must lie in [0, 1), got {coherence_min!r}")
    f_grid = np.fft.rfftfreq(n, 1.0 / fs)
    h_grid, coh_grid = frf_on_grid(frf, f_grid)
    weight = band_weight(f_grid, band_hz) * (np.min(coh_grid, axis=1) >= coherence_min)
    weight = np.where(np.all(np.isfinite(h_grid.reshape(f_grid.size, -1)), axis=1), weight, 0.0)
    if not np.any(weight > 0):
        raise ValueError(
            f"no frequency in the band {band_hz[0]:g}-{band_hz[1]:g} Hz has identification coherence >= "
            f"{coherence_min:g}; identify with more averages or a stronger drive, or lower coherence_min")
    inv = inverse_frf(h_grid, regularization=regularization) * weight[:, None, None]
    # Stability bound on the FRF's own grid (the interpolation adds nothing).
    w_frf = band_weight(frf.f_hz, band_hz) * (np.nan_to_num(np.min(frf.coherence, axis=1)) >= coherence_min)
    rho = predicted_spectral_radius(frf, gain, w_frf)
    # Report it where the full update acts (w = 1): inside the band's cosine edges the radius
    # tends to 1 by construction (no update, error kept), which says nothing about the gain.
    full = w_frf >= 0.999 if np.any(w_frf >= 0.999) else w_frf > 0
    rho_in = rho[full]
    rho_max = float(np.max(rho_in)) if rho_in.size else 0.0
    if rho_max >= 1.0 and on_unstable == "raise":
        worst = frf.f_hz[full][int(np.argmax(rho_in))]
        raise IterationStabilityError(
            f"relaxation gain {gain:g} is not stable: the iteration's error map I - g H H_est^-1 has a "
            f"predicted spectral radius of {rho_max:.3g} >= 1 at {worst:.2f} Hz (exact model: |1 - g| < 1 "
            f"needs 0 < g < 2); lower the gain")

    if drive0 is None:
        d = drive_update(tgt, inv, 1.0, fs, taper_s=taper_s)
    else:
        d = as_columns(drive0, "drive0").copy()
    if d.shape != (n, m):
        raise ValueError(f"drive0 must have shape ({n}, {m}), got {d.shape}")

    runs = 0
    if response0 is None:
        y = as_columns(system(d), "response")
        runs += 1
    else:
        y = as_columns(response0, "response0")
    if y.shape != (n, p):
        raise ValueError(f"the system returned shape {y.shape}, expected ({n}, {p})")

    scored = end_taper(n, fs, taper_s) >= 1.0  # the update cannot act inside the tapers
    if scored.sum() < n // 2:
        raise ValueError(f"the record ({n / fs:g} s) is too short for tapers of {taper_s:g} s at both ends")

    def record(k, d_, y_):
        e = dynamic_error(tgt[scored], y_[scored])
        s = IterationStep(index=k, nrmse=e, nrmse_mean=float(np.mean(e)),
                          drive_rms=np.sqrt(np.mean((d_ - d_.mean(axis=0)) ** 2, axis=0)))
        if callback is not None:
            callback(s)
        return s

    steps = [record(0, d, y)]
    best = (0, d, y)
    status, message = "max_iterations", ""
    growing = 0
    for k in range(1, int(max_iterations) + 1):
        if steps[-1].nrmse_mean <= tolerance:
            status = "converged"
            break
        d_new = d + drive_update(tgt - y, inv, gain, fs, taper_s=taper_s)
        if drive_limit is not None and np.max(np.abs(d_new)) > drive_limit:
            i, j = np.unravel_index(int(np.argmax(np.abs(d_new))), d_new.shape)
            status = "drive_limit"
            message = (f"the next drive would reach {abs(d_new[i, j]):.4g} on channel {j} at sample {i}, beyond "
                       f"the limit {drive_limit:g}; stopped with the best drive so far")
            break
        y_new = as_columns(system(d_new), "response")
        runs += 1
        d, y = d_new, y_new
        steps.append(record(k, d, y))
        prev, cur = steps[-2].nrmse_mean, steps[-1].nrmse_mean
        if cur < _best_err(best, steps):
            best = (k, d, y)
        if cur > prev:
            growing += 1
            if growing >= 2:
                status = "diverged"
                message = (f"the error grew in two consecutive iterations ({steps[-3].nrmse_mean:.4g} -> {prev:.4g} "
                           f"-> {cur:.4g}): the relaxation gain {gain:g} is too high for this rig (predicted "
                           f"spectral radius bound {rho_max:.3g}) or the rig is too nonlinear; stopped with the "
                           f"best drive (iteration {best[0]})")
                break
        else:
            growing = 0
            if cur <= tolerance:
                status = "converged"
                break
            if prev - cur < min_improvement * prev:
                status = "stalled"
                message = (f"the error improved by only {100 * (prev - cur) / prev:.1f} % in iteration {k} "
                           f"({prev:.4g} -> {cur:.4g}); stopped")
                break
    if status == "converged" and not message:
        message = f"mean NRMSE {steps[best[0]].nrmse_mean:.4g} <= tolerance {tolerance:g} after {best[0]} update(s)"
    if status == "max_iterations":
        message = f"stopped after {max_iterations} iterations at mean NRMSE {steps[best[0]].nrmse_mean:.4g}"
    return IterationResult(drive=best[1], response=best[2], steps=steps, status=status, message=message,
                           gain=float(gain), spectral_radius_bound=rho_max, best_index=best[0], runs=runs)


def _best_err(best, steps) -> float:
    return steps[best[0]].nrmse_mean
