"""The model correction: a truck model calibrated on the record predicts what the rig did to the force.

A truck model driven by the rig's measured pan motion x_a should reproduce the measured wheel
force F_rig; driven by the drive x_ref (the road profile) it predicts the road force. Two ways
to use it:

* the differential correction, F_rig + F_model(x_ref) - F_model(x_a): the model only has to
  predict the change the actuators' error x_a - x_ref causes, its own errors largely cancel;
  unfiltered (nothing is inverted);
* with the record's linear correction L (``T_a^-1 T_F`` per wheel), F_model(x_ref) +
  L(W(F_rig - F_model(x_a))): the part of the rig force the model does not explain (a left/right
  asymmetry, a damper's nonlinearity, the lab's channels) is corrected for the actuators too
  instead of being kept as the rig made it. It equals L(F_rig) plus the model's estimate of L's
  own error, so it tends to the linear correction as the model explains less. W takes the load
  cells' white noise out of that residual where it outweighs the model's error
  (:mod:`rigsim.correction.output.denoise`): with the truck's force explained by the model, the residual
  is mostly noise, and on a smooth road that noise is a large part of what is left to correct.
  W also takes the residual's slow part out, below :data:`~rigsim.correction.output.denoise.DRIFT_HZ`
  (0.7 Hz), as far as it is at the load cells' drift level
  (:data:`~rigsim.correction.output.denoise.DRIFT_RMS_N`): there the load cells drift (a lab's coloured
  noise, tens of newtons) and the pans follow the drive, so the model's F_model(x_ref) carries the
  slow force alone; a slow residual far above any drift is the model's own error (a body roll mode
  at 0.3-0.7 Hz that it misses) and is kept, corrected like the rest. On a loaded truck
  on a smooth road, whose front wheels' slow force is small, the drift is a large part of what the
  correction leaves without the cut (``benchmarks/mismatch_suite.py --drift-cut-hz 0`` with
  ``--lab typical`` and ``--lab typical-no-drift`` measures it). A lab whose cells do not drift
  can switch the cut off (``drift_hz=None``).

Both model runs start from rest while the truck on the rig was already moving at the record's
first sample; the two start-up errors largely cancel, but not wholly (the road's and the rig's
truck states at t = 0 differ, and the leaves' friction lets the difference decay slowly): the
first :data:`START_S` of the corrected force are not settled (:func:`settled_mask`), as the
linear correction's filter transients are not.

:func:`correct_with_model` calibrates the model from the record
(:func:`rigsim.scenarios.records.model.calibrate.calibrate`) and corrects, or says in one
sentence why the linear correction is to be used instead: the calibration did not converge or could
not run; the calibrated model does not reproduce F_rig's dynamic part in the correction's band
beyond the load cells' noise (without L, on any wheel; with L, on the wheels it names), on the
calibration's windows or over the whole record the correction runs it on; with L, the model's own runs show
that L could turn the model's residual against the hybrid on the wheels it names
(derived from the linear correction's error on the model truck and what L does to the residual,
the DLC guarded apart). The limits, those decisions and their sentences are
:mod:`~rigsim.scenarios.records.model.fallback`'s.
"""

from __future__ import annotations

import contextlib
import dataclasses
import time

import numpy as np

from rigsim.correction.output.denoise import DRIFT_HZ, DRIFT_RMS_N, NoiseGain, check_drift_hz, design_noise_gain
from rigsim.mjcf.variant import TruckVariant
from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.config import Scenario, ScenarioError
from rigsim.scenarios.core.pool import local_executor, run_jobs
from rigsim.scenarios.core.watch import SimulationError
from rigsim.scenarios.records.model.cab_choice import AUTO, check_cab
from rigsim.scenarios.records.model.cell_mass import without_cell_mass
from rigsim.scenarios.records.model.frame_choice import calibrate_truck
from rigsim.scenarios.records.model.band_error import record_errors
from rigsim.scenarios.records.model.fallback import (calibration_failed, differential_holds, fallback_reason,
                                                     hybrid_outlook, hybrid_reason, model_error_limit, outlier_reason,
                                                     outlier_wheel, record_holds, record_reason)
