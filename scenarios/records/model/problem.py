"""The calibration's least-squares problem: scaled parameters, the weighted residual, its Jacobian.

:func:`rigsim.scenarios.records.model.calibrate.calibrate` sets it up and hands it to
``scipy.optimize.least_squares``; the load cells' mass is solved for inside the residual
(:mod:`rigsim.scenarios.records.model.cell_mass`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigsim.mjcf.variant import BOUNDS, TruckVariant
from rigsim.scenarios.core.pool import run_jobs
from rigsim.scenarios.records.model.cell_mass import band_limited, mass_of, mass_sigma
from rigsim.scenarios.records.model.family import ADDITIVE, COMPLIANCE, RANGES
from rigsim.scenarios.records.model.model_runs import SETTLE_S, fit_window_job, model_step, portable
from rigsim.scenarios.records.model.onset_load import ONSET_STIFFNESS

__all__ = ["FitProblem", "FitState", "FD_STEP", "REUSE_MAX", "REUSE_RATIO"]

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


@dataclass(frozen=True)
class FitState:
    """A finished fit as its least-squares problem left it: for a question about the optimum that
    needs model runs through the same residual (:func:`~rigsim.scenarios.records.model.cab_choice.cab_scan`).

    Attributes
    ----------
    problem : FitProblem
        The problem (its worker pool is the caller's; used only while that pool runs).
    theta : numpy.ndarray
        The optimum, scaled parameters (1).
    jacobian : numpy.ndarray or None
        The residual's finite-difference Jacobian there (residuals x parameters, 1); None where the
        calibration left its uncertainties for later (``calibrate(sigma=False)``).
    residual : numpy.ndarray
        The weighted residual there (1).
    upper : numpy.ndarray or None
        The upper bounds on theta (1): a finite-difference step that would pass one is taken backwards.
    """

    problem: "FitProblem"
    theta: np.ndarray
    jacobian: np.ndarray | None
    residual: np.ndarray
    upper: np.ndarray | None = None


class FitProblem:
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
        self.acc_w = self.acc_t = self.mass_weights = None
        if acc is not None:
            self.mass_weights = self.use / self.norm ** 2  # the residual's weight per wheel, 1/N^2
            # the regressor and its test vector, band-limited once more (cell_mass)
            fs = 1.0 / (t[1] - t[0])
            self.acc_w, self.acc_t = (self.weighted([x[a:e] for a, _, e in windows], subtract=False)
                                      for x in (acc, band_limited(acc, fs)))
        # the model runs' step (a wheel that lifts: finer); None where no record is given (a problem for its mappings)
        self.step_s = None if force is None or t is None else model_step(force, 1.0 / (t[1] - t[0]))
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
        return self.runs([self.variant(th) for th in thetas])

    def runs(self, variants) -> list[list[np.ndarray]]:
        """The force of each truck variant (:class:`~rigsim.mjcf.variant.TruckVariant`) on each window
        (lead-in included), N: one worker job per window and variant, all at once."""
        jobs = [(fit_window_job, (v, self.t[a:e], self.x_a[a:e], self.base, SETTLE_S, self.step_s))
                for v in variants for a, _, e in self.windows]
        sizes = [e - a for _ in variants for a, _, e in self.windows]
        # a trial truck with no rest predicts no force: the whole measured force is its residual
        out = [np.zeros((n, 4)) if f is None else f for f, n in zip(run_jobs(jobs, executor=self.executor), sizes)]
        self.evaluations += len(variants)
        w = len(self.windows)
        return [out[i * w:(i + 1) * w] for i in range(len(variants))]

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

    def cell_mass(self, model_N, block: int) -> tuple[float, float]:
        """The load cells' uncompensated mass that best explains the weighted residual and its
        block-robust 1-sigma over blocks of ``block`` rows, kg (:mod:`~rigsim.scenarios.records.model.cell_mass`);
        (0, 0) without the pans' acceleration."""
        if self.acc is None:
            return 0.0, 0.0
        err = self.weighted(model_N)
        mass = mass_of(err, self.acc_w, self.mass_weights, self.acc_t)
        return mass, mass_sigma(err + mass * self.acc_w, self.acc_w, self.mass_weights, block, self.acc_t)

    def as_measured(self, model_N, mass: float) -> list[np.ndarray]:
        """The model's force on each window as the load cells read it with ``mass`` (kg) on them, N."""
        return [m + mass * self.acc[a:e] for m, (a, _, e) in zip(model_N, self.windows)] if mass else model_N

    def residual(self, model_N) -> np.ndarray:
        err = self.weighted(model_N)
        if self.acc is not None:  # variable projection: the cells' mass solved for and taken out
            err = err + mass_of(err, self.acc_w, self.mass_weights, self.acc_t) * self.acc_w
        return (err / self.norm)[:, self.use].ravel()

    def fun(self, theta) -> np.ndarray:
        key = tuple(np.asarray(theta, float))
        if key not in self.cache:
            m = self.model([theta])[0]
            self.cache = {key: (self.residual(m), m)}
        return self.cache[key][0]

    def jac(self, theta, upper, reuse: int | None = None) -> np.ndarray:
        """The residual's Jacobian at ``theta`` (a step that would pass ``upper`` is taken backwards):
        by forward differences, or (``reuse`` > 0) the last
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

    def final_jac(self, theta, upper) -> np.ndarray:
        """The finite-difference Jacobian at ``theta`` (the last one if it is that)."""
        last = self.last
        if last is not None and last[3] == 0 and np.array_equal(last[0], np.asarray(theta, float)):
            return last[2]
        return self.jac(theta, upper, reuse=0)
