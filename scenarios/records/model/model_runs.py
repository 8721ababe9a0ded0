"""Truck-model runs driven by measured pan motion: the model half of the model correction.

:func:`model_forces` is the road test of a truck variant (:class:`rigsim.mjcf.variant.TruckVariant`) whose
wheelpans follow a given motion sampled at the output rate (a rig's drive x_ref or its LVDTs'
x_a, 1 kHz): the motion is interpolated onto the road test's steps (:data:`MODEL_STEP_S`) by a cubic
spline (positions, velocities and the mid-step values each step holds, all from the one spline), and
the forces on those steps are splined back onto the samples; the truck starts from static rest on the
pans at the first sample's positions and is held there for a settling lead-in
(:data:`SETTLE_S`, so the leaf springs' dry friction and the soft constraints settle), then the
pans follow the motion. It uses the one rig (:class:`rigsim.scenarios.core.rig.Rig`, ``hydraulic=False``)
and nothing of a road: only measured signals enter.

:func:`static_axle_loads` gives the static tire loads of a variant at rest (the catalogue
truck's weight split, used for the calibration's first guess), :func:`window_job` is the
picklable unit of work the calibration sends to the worker pool.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rigsim.mjcf.variant import TruckVariant
from rigsim.mjcf.physics import EquilibriumError, tire_forces
from rigsim.scenarios.core.config import Scenario, ScenarioError
from rigsim.scenarios.core.drive import Drive
from rigsim.scenarios.core.rig import Rig, rig_step_s

__all__ = ["SETTLE_S", "MODEL_STEP_S", "LIFT_FRACTION", "model_step", "NoRestError", "on_samples", "model_forces",
           "pan_motion_drive", "static_axle_loads", "window_job", "fit_window_job", "check_record", "portable"]

#: Settling lead-in before a model run follows its pan motion, s: the truck is put at static
#: rest on the pans' first positions (the frictionless equilibrium, :meth:`Rig.rest_state`), then
#: held there with the leaves' friction on, so that the friction's soft constraint settles before
#: the pans move. It does not remove the other start-up: the truck on the rig was moving at the
#: record's first sample, the model's is at rest (see ``differential.START_S`` and
#: ``calibrate.WINDOW_LEAD_S``, which handle that).
SETTLE_S = 0.5
#: The model runs' integration step, s (RK4, as the rig's runs): their forces are computed on these
#: steps and splined (cubic, not-a-knot) onto the record's samples. Against the same truck run at
#: 2.5e-4 s, the forces' error is 0.0002 of their std at 1e-3 s, 0.0008 at 2e-3 s, 0.002 at
#: 3e-3 s and 0.004 at 4e-3 s, where the load cells' 100 N of noise is 0.006-0.03 of it
#: (``benchmarks/model_step.py``, docs/results/model_step.md); a run costs about the step's inverse.
MODEL_STEP_S = 2e-3
#: A wheel leaves its pan where its measured force falls below this share of its mean, 1: a tire's
#: force kinks at zero load, which steps of :data:`MODEL_STEP_S` resolve too coarsely for the fit
#: (:func:`model_step`). Measured on the generalization suite's gen15 (an empty truck on a class D
#: road at 100 km/h, whose rear wheels lift): against 0.25 ms, the forces' error 0.0005 of their std
#: at 1 ms and 0.002 at 2 ms (a third of the load cells' noise there), the largest 71 N and 776 N
#: (``benchmarks/model_step.py``); calibrated at 2 ms its tire plant's rear
#: wheels ended at 1.11 of the linear floor, at 1 ms 0.00.
LIFT_FRACTION = 0.05


def check_record(t_s, signals: dict) -> tuple[np.ndarray, float]:
    """Check a measured record before any run: ``t_s`` (s) 1-D, uniformly spaced, increasing;
    each of ``signals`` (name -> array) of shape (n, 4) and finite. Returns (t_s, rate in Hz).

    Raises
    ------
    ScenarioError
        Naming the field and the fix (one sentence).
    """
    t = np.asarray(t_s, dtype=float)
    if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)):
        raise ScenarioError(f"t_s must be a finite 1-D time axis of at least 2 samples, got shape {t.shape}; "
                            "pass the record's time column in s")
    dt = np.diff(t)
    if not (dt[0] > 0 and np.allclose(dt, dt[0], rtol=1e-6, atol=1e-12)):
        raise ScenarioError("t_s must be uniformly spaced and increasing; resample the record to a constant rate")
    for name, arr in signals.items():
        a = np.asarray(arr, dtype=float)
        if a.shape != (t.size, 4):
            raise ScenarioError(f"{name} must have shape ({t.size}, 4) (samples x corners fl, fr, rl, rr), "
                                f"got {a.shape}; pass one column per wheel on the record's time axis")
        if not np.all(np.isfinite(a)):
            raise ScenarioError(f"{name} contains NaN or infinite values; clean or cut the record first")
    return t, float(1.0 / dt[0])


def model_step(force_N, rate_hz: float) -> float:
    """The model runs' step for a record whose measured wheel forces are ``force_N`` (N, (n, 4)) at
    ``rate_hz`` (Hz), s: :data:`MODEL_STEP_S`, or where any wheel's force falls below
    :data:`LIFT_FRACTION` of its mean (a wheel that leaves its pan) the rig's own step
    (:func:`~rigsim.scenarios.core.rig.rig_step_s`), whose samples the runs then give without a spline."""
    force = np.asarray(force_N, dtype=float)
    mean = force.mean(axis=0)
    if np.any(force.min(axis=0) < LIFT_FRACTION * mean):
        return rig_step_s(rate_hz)
    return MODEL_STEP_S


def pan_motion_drive(t_s, pan_m, dt_s: float, settle_s: float = SETTLE_S, start_m=None) -> Drive:
    """The pans' drive on the model's steps: ``pan_m`` (m, (n, 4), sampled at ``t_s``, s) through
    a cubic spline (not-a-knot) onto steps of ``dt_s`` (s) from ``-settle_s`` (s) before the first
    sample to the first step at or past the last one (the spline extrapolated by less than a step);
    held at the first sample (velocity 0) during the lead-in, or, with ``start_m`` (m, (4,)), moved
    from ``start_m`` to the first sample over the lead-in (a half-cosine: at rest at both ends). Each
    step holds the drive's value at mid-step (:meth:`Drive.held`; the last step's is extrapolated).
    Times are relative to ``t_s[0]``."""
    from scipy.interpolate import CubicSpline

    t = np.asarray(t_s, dtype=float) - float(t_s[0])
    x = np.asarray(pan_m, dtype=float)
    n_lead = int(round(settle_s / dt_s))
    k = np.arange(-n_lead, int(np.ceil(t[-1] / dt_s - 1e-6)) + 1)
    tt = k * dt_s
    spline = CubicSpline(t, x, axis=0)
    ahead = k >= 0
    z = np.empty((k.size, 4))
    v = np.zeros((k.size, 4))
    z[ahead] = spline(tt[ahead])
    v[ahead] = spline(tt[ahead], 1)
    mid = tt + 0.5 * dt_s
    held = spline(np.maximum(mid, 0.0))
    if start_m is None:
        z[~ahead] = x[0]
        held[mid < 0.0] = x[0]
    else:
        z0, dz = np.asarray(start_m, float), x[0] - np.asarray(start_m, float)

        def ramp(tau):  # 0 at -settle_s, 1 at 0
            return 0.5 - 0.5 * np.cos(np.pi * (tau + settle_s) / settle_s)

        z[~ahead] = z0 + ramp(tt[~ahead])[:, None] * dz
        v[~ahead] = (0.5 * np.pi / settle_s * np.sin(np.pi * (tt[~ahead] + settle_s) / settle_s))[:, None] * dz
        held[mid < 0.0] = z0 + ramp(mid[mid < 0.0])[:, None] * dz
    return Drive(tt, z, v, held_m=held)


def planar_part(rig: Rig, pan_m) -> np.ndarray:
    """The pans' heights (m, (4,)) on the plane that best fits ``pan_m`` (m, (4,)) at the pans'
    positions (least squares, z = a + b x + c y): the pose without its twist, which a truck whose
    frame is stiff in torsion can stand on."""
    xy = rig.model.body_pos[rig.index.pan_body][:, :2]
    a = np.column_stack([np.ones(4), xy])
    coef, *_ = np.linalg.lstsq(a, np.asarray(pan_m, float), rcond=None)
    return a @ coef


def model_scenario(variant: TruckVariant, base_scenario: Scenario, duration_s: float, settle_s: float) -> Scenario:
    """``base_scenario`` (output rate, actuator stroke) carrying ``variant`` as its whole truck."""
    return dataclasses.replace(base_scenario, vehicle=variant, duration_s=float(duration_s),
                               lead_in_s=float(settle_s))


class NoRestError(ScenarioError):
    """A model truck that finds no rest on the pans' first pose (one sentence)."""