from rigsim.scenarios.records.model.calibrate import WINDOW_LEAD_S, WINDOW_S, WINDOWS, fit_windows
from rigsim.scenarios.records.model.model_runs import SETTLE_S, check_record, model_step, portable, window_job
from rigsim.scenarios.records.model.restart import calibrate_again
from rigsim.scenarios.records.model.result import LINEAR, MODEL, Calibration, ModelCorrection
from rigsim.scenarios.records.model.saved import check_saved
from rigsim.scenarios.records.model.refine import refine_on_record, refined_names

__all__ = ["START_S", "HYBRID_FORMULA", "DIFFERENTIAL_FORMULA", "model_force_pair", "model_forces_on",
           "differential_correction",
           "hybrid_correction", "settled_mask", "correct_with_model"]

#: The model runs' start-up transient, s: samples before it are not settled. Measured on the
#: medium 72 km/h case with the exact truck as model: the differential's start-up error (rms per
#: wheel) is 0.4-1.5 kN in the first 0.1 s, 0.1-0.2 kN at 1-2 s, 35-90 N at 3-5 s and 10-25 N
#: after 5 s, against the load cells' 25 N rms through the 30 Hz band limit.
START_S = 3.0


def settled_mask(t_s, start_s: float = START_S) -> np.ndarray:
    """Samples (bool, (n,)) past the model runs' start-up (``start_s``, s, after the first sample)."""
    t = np.asarray(t_s, dtype=float)
    return (t - t[0]) >= start_s - 1e-9


def model_force_pair(variant: TruckVariant, t_s, x_ref_m, x_a_m, *, force_N, base_scenario: Scenario,
                     workers: int | None = None, executor=None) -> tuple[np.ndarray, np.ndarray]:
    """The model truck's wheel forces (N, (n, 4)) on pans following the drive and following the
    measured pans: ``(F_model(x_ref), F_model(x_a))``, on the step the record's measured force
    ``force_N`` (N) calls for (:func:`~rigsim.scenarios.records.model.model_runs.model_step`);
    parameters as :func:`differential_correction`'s."""
    check_record(t_s, {"x_ref_m": x_ref_m, "x_a_m": x_a_m, "force_N": force_N})  # refused by these names
    return model_forces_on(variant, t_s, (x_ref_m, x_a_m), force_N=force_N, base_scenario=base_scenario,
                           workers=workers, executor=executor)


def model_forces_on(variant: TruckVariant, t_s, pans_m, *, force_N, base_scenario: Scenario,
                    workers: int | None = None, executor=None) -> tuple:
    """The model truck's wheel forces (N, (n, 4)) on each of ``pans_m`` (a sequence of pan motions,
    m, (n, 4) each), one run each from the record's first sample, in parallel, on the step the
    record's measured force ``force_N`` (N) calls for; :func:`model_force_pair` runs the drive and
    the measured pans, a saved calibration's check (:func:`~rigsim.scenarios.records.model.saved.check_saved`)
    the measured pans alone where its tire is refitted after it."""
    t, fs = check_record(t_s, {"force_N": force_N} | {f"pans_m[{i}]": x for i, x in enumerate(pans_m)})
    base, step = portable(base_scenario), model_step(force_N, fs)
    jobs = [(window_job, (variant, t, np.asarray(x, float), base, SETTLE_S, step)) for x in pans_m]
    return tuple(run_jobs(jobs, workers=workers, executor=executor))


