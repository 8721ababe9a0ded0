"""Calibrating the truck model from the rig's own signals (x_a and F_rig), never the road run.

The fields fitted, their units and search ranges: :mod:`scenarios.records.model.family`.

First guess: :mod:`scenarios.records.model.first_guess` (payload from the record's
static loads, the rest a catalogue guess that never reads a plant).

The fit: ``scipy.optimize.least_squares`` (trust-region reflective, bounded) of the residual
(F_model(x_a) - F_rig) / std(F_rig) per wheel over a few windows of the record (each run starts
from rest with a lead-in of measured x_a before its scored span, so the unknown truck state at
the window's start has decayed). Given the drive x_ref, the residual is weighted towards the
frequencies where the pans miss the drive (:mod:`scenarios.records.model.weighting`):
what the differential correction takes from the model. With the plant in the model family it
changes nothing; with a structural mismatch it keeps the mismatch from bending the parameters
where the correction needs them. The leaves' dry friction is MuJoCo's ``frictionloss``, a soft
constraint (smoothed), so the forces are smooth in the parameters and a forward-difference
Jacobian (step :data:`FD_STEP` of each scaled parameter) works; its perturbed runs go to the
worker pool (:func:`scenarios.core.pool.run_jobs`) together, one model run per window and variant.

Results: ``benchmarks/model_correction.py`` measures the calibration on the paper's cases and the
generalization suite (fitted values and their 1-sigma, fit and corrected NRMSE per wheel against
the linear floor, DLC, wall time); docs/model_correction.md discusses them.
"""

from __future__ import annotations

import contextlib
import time

import numpy as np

from correction.identification.noise import noise_rms
from mjcf.names import CORNERS, FRONT, REAR
from mjcf.variant import BOUNDS, TruckVariant
from scenarios.core.config import Scenario, ScenarioError
from scenarios.core.pool import local_executor, run_jobs
from scenarios.records.model.band_error import band_errors
from scenarios.records.model.cell_mass import band_acceleration, band_limited, mass_of, mass_sigma
from scenarios.records.model.family import ADDITIVE, COMPLIANCE, DEFAULT_NAMES, FITTED, RANGES, STATION_FITTED, UNITS
from scenarios.records.model.first_guess import catalogue, static_guess, static_lateral
from scenarios.records.model.model_runs import SETTLE_S, check_record, portable, window_job
from scenarios.records.model.onset_load import ONSET_RATIO, ONSET_STIFFNESS, TOP, load_guess, load_range
from scenarios.records.model.result import Calibration
from scenarios.records.model.uncertainty import uncertainties
from scenarios.records.model.weighting import differential_kernel

__all__ = ["fit_windows", "calibrate",
           "WINDOWS", "WINDOW_S", "WINDOW_LEAD_S", "FD_STEP", "MAX_NFEV", "BLOCK_S", "REUSE_MAX", "REUSE_RATIO"]

#: Windows of the record fitted: how many, scored seconds each, measured lead-in before each (s).
#: The lead-in: a model run started at rest on a moving truck's record carries the start's state
#: error for ~3 s (leaf friction makes it slow: at 2.5 s it is down to ~10 % of the fit's residual
#: on the medium case), so 2.5 s is run and not scored.
WINDOWS, WINDOW_S, WINDOW_LEAD_S = 3, 4.0, 2.5
#: Forward-difference step of each scaled parameter (1: 1 % of a positive field, 1 cm of payload x).
FD_STEP = 0.01
#: Jacobian reuse: after a step whose reduction of the sum of squares is at least :data:`REUSE_RATIO`
#: of the one the last Jacobian predicted, the Jacobian is updated by Broyden's rank-one formula
#: from the step and its residual change instead of recomputed by finite differences (one run of
#: every variant), at most :data:`REUSE_MAX` times in a row (0: always recomputed). The Jacobian
#: the uncertainties are read from is always a finite-difference one at the optimum. Measured on
#: the paper's three cases (30 s, 100 N noise, cab held): 228-266 variants with every Jacobian
#: recomputed, 85-105 with at most 4 updates in a row, the same fit NRMSE and model error to three
#: digits; without a limit 54-72, the model error up to 0.0003 worse.
REUSE_MAX, REUSE_RATIO = 4, 0.5
#: Most residual evaluations of the least squares (the Jacobians come on top, one per iteration).
#: 60: with each axle's stiffening fitted (12 values), a cap of 30 leaves two of the generalization
#: suite's 72 calibrations (30 s, cab held) unconverged, and they fall back to the linear
#: correction: gen17's rigid plant (its front tires sit past any onset, kt and ratio crawl along
#: their valley) and gen04's gradual stiffening; at 60 both converge (0.07-0.09 x and 0.10 x the
#: floor, DLC within 0.24 %). A cap changes nothing for a fit that converges below it (the same
#: trajectory).
MAX_NFEV = 60
#: Block of the robust uncertainty, s: longer than the fit residual's correlation (the truck's
#: slowest modes, ~0.6 s period), short enough for a few dozen blocks in the windows.
BLOCK_S = 0.5