def model_forces(variant: TruckVariant, t_s, pan_m, *, base_scenario: Scenario,
                 settle_s: float = SETTLE_S, step_s: float | None = None) -> np.ndarray:
    """Tire forces of the truck ``variant`` with its pans following ``pan_m``.

    Parameters
    ----------
    variant : TruckVariant
        The model truck (every field; nothing is taken from ``base_scenario.vehicle``).
    t_s : array_like, s, (n,)
        Sample times of the motion (uniform: 1 kHz, say).
    pan_m : array_like, m, (n, 4)
        Pan displacement per corner (fl, fr, rl, rr) from mid-stroke: the drive x_ref or the
        measured x_a.
    base_scenario : Scenario
        Supplies the actuator stroke (the pans' travel) and the output rate; its truck is not used.
    settle_s : float, s
        Settling lead-in at the first sample's positions (see :data:`SETTLE_S`).
    step_s : float, s, optional
        The integration step (:func:`model_step` chooses it for a record; default
        :data:`MODEL_STEP_S`).

    Returns
    -------
    numpy.ndarray, N, (n, 4)
        Tire force on each pan at the samples ``t_s`` (compression positive): the force of the
        state at that instant (as the rig's load cells and the road test record it) where the
        step divides the sample interval, else the force at each step splined onto the samples.

    Raises
    ------
    ScenarioError
        A bad record, a motion that leaves the stroke, or a truck with no rest (before the run).
    """
    t, fs = check_record(t_s, {"pan_m": pan_m})
    sc = model_scenario(variant, base_scenario, t[-1] - t[0], settle_s)
    rig = Rig(sc, hydraulic=False, timestep_s=MODEL_STEP_S if step_s is None else step_s)
    decim = 1.0 / (fs * rig.dt_s)
    on_steps = abs(decim - round(decim)) < 1e-6  # the samples fall on steps: recorded there, no spline
    rate = fs if on_steps else 1.0 / rig.dt_s
    drive = pan_motion_drive(t, pan_m, rig.dt_s, settle_s)
    try:
        drive.check_stroke(rig.half_stroke_m)
    except ValueError as exc:
        raise ScenarioError(f"pan motion: {exc}") from None
    try:
        rec = rig.run(drive, rate_hz=rate)  # its first act is the rest state: a truck with none stops before a step
    except EquilibriumError:
        # No rest on the first pose, even moved there from mid-stroke (static_equilibrium's
        # continuation): start on its planar part, which a truck whose frame is stiff in torsion
        # can stand on, and twist the pans in over the lead-in, which ends before any scored sample.
        drive = pan_motion_drive(t, pan_m, rig.dt_s, settle_s, start_m=planar_part(rig, np.asarray(pan_m)[0]))
        try:
            rec = rig.run(drive, rate_hz=rate)
        except EquilibriumError as exc:
            raise NoRestError(f"model truck: {exc}") from None
    if on_steps:
        if rec.tire_force_N.shape != (t.size, 4):
            raise RuntimeError(f"the model run gave {rec.tire_force_N.shape[0]} samples for {t.size}")
        return np.asarray(rec.tire_force_N)
    return on_samples(rec.t_s, rec.tire_force_N, t - t[0])