def differential_correction(variant: TruckVariant, t_s, x_ref_m, x_a_m, force_N, *, base_scenario: Scenario,
                            workers: int | None = None, executor=None) -> np.ndarray:
    """F_rig + F_model(x_ref) - F_model(x_a) per wheel, N, (n, 4).

    Parameters
    ----------
    variant : TruckVariant
        The model truck (a calibration's :meth:`~rigsim.scenarios.records.model.result.Calibration.variant`).
    t_s : array_like, s, (n,)
        The record's time axis (uniform, 1 kHz).
    x_ref_m, x_a_m : array_like, m, (n, 4)
        The drive and the measured pan displacement, corners fl, fr, rl, rr.
    force_N : array_like, N, (n, 4)
        The measured wheel force.
    base_scenario : Scenario
        The rig (actuator stroke) and output rate; its truck is not used.
    workers : int, optional
        Worker processes for the two model runs (default: all cores, at most 2 used).
    executor : concurrent.futures.Executor, optional
        A running pool to use instead.
    """
    check_record(t_s, {"x_ref_m": x_ref_m, "x_a_m": x_a_m, "force_N": force_N})
    f_ref, f_a = model_force_pair(variant, t_s, x_ref_m, x_a_m, force_N=force_N, base_scenario=base_scenario,
                                  workers=workers, executor=executor)
    return np.asarray(force_N, dtype=float) + f_ref - f_a


def hybrid_correction(force_N, f_ref_N, f_a_N, linear, fs_hz: float, settled=None, *,
                      drift_hz: float | None = DRIFT_HZ,
                      drift_rms_N: float | None = DRIFT_RMS_N, with_residual: bool = False) -> tuple:
    """F_model(x_ref) + L(W(F_rig - F_model(x_a))) per wheel: :data:`HYBRID_FORMULA`.

    Parameters
    ----------
    force_N : array_like, N, (n, 4)
        The measured wheel force, the load cells' uncompensated mass taken out.
    f_ref_N, f_a_N : array_like, N, (n, 4)
        The model's forces on pans following the drive and the measured pans (:func:`model_force_pair`).
    linear : callable
        The record's linear correction L: ``linear(forces)`` -> ``(corrected (N), settled (bool, (n,)))``.
    fs_hz : float, Hz
        The record's rate.
    settled : array_like of bool, (n,), optional
        The samples past the model runs' start-up (:func:`settled_mask`, a run of samples to the
        record's end). W is designed and applied on them alone: the start-up transient's residual
        (kilonewtons) would raise the residual's spectrum and, where W keeps little but the mean,
        shift the whole record by that transient's share of the mean. Before them the residual
        entering L is held at W's first settled value. None: every sample is settled.
    drift_hz : float or None, Hz
        The corner of W's drift cut (default :data:`~rigsim.correction.output.denoise.DRIFT_HZ`): below it
        the residual is taken for the load cells' drift and the model's slow force stands alone.
        None: no drift cut, for a lab whose cells do not drift (W takes the white noise only).
    drift_rms_N : float or None, N
        The load cells' drift level (default :data:`~rigsim.correction.output.denoise.DRIFT_RMS_N`): a
        wheel's slow residual at that level is cut as drift, one far above it is the model's error
        and kept (:func:`~rigsim.correction.output.denoise.drift_keep`); None: cut whatever its level.
    with_residual : bool
        Return the residual L corrected, ``W(F_rig - F_model(x_a))`` (N, (n, 4)), too.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray, NoiseGain)
        The corrected force (N, (n, 4)), L's settled samples (bool, (n,)) and W, the gain that took
        the residual's white noise and its slow part (the load cells' drift, below ``drift_hz``)
        out (its ``noise_rms``, N, and ``measured`` per wheel); with ``with_residual``, the
        residual L corrected fourth.
    """
    residual = np.asarray(force_N, dtype=float) - f_a_N
    first = 0 if settled is None else int(np.argmax(np.asarray(settled, dtype=bool)))
    if settled is not None and not np.all(np.asarray(settled, dtype=bool)[first:]):
        raise ValueError("settled must be one run of samples reaching the record's end")
    gain = design_noise_gain(residual[first:], fs_hz, drift_hz=drift_hz, drift_rms=drift_rms_N)
    body = gain.apply(residual[first:])
    denoised = np.concatenate([np.repeat(body[:1], first, axis=0), body], axis=0)
    corrected, lin_settled = linear(denoised)
    out = (np.asarray(f_ref_N, dtype=float) + corrected, lin_settled, gain)
    return out + (denoised,) if with_residual else out


