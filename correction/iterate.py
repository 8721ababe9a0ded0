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

Stability of the relaxation gain: with the true rig ``H`` and the estimate ``H_e``, the error
obeys ``e_{k+1} = (I - g H H_e^-1) e_k`` per frequency in the band. Its spectral radius must stay
below 1. :func:`error_map_spectral_radius` computes it for a known ``H``; from the
identification alone :func:`predicted_spectral_radius` bounds it by ``|1 - g| + g delta(f)``,
``delta`` the relative random error of the H1 estimate (Bendat & Piersol, eq. 9.90:
``sqrt((1 - gamma^2) / (2 n_d gamma^2))`` with ``n_d`` the number of averages). A gain whose
bound reaches 1 is refused (:class:`IterationStabilityError`) unless asked to run anyway; in
any case two growing errors in a row stop the iteration with ``status = "diverged"`` and the
best drive so far.

numpy and scipy only (no simulator): works on data of a real rig. Units SI (m, N, s, Hz).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from correction.identify import h1_estimate

__all__ = [
    "IterationStabilityError",
    "FRF",
    "IterationStep",
    "IterationResult",
    "identify_frf",
    "frf_on_grid",
    "inverse_frf",
    "error_map_spectral_radius",
    "predicted_spectral_radius",
    "nrmse",
    "drive_update",
    "iterate_drive",
]


class IterationStabilityError(ValueError):
    """The relaxation gain makes the iteration's error map expand (spectral radius >= 1)."""


@dataclass(frozen=True)
class FRF:
    """A measured frequency-response matrix.

    Attributes
    ----------
    f_hz : numpy.ndarray, Hz, (nf,)
    h : numpy.ndarray of complex, (nf, p, m)
        ``h[:, i, j]``: response ``i`` per unit of drive ``j`` (e.g. m/m or N/m).
    coherence : numpy.ndarray, (nf, p)
        Multiple coherence of each response with all drives (1: linear and noise-free).
    averages : int
        Number of independent Welch averages (about ``2 N / nperseg - 1`` with half overlap).
    """

    f_hz: np.ndarray
    h: np.ndarray
    coherence: np.ndarray
    averages: int


@dataclass(frozen=True)
class IterationStep:
    """One rig run of the iteration: the drive ``k`` and how well its response met the target."""

    index: int
    nrmse: np.ndarray  # per response channel, 1
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