def on_samples(step_t_s, force_N, t_s) -> np.ndarray:
    """A model run's force (N, (m, 4)) at its steps ``step_t_s`` (s, from 0) splined (cubic,
    not-a-knot) onto the record's sample times ``t_s`` (s, from 0, within the steps), N, (n, 4)."""
    from scipy.interpolate import CubicSpline

    step_t, tt = np.asarray(step_t_s, float), np.asarray(t_s, float)
    if step_t.size < 4 or tt[-1] > step_t[-1] + 1e-9:
        raise RuntimeError(f"the model run's {step_t.size} steps end at {step_t[-1]:g} s, before the record's "
                           f"last sample at {tt[-1]:g} s")
    return CubicSpline(step_t, np.asarray(force_N, float), axis=0)(tt)


def static_axle_loads(variant: TruckVariant, base_scenario: Scenario) -> np.ndarray:
    """Static tire load of each wheel (N, (4,)) of ``variant`` at rest on the pans at mid-stroke
    (dry friction off: the frictionless equilibrium)."""
    rig = Rig(model_scenario(variant, base_scenario, 1.0, SETTLE_S), hydraulic=False)
    data = rig.rest_state()
    return np.asarray(tire_forces(rig.model, data, rig.index), dtype=float)


def portable(scenario: Scenario) -> Scenario:
    """``scenario`` with its actuator overrides as a plain dict, so that it pickles to a worker
    (a :class:`types.MappingProxyType` does not)."""
    return dataclasses.replace(scenario, actuator=dict(scenario.actuator))


def window_job(variant: TruckVariant, t_s, pan_m, base_scenario: Scenario, settle_s: float,
               step_s: float | None = None) -> np.ndarray:
    """:func:`model_forces` as a worker job (positional arguments only)."""
    return model_forces(variant, t_s, pan_m, base_scenario=base_scenario, settle_s=settle_s, step_s=step_s)


def fit_window_job(variant: TruckVariant, t_s, pan_m, base_scenario: Scenario, settle_s: float,
                   step_s: float | None = None) -> np.ndarray | None:
    """:func:`window_job` for a fit's trial truck: None where that truck finds no rest on the window's first
    pose (:class:`NoRestError`: a trial far from the first guess, soft air springs under a high load that
    roll it over, say), which the fit scores as the worst of fits rather than ending on it."""
    try:
        return window_job(variant, t_s, pan_m, base_scenario, settle_s, step_s)
    except NoRestError:
        return None