#: The model correction with the linear correction L of the model's residual (``linear`` given).
HYBRID_FORMULA = "F_model(x_ref) + L(W(F_rig - F_model(x_a)))"
#: The differential model correction (no ``linear``).
DIFFERENTIAL_FORMULA = "F_rig + F_model(x_ref) - F_model(x_a)"


def correct_with_model(t_s, x_ref_m, x_a_m, force_N, *, base_scenario: Scenario, workers: int | None = None,
                       excess_limit: float | None = None, cab: str = AUTO, linear=None,
                       drift_hz: float | None = DRIFT_HZ, drift_rms_N: float | None = DRIFT_RMS_N,
                       saved: Calibration | None = None, **calibrate_kw) -> ModelCorrection:
    """Calibrate the truck model on the record, then correct it, or say why the linear correction is to be used.

    With ``linear`` (L, ``T_a^-1 T_F`` per wheel) the corrected force is :data:`HYBRID_FORMULA`
    (:func:`hybrid_correction`): the model's road force, plus the rig force the model does not
    explain corrected by L; a wheel where the model's runs show that L could turn the residual
    against it (:func:`~rigsim.scenarios.records.model.fallback.hybrid_outlook`) is corrected by L
    alone (``reason`` names it). Without ``linear``: :data:`DIFFERENTIAL_FORMULA` on every wheel, or
    L on all of them, as the model error stays within ``excess_limit``.

    Parameters
    ----------
    t_s, x_ref_m, x_a_m, force_N
        The record: time (s), drive and measured pan displacement (m), measured wheel force (N);
        see :func:`differential_correction`.
    base_scenario : Scenario
        The rig (actuator stroke) and output rate; its truck is never used.
    workers : int, optional
        Worker processes (default: all cores), one pool for the calibration and the correction.
    excess_limit : float, 1, optional
        The model error past which (without ``linear``) the linear correction is used, and (with
        ``linear``) a lone wheel is left out and the truck calibrated again, or a fit searched
        again: default :func:`~rigsim.scenarios.records.model.fallback.model_error_limit`
        (``HYBRID_LIMIT`` with ``linear``, else ``DIFFERENTIAL_LIMIT``).
    cab : {"auto", "held", "fitted"}
        Whether the model's cab is held, fitted, or (default) chosen by the two fits
        (:func:`~rigsim.scenarios.records.model.cab_choice.calibrate_cab`); on a described truck the
        frame's modes are then fitted where they make the fit clearly better
        (:func:`~rigsim.scenarios.records.model.frame_choice.calibrate_truck`).
    linear : callable, optional
        ``linear(forces)`` -> ``(corrected, settled)``: the linear correction of (n, 4) forces (N) and
        its settled samples (bool, (n,)).
    drift_hz : float or None, Hz
        The corner of W's drift cut (:func:`hybrid_correction`; with ``linear`` only); None: no
        cut, for a lab whose load cells do not drift.
    drift_rms_N : float or None, N
        The load cells' drift level the cut subtracts (:func:`hybrid_correction`); None: every
        wheel's slow residual cut.
    saved : Calibration, optional
        A calibration of this truck from another record, used where its model error on this
        record holds (:func:`~rigsim.scenarios.records.model.saved.check_saved`) with its tire's
        progressive stiffening refitted on this record's loads
        (:func:`~rigsim.scenarios.records.model.refine.refine_on_record`), else the start of a
        calibration on this record (said in its ``second_start``).
    **calibrate_kw
        Passed to :func:`~rigsim.scenarios.records.model.calibrate.calibrate` (windows, max_nfev,
        fitted_guess...).

    Returns
    -------
    ModelCorrection
        ``method`` "model" with the corrected forces (and the wheels the model corrects), or
        "linear" with one sentence why.

    Raises
    ------
    ScenarioError
        A malformed record (shapes, NaN, time axis), before any run.
    """
    wall0 = time.perf_counter()
    if excess_limit is None:
        excess_limit = model_error_limit(hybrid=linear is not None)
    t, fs = check_record(t_s, {"x_ref_m": x_ref_m, "x_a_m": x_a_m, "force_N": force_N})
    check_cab(cab, calibrate_kw.get("names"))
    try:  # refused before any run, as the hybrid's noise gain would refuse it after the calibration
        check_drift_hz(drift_hz, fs)
    except ValueError as exc:
        raise ScenarioError(str(exc)) from None
    # A record too short for the calibration's windows is the caller's to fix (raised); any other
    # refusal by the calibration means the model cannot be used on this record (the fallback).
    wins = fit_windows(t, *(calibrate_kw.get(k, d) for k, d in (("windows", WINDOWS), ("window_s", WINDOW_S),
                                                                ("lead_s", WINDOW_LEAD_S))))
    timings = {}

    def defer(held: Calibration) -> str:  # a wheel to leave out first: the cab chosen on the others' fit
        first = len(held.wheels) == len(CORNERS)  # the fit without that wheel chooses
        bad = outlier_wheel(held, excess_limit) if linear is not None and held.converged and first else None
        return "" if bad is None else outlier_reason(held, bad)

    with local_executor(workers) as ex:
        def calibrated(**kw) -> Calibration:
            return calibrate_truck(t, x_a_m, force_N, cab=cab, base_scenario=base_scenario, x_ref_m=x_ref_m,
                                   executor=ex, defer=defer, **(calibrate_kw | kw))

        cal, pair, refit, reason = None, None, "", ""
        if saved is not None:  # checked on this record by the model runs the correction needs: both where
            # the saved values are used as they are, F_model(x_a) alone where a refit changes them after
            pans = (x_a_m,) if refined_names(saved) else (x_ref_m, x_a_m)
            cal, runs, refit = check_saved(saved, lambda v: model_forces_on(
                v, t, pans, force_N=force_N, base_scenario=base_scenario, executor=ex), force_N, x_a_m, t, wins,
                excess_limit)
            pair = runs if runs is not None and len(runs) == 2 else None
            calibrate_kw = calibrate_kw | ({"start": dict(zip(saved.names, saved.fitted))} if refit else {})
            if cal is not None and refined_names(cal):  # the tire's stiffening at this record's loads
                with contextlib.suppress(ScenarioError, SimulationError):  # a refit that cannot run: the check's
                    cal, pair = refine_on_record(cal, t, x_a_m, force_N, base_scenario=base_scenario,
                                                 x_ref_m=x_ref_m, executor=ex, **calibrate_kw), None
        if cal is not None:
            timings["calibration_s"] = cal.wall_time_s
        else:
            fitted = _fit(calibrated, excess_limit, linear, wall0, timings)
            if isinstance(fitted, ModelCorrection):
                return fitted
            cal, reason = fitted
            if refit:
                cal = dataclasses.replace(cal, second_start=refit)
        if linear is None:  # the differential form: the model error's limit decides
            holds = differential_holds(cal, excess_limit)
            if reason or not holds.all():
                return _linear(reason, cal, wall0, timings)
        elif not cal.converged:
            return _linear(fallback_reason(cal, excess_limit), cal, wall0, timings)
        else:  # the hybrid: decided on the model runs (fallback.hybrid_outlook); a wheel left out stays linear
            holds = np.isin(CORNERS, cal.wheels)
        t1 = time.perf_counter()
        f_ref, f_a = pair or model_force_pair(cal.variant(), t, x_ref_m, x_a_m, force_N=force_N,
                                              base_scenario=base_scenario, executor=ex)
        # the load cells' uncompensated mass, fitted with the truck, taken out
        force = without_cell_mass(force_N, x_a_m, fs, cal.cell_mass_kg)
        started = settled_mask(t)  # past the model runs' start-up
        on_record = record_errors(f_a, force, int(np.argmax(started)), fs)  # the run the correction uses
        noise = outlook = None
        if linear is None:
            if not record_holds(on_record, excess_limit).all():
                return _linear(record_reason(cal, on_record, holds, excess_limit), cal, wall0, timings,
                               record_error=on_record)
            corrected, settled, formula = force + f_ref - f_a, started, DIFFERENTIAL_FORMULA
        else:
            corrected, settled, gain, residual = hybrid_correction(force, f_ref, f_a, linear, fs, started,
                                                                    drift_hz=drift_hz, drift_rms_N=drift_rms_N,
                                                                    with_residual=True)
            settled = started & np.asarray(settled, dtype=bool)  # and past L's own transients
            outlook = hybrid_outlook(f_ref, f_a, residual, corrected, linear, fs, settled, pans_m=x_a_m)
            reason = hybrid_reason(cal, holds, outlook, excess_limit, on_record)
            holds = holds & record_holds(on_record, excess_limit) & outlook.holds
            if not holds.any():
                return _linear(reason, cal, wall0, timings, outlook, on_record)
            formula = HYBRID_FORMULA
            noise = {c: float(v) if white else None
                     for c, v, white, ok in zip(CORNERS, gain.noise_rms, gain.measured, holds) if ok}
            if not holds.all():
                corrected[:, ~holds] = linear(np.asarray(force_N, dtype=float))[0][:, ~holds]
        timings["correction_s"] = round(time.perf_counter() - t1, 3)
    return ModelCorrection(method=MODEL, reason=reason if linear is not None else "",
                           calibration=cal, corrected_N=corrected, settled=settled,
                           wall_time_s=round(time.perf_counter() - wall0, 3), timings=timings,
                           wheels=tuple(c for c, ok in zip(CORNERS, holds) if ok or linear is None), formula=formula,
                           model_N=(f_ref, f_a), residual_noise_N=noise, outlook=outlook, record_error=on_record)