def fit_windows(t_s, n: int = WINDOWS, scored_s: float = WINDOW_S,
                lead_s: float = WINDOW_LEAD_S) -> list[tuple[int, int, int]]:
    """``n`` windows spread evenly over the record: (first run sample, first scored sample, end).

    Raises
    ------
    ScenarioError
        A record shorter than one lead-in plus one scored window.
    """
    t = np.asarray(t_s, dtype=float)
    fs = 1.0 / (t[1] - t[0])
    lead, span = int(round(lead_s * fs)), int(round(scored_s * fs))
    if t.size < lead + span:
        raise ScenarioError(f"the record ({t.size / fs:g} s) is shorter than a calibration window "
                            f"({lead_s:g} s lead-in + {scored_s:g} s); record at least {lead_s + scored_s:g} s")
    starts = np.linspace(lead, t.size - span, n).round().astype(int)
    return [(int(s - lead), int(s), int(s + span)) for s in starts]


class _Problem:
    """The least-squares problem in scaled parameters theta (1 at the first guess).

    Residual: per window, (F_model - F_rig) through the weighting ``kernel`` (zero-phase FIR,
    none: unweighted) on the scored samples, less the kernel's half-length at the end; each wheel
    divided by the std of its measured force on the scored samples. Each theta is the field over
    its first guess (the payload's x: offset by metres), but for the fields of :data:`COMPLIANCE`:
    theta = (guess / value)^2, the mount's compliance over the guess's."""

    def __init__(self, names, t, x_a, force, windows, base, guess, fixed, executor, kernel=None, loads=None,
                 use=None, acc=None):
        self.names, self.t, self.x_a, self.force, self.windows = names, t, x_a, force, windows
        self.use = np.ones(force.shape[1], bool) if use is None else np.asarray(use, bool)  # the wheels fitted
        self.base, self.fixed, self.executor, self.kernel = portable(base), fixed, executor, kernel
        loads = loads or {}  # onset name: (first-guess load, span), N (onset_load)
        start = {k: loads[k] if k in loads else (guess[k], RANGES[k]) for k in names if k in ADDITIVE}
        self.offset = np.array([start[k][0] - start[k][1] if k in start else 0.0 for k in names])
        self.scale = np.array([start[k][1] if k in start else guess[k] for k in names])
        self.compliance = np.array([k in COMPLIANCE for k in names])
        # (onset's index, its kt's index or None, kt held): onset = load / kt
        self.onsets = [(i, names.index(ONSET_STIFFNESS[k]) if ONSET_STIFFNESS[k] in names else None,
                        fixed.get(ONSET_STIFFNESS[k])) for i, k in enumerate(names) if k in loads]
        self.norm = np.concatenate([force[s:e] for _, s, e in windows]).std(axis=0)
        self.half = 0 if kernel is None else kernel.size // 2
        # the pans' acceleration (whole record), weighted as the residual, for the cells' mass
        self.acc = acc
        self.acc_w = self.acc_t = None
        if acc is not None:  # the regressor and its test vector, band-limited once more (cell_mass)
            fs = 1.0 / (t[1] - t[0])
            self.acc_w, self.acc_t = (self.weighted([x[a:e] for a, _, e in windows], subtract=False)
                                      for x in (acc, band_limited(acc, fs)))
        self.evaluations, self.cache = 0, {}
        self.last = None  # (theta, residual, Jacobian, Broyden updates in a row) of the last Jacobian

    def fields(self, theta) -> np.ndarray:
        """The fields' values (SI) of ``theta``."""
        theta = np.asarray(theta, float)
        out = self.offset + self.scale * theta
        c = self.compliance
        out[c] = self.scale[c] / np.sqrt(theta[c])
        for i, j, kt in self.onsets:  # a soft kt tried against a large load: kept within the field's bounds
            out[i] = np.clip(out[i] / (out[j] if j is not None else kt), *BOUNDS[self.names[i]][:2])
        return out

    def mapping(self, theta) -> np.ndarray:
        """d field_i / d theta_j at ``theta`` (SI per 1, n x n): diagonal but for an onset's kt."""
        theta = np.asarray(theta, float)
        c = self.compliance
        slope = self.scale.copy()
        slope[c] = -0.5 * self.scale[c] * theta[c] ** -1.5
        out, values = np.diag(slope), self.fields(theta)
        for i, j, kt in self.onsets:
            out[i, i] = self.scale[i] / (values[j] if j is not None else kt)
            if j is not None:  # onset = load / kt
                out[i, j] = -values[i] / values[j] * self.scale[j]
        return out

    def thetas(self, lower, upper) -> tuple[np.ndarray, np.ndarray]:
        """The bounds on theta of fields bounded by ``lower`` and ``upper`` (SI)."""
        lo, hi = (np.array(lower, float) - self.offset) / self.scale, (np.array(upper, float) - self.offset) / self.scale
        c = self.compliance
        lo[c], hi[c] = (self.scale[c] / np.array(upper, float)[c]) ** 2, (self.scale[c] / np.array(lower, float)[c]) ** 2
        return lo, hi

    def theta_of(self, values, lower, upper) -> np.ndarray:
        """theta of the fields' ``values`` (SI; a field not given: 1, its first guess), clipped into
        the bounds ``lower``, ``upper`` on theta (an onset at the kt this theta gives)."""
        theta = np.ones(len(self.names))
        for i, k in enumerate(self.names):
            if values.get(k) is not None and k not in ONSET_STIFFNESS:
                v = float(values[k])
                theta[i] = (self.scale[i] / v) ** 2 if self.compliance[i] else (v - self.offset[i]) / self.scale[i]
        for i, j, kt in self.onsets:  # onset = load / kt, load = offset + scale theta
            if values.get(self.names[i]) is not None:
                stiffness = self.fields(theta)[j] if j is not None else kt
                theta[i] = (float(values[self.names[i]]) * stiffness - self.offset[i]) / self.scale[i]
        return np.clip(theta, lower, upper)

    def values(self, theta) -> dict[str, float]:
        return dict(zip(self.names, self.fields(theta).tolist()))

    def variant(self, theta) -> TruckVariant:
        return TruckVariant(**self.fixed, **self.values(theta))

    def model(self, thetas) -> list[list[np.ndarray]]:
        """The model's force on each window (lead-in included), per theta."""
        jobs = [(window_job, (self.variant(th), self.t[a:e], self.x_a[a:e], self.base, SETTLE_S))
                for th in thetas for a, _, e in self.windows]
        out = run_jobs(jobs, executor=self.executor)
        self.evaluations += len(thetas)
        w = len(self.windows)
        return [out[i * w:(i + 1) * w] for i in range(len(thetas))]

    def plain(self, model_N) -> np.ndarray:
        """Unweighted residual (scored samples x 4), N."""
        return np.concatenate([m[s - a:] - self.force[s:e] for m, (a, s, e) in zip(model_N, self.windows)])

    def weighted(self, model_N, subtract: bool = True) -> np.ndarray:
        """The residual (model less measured force, or the windows' ``model_N`` alone), weighted
        (rows x 4), N."""
        if self.kernel is None:
            return np.concatenate([m[s - a:] - (self.force[s:e] if subtract else 0.0)
                                   for m, (a, s, e) in zip(model_N, self.windows)])
        from scipy.signal import fftconvolve

        parts = []
        for m, (a, s, e) in zip(model_N, self.windows):
            err = fftconvolve(m - (self.force[a:e] if subtract else 0.0), self.kernel[:, None], mode="same", axes=0)
            parts.append(err[s - a:e - a - self.half])
        return np.concatenate(parts)

    def mass(self, model_N) -> float:
        """The load cells' uncompensated mass that best explains the weighted residual, kg
        (:mod:`~scenarios.records.model.cell_mass`); 0 without the pans' acceleration."""
        return 0.0 if self.acc is None else mass_of(self.weighted(model_N), self.acc_w, self.use / self.norm ** 2, self.acc_t)

    def as_measured(self, model_N) -> list[np.ndarray]:
        """The model's force on each window as the load cells read it (with the cells' mass), N."""
        mass = self.mass(model_N)
        return [m + mass * self.acc[a:e] for m, (a, _, e) in zip(model_N, self.windows)] if mass else model_N

    def residual(self, model_N) -> np.ndarray:
        err = self.weighted(model_N)
        if self.acc is not None:  # variable projection: the cells' mass solved for and taken out
            err = err + mass_of(err, self.acc_w, self.use / self.norm ** 2, self.acc_t) * self.acc_w
        return (err / self.norm)[:, self.use].ravel()

    def fun(self, theta) -> np.ndarray:
        key = tuple(np.asarray(theta, float))
        if key not in self.cache:
            m = self.model([theta])[0]
            self.cache = {key: (self.residual(m), m)}
        return self.cache[key][0]

    def jac(self, theta, lower, upper, reuse: int | None = None) -> np.ndarray:
        """The residual's Jacobian at ``theta``: by forward differences, or (``reuse`` > 0) the last
        one updated by Broyden's formula where it predicted the step's reduction well (:data:`REUSE_MAX`)."""
        theta = np.asarray(theta, float)
        f0 = self.fun(theta)
        if self.last is not None and self.last[3] < (REUSE_MAX if reuse is None else reuse):
            th1, f1, j1, n = self.last
            step = theta - th1
            pred = f1 + j1 @ step
            predicted, actual = f1 @ f1 - pred @ pred, f1 @ f1 - f0 @ f0
            if step @ step > 0.0 and predicted > 0.0 and actual >= REUSE_RATIO * predicted:
                jac = j1 + np.outer(f0 - pred, step / (step @ step))
                self.last = (theta, f0, jac, n + 1)
                return jac
        steps = np.where(theta + FD_STEP <= upper, FD_STEP, -FD_STEP)
        thetas = [theta + h * np.eye(theta.size)[i] for i, h in enumerate(steps)]
        jac = np.column_stack([(self.residual(m) - f0) / h for m, h in zip(self.model(thetas), steps)])
        self.last = (theta, f0, jac, 0)
        return jac

    def final_jac(self, theta, lower, upper) -> np.ndarray:
        """The finite-difference Jacobian at ``theta`` (the last one if it is that)."""
        last = self.last
        if last is not None and last[3] == 0 and np.array_equal(last[0], np.asarray(theta, float)):
            return last[2]
        return self.jac(theta, lower, upper, reuse=0)