def _cols(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise ValueError(f"{name} must be 1-D or 2-D (N, channels), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def identify_frf(drive, response, fs: float, nperseg: int) -> FRF:
    """H1 estimate of the rig's FRF matrix from a broadband drive (independent channels).

    Parameters
    ----------
    drive : array_like, (N, m)
        Simultaneous, mutually uncorrelated broadband drives (e.g. independent random noise).
    response : array_like, (N, p)
        The measured responses.
    fs : float, Hz
    nperseg : int
        Welch segment length (resolution ``fs / nperseg``).
    """
    u = _cols(drive, "drive")
    y = _cols(response, "response")
    f, h, coh = h1_estimate(u, y, fs, nperseg)
    if h.ndim == 1:  # SISO
        h = h[:, None, None]
        coh = coh[:, None]
    n_avg = max(1, int(2 * u.shape[0] // int(nperseg)) - 1)
    return FRF(f_hz=f, h=h, coherence=coh, averages=n_avg)


def frf_on_grid(frf: FRF, f_hz) -> tuple[np.ndarray, np.ndarray]:
    """Interpolate ``frf`` (real and imaginary parts, linearly) onto ``f_hz``.

    Returns ``(h, coherence)`` of shapes (nf, p, m) and (nf, p); NaN outside the measured range
    or where the estimate is undefined.
    """
    f = np.asarray(f_hz, dtype=float)
    nf, p, m = frf.h.shape
    h = np.empty((f.size, p, m), dtype=complex)
    for i in range(p):
        for j in range(m):
            hij = frf.h[:, i, j]
            ok = np.isfinite(hij)
            re = np.interp(f, frf.f_hz[ok], hij[ok].real, left=np.nan, right=np.nan)
            im = np.interp(f, frf.f_hz[ok], hij[ok].imag, left=np.nan, right=np.nan)
            h[:, i, j] = re + 1j * im
    coh = np.empty((f.size, p))
    for i in range(p):
        c = np.nan_to_num(frf.coherence[:, i], nan=0.0)
        coh[:, i] = np.interp(f, frf.f_hz, c, left=0.0, right=0.0)
    return h, coh


def _band_weight(f: np.ndarray, band_hz: tuple[float, float], edge: float = 0.15) -> np.ndarray:
    """1 inside ``band_hz``, cosine roll-off to 0 over ``edge`` of each edge frequency outside."""
    lo, hi = float(band_hz[0]), float(band_hz[1])
    if not (0 <= lo < hi):
        raise ValueError(f"band_hz must be (low, high) with 0 <= low < high, got {band_hz!r}")
    w = np.ones_like(f)
    if lo > 0:
        lo0 = lo * (1 - edge)
        w = np.where(f < lo0, 0.0, w)
        r = (f >= lo0) & (f < lo)
        w = np.where(r, 0.5 - 0.5 * np.cos(np.pi * (f - lo0) / (lo - lo0)), w)
    hi1 = hi * (1 + edge)
    w = np.where(f > hi1, 0.0, w)
    r = (f > hi) & (f <= hi1)
    w = np.where(r, 0.5 + 0.5 * np.cos(np.pi * (f - hi) / (hi1 - hi)), w)
    return w


def inverse_frf(h: np.ndarray, *, regularization: float = 1e-3) -> np.ndarray:
    """Per-frequency (pseudo-)inverse ``(H^H H + lambda I)^-1 H^H`` of ``h`` (nf, p, m) -> (nf, m, p).

    ``lambda = regularization * sigma_max^2`` at each frequency (Tikhonov): directions the rig
    barely responds to get a bounded drive instead of an infinite one. Non-finite ``h`` gives 0.
    """
    h = np.asarray(h, dtype=complex)
    nf, p, m = h.shape
    out = np.zeros((nf, m, p), dtype=complex)
    ok = np.all(np.isfinite(h.reshape(nf, -1)), axis=1)
    hh = h[ok]
    hH = np.conj(np.swapaxes(hh, 1, 2))
    a = hH @ hh
    smax2 = np.linalg.norm(hh, ord=2, axis=(1, 2)) ** 2
    lam = float(regularization) * smax2
    a = a + lam[:, None, None] * np.eye(m)[None]
    good = smax2 > 0
    out_ok = np.zeros((hh.shape[0], m, p), dtype=complex)
    if np.any(good):
        out_ok[good] = np.linalg.solve(a[good], hH[good])
    out[ok] = out_ok
    return out


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


def nrmse(target, response) -> np.ndarray:
    """Per channel ``rms(e - mean(e)) / std(target)``, ``e = target - response`` (means removed:
    the static level is not what a drive iteration controls)."""
    t = _cols(target, "target")
    y = _cols(response, "response")
    e = t - y
    e = e - e.mean(axis=0)
    s = t.std(axis=0)
    s = np.where(s > 0, s, 1.0)
    return np.sqrt(np.mean(e ** 2, axis=0)) / s


def _taper(n: int, fs: float, taper_s: float) -> np.ndarray:
    k = int(round(taper_s * fs))
    w = np.ones(n)
    if k > 0 and 2 * k < n:
        ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(k) / k)
        w[:k] = ramp
        w[-k:] = ramp[::-1]
    return w


def drive_update(error, inv_w: np.ndarray, gain: float, fs: float, *, taper_s: float = 0.5) -> np.ndarray:
    """``g IFFT(W H^-1 FFT(e))`` of the whole record, tapered at both ends.

    ``inv_w`` (nf, m, p) is the weighted inverse on ``numpy.fft.rfftfreq(N, 1/fs)``. The error is
    tapered (cosine, ``taper_s``) before the FFT and the update after it, so the update starts
    and ends at zero (the drive's fade-in and the rig's rest state stay untouched) and the FFT's
    circular wrap-around cannot leak the end of the record into its start.
    """
    e = _cols(error, "error")
    n = e.shape[0]
    w = _taper(n, fs, taper_s)
    ef = np.fft.rfft((e - e.mean(axis=0)) * w[:, None], axis=0)  # (nf, p)
    df = np.einsum("fmp,fp->fm", inv_w, ef)
    d = np.fft.irfft(df, n=n, axis=0)
    return float(gain) * d * w[:, None]


def iterate_drive(
    system: Callable[[np.ndarray], np.ndarray],
    target,
    frf: FRF,
    fs: float,
    *,
    drive0=None,
    response0=None,
    gain: float = 0.8,
    band_hz: tuple[float, float] = (0.3, 30.0),
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
    tgt = _cols(target, "target")
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
    weight = _band_weight(f_grid, band_hz) * (np.min(coh_grid, axis=1) >= coherence_min)
    weight = np.where(np.all(np.isfinite(h_grid.reshape(f_grid.size, -1)), axis=1), weight, 0.0)
    if not np.any(weight > 0):
        raise ValueError(
            f"no frequency in the band {band_hz[0]:g}-{band_hz[1]:g} Hz has identification coherence >= "
            f"{coherence_min:g}; identify with more averages or a stronger drive, or lower coherence_min")
    inv = inverse_frf(h_grid, regularization=regularization) * weight[:, None, None]
    # Stability bound on the FRF's own grid (the interpolation adds nothing).
    w_frf = _band_weight(frf.f_hz, band_hz) * (np.nan_to_num(np.min(frf.coherence, axis=1)) >= coherence_min)
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
        d = _cols(drive0, "drive0").copy()
    if d.shape != (n, m):
        raise ValueError(f"drive0 must have shape ({n}, {m}), got {d.shape}")

    runs = 0
    if response0 is None:
        y = _cols(system(d), "response")
        runs += 1
    else:
        y = _cols(response0, "response0")
    if y.shape != (n, p):
        raise ValueError(f"the system returned shape {y.shape}, expected ({n}, {p})")

    scored = _taper(n, fs, taper_s) >= 1.0  # the update cannot act inside the tapers
    if scored.sum() < n // 2:
        raise ValueError(f"the record ({n / fs:g} s) is too short for tapers of {taper_s:g} s at both ends")

    def record(k, d_, y_):
        e = nrmse(tgt[scored], y_[scored])
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
        y_new = _cols(system(d_new), "response")
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