def _fit(calibrated, excess_limit: float, linear, wall0: float, timings: dict):
    """(the record's calibration, the fallback's reason) or, where none could be made, the linear
    fallback's :class:`ModelCorrection`: searched again past the limit, a lone bad wheel left out."""
    try:
        cal = calibrated()
    except (ScenarioError, SimulationError) as exc:
        return _linear(calibration_failed(exc), None, wall0, timings)
    if cal.converged:  # a fit refused for its model error: searched again (the springs sliding, the
        cal = calibrate_again(cal, calibrated, excess_limit)  # stations alike); a failed search skipped
    timings["calibration_s"] = cal.wall_time_s
    reason = fallback_reason(cal, excess_limit)
    bad = outlier_wheel(cal, excess_limit) if reason and linear is not None and cal.converged else None
    if bad is not None:  # one wheel the model cannot reproduce: calibrated again on the others,
        try:  # from where the fit with it ended (its second start's sliding springs, if kept)
            again = calibrated(wheels=tuple(c for c in CORNERS if c != CORNERS[bad]),
                               start=dict(zip(cal.names, cal.fitted)))
        except (ScenarioError, SimulationError):
            again = None
        if again is not None and again.converged:
            timings["calibration_s"] = round(cal.wall_time_s + again.wall_time_s, 3)
            again = dataclasses.replace(again, evaluations=cal.evaluations + again.evaluations,
                                        wall_time_s=timings["calibration_s"])
            cal, reason = again, fallback_reason(again, excess_limit)
    return cal, reason


def _linear(reason: str, cal, wall0: float, timings: dict, outlook=None, record_error=None) -> ModelCorrection:
    return ModelCorrection(method=LINEAR, reason=reason, calibration=cal,
                           wall_time_s=round(time.perf_counter() - wall0, 3), timings=timings, outlook=outlook,
                           record_error=record_error)