def calibrate(t_s, x_a_m, force_N, *, base_scenario: Scenario, x_ref_m=None, names=DEFAULT_NAMES,
              fitted_guess: dict | None = None, start: dict | None = None, wheels=CORNERS,
              windows: int = WINDOWS, window_s: float = WINDOW_S, lead_s: float = WINDOW_LEAD_S,
              workers: int | None = None, max_nfev: int = MAX_NFEV, executor=None, cell_mass: bool = True) -> Calibration:
    """Fit the truck model so that its force, pans following the measured x_a, matches F_rig.

    Parameters
    ----------
    t_s : array_like, s, (n,)
        The record's time axis (uniform, 1 kHz).
    x_a_m : array_like, m, (n, 4)
        Measured pan displacement (LVDTs), corners fl, fr, rl, rr.
    force_N : array_like, N, (n, 4)
        Measured wheel force (load cells, with their noise).
    base_scenario : Scenario
        The rig (actuator stroke) and output rate; its truck is never used.
    x_ref_m : array_like, m, (n, 4), optional
        The drive: given, the residual is weighted by where the differential correction uses the
        model (:mod:`scenarios.records.model.weighting`); None: unweighted.
    names : sequence of str
        The fields to fit (default :data:`DEFAULT_NAMES`); the others of :data:`FITTED` are held at
        their first guess (:attr:`Calibration.fixed`), the cab mount rigid (None) unless
        ``fitted_guess`` gives it.
    fitted_guess : dict, optional
        First guesses (SI) of fitted fields to use instead of the static-load and catalogue ones;
        for a field held (not in ``names``), the value it is held at, where ``cab_mount_hz: None``
        holds the XML's rigid cab (the model family without the cab's mounts) and
        ``tire_progressive_ratio: None`` its linear tire.
    start : dict, optional
        Values (SI) of fitted fields to start the search from instead of their first guess (a fit of
        the same record with fewer fields, say); the search ranges stay the first guess's, and a
        value outside its range starts at the range's edge.
    wheels : sequence of str
        The corners whose measured forces the fit uses (default all four): a channel the model
        cannot reproduce (a broken load cell, a wheel unlike the model's) left out keeps it from
        pulling the others' parameters. An axle with a wheel left out has its left/right factors
        (:data:`STATION_FITTED`) held at 1: one wheel cannot tell left from right.
    windows, window_s, lead_s : int, s, s
        See :func:`fit_windows`.
    workers : int, optional
        Worker processes (default: all cores).
    max_nfev : int
        Most residual evaluations.
    executor : concurrent.futures.Executor, optional
        A running pool to use instead of starting one.
    cell_mass : bool
        Fit the load cells' uncompensated mass too (:mod:`~scenarios.records.model.cell_mass`,
        default); False holds it at 0 (a lab whose mass compensation is known to be exact).

    Returns
    -------
    Calibration

    Raises
    ------
    ScenarioError
        A bad record or static loads that imply no truck (before any model run).
    """
    from scipy.optimize import least_squares

    wall0 = time.perf_counter()
    names = tuple(names)
    unknown = sorted(set(names) - set(FITTED))
    if unknown or not names:
        raise ScenarioError(f"names must be a non-empty subset of {', '.join(FITTED)}, got {', '.join(unknown) or 'none'}")
    tire_only = [k for k in names if k.startswith("tire_progressive") and k != "tire_progressive_ratio"]
    if tire_only and "tire_progressive_ratio" not in names and (fitted_guess or {}).get("tire_progressive_ratio") is None:
        raise ScenarioError(f"{tire_only[0]} is the progressive tire's: fit tire_progressive_ratio too, or give its "
                            "value in fitted_guess")
    wheels = tuple(wheels)
    if not wheels or set(wheels) - set(CORNERS) or len(set(wheels)) != len(wheels):
        raise ScenarioError(f"wheels must be distinct corners of {', '.join(CORNERS)}, got {', '.join(wheels) or 'none'}")
    use = np.array([c in wheels for c in CORNERS])
    # a left/right factor (named by its axle's left corner) needs both wheels of its axle
    names = tuple(k for k in names if k not in STATION_FITTED
                  or set(FRONT if k.endswith(FRONT[0]) else REAR) <= set(wheels))
    t, fs = check_record(t_s, {"x_a_m": x_a_m, "force_N": force_N} | ({} if x_ref_m is None else {"x_ref_m": x_ref_m}))
    x_a, force = np.asarray(x_a_m, float), np.asarray(force_N, float)
    kernel = None if x_ref_m is None else differential_kernel(x_ref_m, x_a, fs)
    wins = fit_windows(t, windows, window_s, lead_s)
    payload, x = static_guess(force, base_scenario)
    if payload == 0.0 and "payload_kg" not in (fitted_guess or {}):  # an empty truck: nothing to fit there
        names = tuple(k for k in names if k not in ("payload_kg", "payload_x_m"))
        if not names:
            raise ScenarioError("the measured loads are those of an empty truck, which has no payload to fit; "
                                "name other fields to fit")
    # The payload's centre across the truck: pinned by the measured left/right moment (held, not fitted).
    y = static_lateral(force, base_scenario, payload, x)
    guess = {"payload_kg": payload, "payload_x_m": x, "payload_y_m": y, **catalogue(),
             **dict.fromkeys(STATION_FITTED, 1.0), **(fitted_guess or {})}
    held = [k for k in FITTED if k == "cab_mount_hz" or k.startswith("tire_progressive") or k in STATION_FITTED]
    for k in held:  # held: rigid cab, linear tire, left and right stations alike
        if k not in names and k not in (fitted_guess or {}):
            guess[k] = None
    lower, upper, loads = [], [], {}
    fixed = {k: None if v is None else float(v) for k, v in guess.items() if k not in names}
    for k in names:
        if guess[k] is None:
            raise ScenarioError(f"fitted_guess gives no value for {k}, which is fitted; give a number or leave it out "
                                "of names")
        if k in ONSET_STIFFNESS:  # searched as the load where the tire stiffens (onset_load), N
            kt = guess[ONSET_STIFFNESS[k]]
            (a, b), load = load_range(force, wins, k), load_guess(force, wins, k, (fitted_guess or {}).get(k), kt)
            b = max(b, a + 1.0)  # a range, however narrow (least squares needs lower < upper)
            loads[k], guess[k] = (load, b - a), load / kt
        else:
            lo, hi = BOUNDS.get(k, (-3.5, 3.5) if k == "payload_x_m" else (0.0, np.inf))[:2]
            r = RANGES[k]
            a, b = (guess[k] - r, guess[k] + r) if k in ADDITIVE else (guess[k] * r[0], guess[k] * r[1])
            a, b = max(a, lo), min(b, hi)
        lower.append(a)
        upper.append(b)
    with local_executor(workers) if executor is None else contextlib.nullcontext(executor) as ex:
        acc = band_acceleration(x_a, fs) if cell_mass else None
        prob = _Problem(names, t, x_a, force, wins, base_scenario, guess, fixed, ex, kernel, loads, use, acc)
        lb, ub = prob.thetas(lower, upper)
        theta0 = prob.theta_of(start or {}, lb, ub)
        prob.fun(theta0)
        m_init = prob.as_measured(prob.cache[tuple(theta0)][1])
        res = least_squares(prob.fun, theta0, jac=lambda th: prob.jac(th, lb, ub), bounds=(lb, ub), method="trf",
                            x_scale=1.0, ftol=1e-4, xtol=1e-4, gtol=1e-6, max_nfev=max_nfev)
        jac = prob.final_jac(res.x, lb, ub)
        f_opt, m_run = prob.fun(res.x), prob.cache[tuple(np.asarray(res.x, float))][1]
        m_opt, mass = prob.as_measured(m_run), prob.mass(m_run)
        mass_1s = 0.0 if acc is None else mass_sigma(prob.weighted(m_run) + mass * prob.acc_w, prob.acc_w,
                                                     use / prob.norm ** 2, int(round(BLOCK_S * fs)), prob.acc_t)
    sigma, robust = uncertainties(jac, f_opt, int(round(BLOCK_S * fs)), prob.mapping(res.x), int(use.sum()))
    fitted, linear = prob.fields(res.x), []
    for i, j, kt in prob.onsets:
        ratio = ONSET_RATIO[names[i]]  # a stiffening beyond every measured load: the tire held linear (TOP)
        if ratio in names and ub[i] - res.x[i] <= TOP * (ub[i] - lb[i]) and fitted[names.index(ratio)] > 0.0:
            fitted[names.index(ratio)] = 0.0
            linear.append(ratio)
        # the onset's range reported in metres, at the fitted kt
        lower[i], upper[i] = (v / (fitted[j] if j is not None else kt) for v in (lower[i], upper[i]))

    def per_wheel(model_N):
        return tuple(float(v) for v in np.sqrt(np.mean(prob.plain(model_N) ** 2, axis=0)) / prob.norm)

    noise = noise_rms(force, fs)  # the load cells' white noise (whole record), N
    band, band_noise = band_errors(m_opt, force, wins, fs, noise)

    return Calibration(names=names, units=tuple(UNITS[k] for k in names),
                       initial=tuple(float(guess[k]) for k in names), fitted=tuple(float(v) for v in fitted),
                       sigma=tuple(float(s) for s in sigma), sigma_robust=tuple(float(s) for s in robust), fixed=fixed, fit_nrmse=per_wheel(m_opt),
                       initial_nrmse=per_wheel(m_init), weighted=kernel is not None,
                       windows_s=tuple((float(t[s]), float(t[e - 1] + 1.0 / fs)) for _, s, e in wins),
                       evaluations=int(prob.evaluations), converged=bool(res.status > 0),
                       message=str(res.message) + "".join(f"; {k} set to 0 (its onset lies beyond every measured load)"
                                                          for k in linear), wall_time_s=round(time.perf_counter() - wall0, 3),
                       bounds=tuple((float(a), float(b)) for a, b in zip(lower, upper)),
                       noise_nrmse=tuple(float(v) for v in noise / prob.norm), band_nrmse=band,
                       band_noise_nrmse=band_noise, wheels=tuple(c for c in CORNERS if c in wheels),
                       cell_mass_kg=float(mass), cell_mass_sigma_kg=mass_1s)

