"""``rigsim validate``: the paper's linearized actuator model checked against the multibody plant.

Three routes to the actuator transfer function ``T_a = X_a / X_p`` (drive signal x_ref of
``hyd_<c>`` to pan displacement, qpos of ``pan_<c>_z``) of the truck on the DYNTRAC rig:

1. **analytic**: the paper's eq. 4 (:func:`rigsim.correction.output.transfer.eq4_transfer_function`) with
   Merritt's Kq, Kc from :func:`rigsim.hydraulics.linearization` at each wheel station's static load
   and that station's tire stiffness;
2. **numerical**: the whole closed-loop MuJoCo plant (truck, pans, four hydraulic actuators,
   all states) linearized at static rest (:meth:`rigsim.scenarios.core.rig.Rig.linearize`, leaf-spring
   dry friction off), ``H(f) = C (exp(j 2 pi f dt) I - A)^-1 B``, all 4 x 4 paths;
3. **identified**: the nonlinear rig driven by independent road-like random drives on all four
   wheels, the MIMO H1 estimate with its coherence (:mod:`rigsim.correction.identification.identify`) and a fitted
   stable rational transfer function per wheel.

Then the paper's Figure 7 (step responses, nonlinear against linear) and Table 1 (DLC of the
road test, the rig test and the truck driven by the linearized actuator model) for the
high-roughness, 72 km/h, 3640 kg case. :func:`validate` schedules the runs
(:mod:`rigsim.scenarios.studies.validate.runs`) on the worker pool and assembles a
:class:`~rigsim.scenarios.studies.validate.result.ValidateResult`;
:func:`rigsim.scenarios.studies.validate.report.write_report` writes ``validate.json``, the PNGs and
``report.md``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.pool import run_jobs, worker_count
from rigsim.scenarios.core.rig import RIG_INTEGRATOR_NAME, Rig
from rigsim.scenarios.core.watch import SayFn
from rigsim.scenarios.studies.validate import runs, sections
from rigsim.scenarios.studies.validate.result import ValidateCurves, ValidateResult
from rigsim.scenarios.studies.validate.routes import route1_models, route3
from rigsim.scenarios.studies.validate.settings import (BODE_RANGE_HZ, COMPARE_MAX_HZ, MAX_WORKERS, MIN_IDENT_S,
                                                        STEP_LARGE_M, STEP_SMALL_M, table1_scenario_path,
                                                        validation_scenario)

__all__ = ["MAX_DURATION_S", "check_arguments", "validate"]

#: Longest Table 1 or identification record accepted, s.
MAX_DURATION_S = 3600.0

def _say(progress: SayFn | None, text: str) -> None:
    if progress is not None:
        progress(text)


def check_arguments(duration_s: float | None, ident_duration_s: float | None, jobs: int | None) -> int:
    """Refuse bad arguments before any work; returns the number of worker processes.

    Parameters
    ----------
    duration_s, ident_duration_s : float, s, optional
        Must lie in (0, :data:`MAX_DURATION_S`] when given.
    jobs : int, optional
        Worker processes, a whole number >= 1 (default: all cores, at most :data:`MAX_WORKERS`).

    Raises
    ------
    ScenarioError
        One sentence naming the option and what it accepts.
    """
    for name, v in (("duration_s", duration_s), ("ident_duration_s", ident_duration_s)):
        if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v) and 0 < v <= MAX_DURATION_S):
            raise ScenarioError(f"--{name.replace('_', '-')} must lie in (0, {MAX_DURATION_S:g}] s, got {v!r}")
    try:
        return worker_count(jobs, MAX_WORKERS)
    except ValueError as exc:
        raise ScenarioError(f"--jobs: {exc}") from None


def validate(*, duration_s: float | None = None, ident_duration_s: float | None = None,
             jobs: int | None = None, progress: SayFn | None = None,
             pose_rate_hz: float | None = None, rig: str = "design") -> ValidateResult:
    """Compute the whole validation (routes 1-3, Figure 7 and Table 1 analogues).

    Parameters
    ----------
    duration_s : float, s, optional
        Analysed duration of the Table 1 runs (default: the scenario's 60 s).
    ident_duration_s : float, s, optional
        Analysed duration of the identification record (default twice ``duration_s``,
        at least :data:`MIN_IDENT_S`).
    jobs : int, optional
        Worker processes (default: all cores, at most :data:`MAX_WORKERS`).
    progress : callable, optional
        ``progress(line)`` for one-line progress messages.
    pose_rate_hz : float, Hz, optional
        Keep the Table 1 road and rig runs with body poses at this rate (for a recording).
    rig : str
        The paper cases' configuration (:data:`rigsim.scenarios.core.config.PAPER_CONFIGURATIONS`):
        ``"design"`` or ``"dyntrac"``.

    Raises
    ------
    ScenarioError
        Bad arguments, before any run.
    SimulationError
        A run failed (MuJoCo warning, divergence), naming the simulated time.
    """
    wall0 = time.perf_counter()
    workers = check_arguments(duration_s, ident_duration_s, jobs)
    path = str(table1_scenario_path(rig))
    sc = validation_scenario(path, duration_s)
    table_s = sc.duration_s
    ident_s = float(ident_duration_s) if ident_duration_s is not None else max(2.0 * table_s, MIN_IDENT_S)
    _say(progress, f"validate: {sc.name}, Table 1 runs {table_s:g} s, identification {ident_s:g} s, "
                   f"{workers} worker(s)")

    _say(progress, "validate: route 2, linearizing the plant with mjd_transitionFD")
    rig = Rig(sc)
    lin = rig.linearize()
    params = rig.params
    _say(progress, "validate: route 1, eq. 4 per wheel station")
    r1 = [route1_models(params, lin.kt_N_per_m[i], lin.load_N[i]) for i in range(4)]
    eq4 = [r1[i]["static_mean"][0] for i in range(4)]
    model_r2 = lin
    model_eq4 = ([(np.ravel(tf.num[0][0]), np.ravel(tf.den[0][0])) for tf in eq4], lin.dt_s)

    # Longest first. The friction-free runs are a diagnostic (route 2 linearizes without friction).
    job_table = {
        "ident": (runs.identification_run, (path, ident_s)),
        "ident_nofriction": (runs.identification_run, (path, ident_s, False)),
        "rig": (runs.scenario_run, (path, table_s, "rig", pose_rate_hz)),
        "road": (runs.scenario_run, (path, table_s, "road", pose_rate_hz)),
        "lin_route2_per_wheel": (runs.linear_model_run, (path, table_s, "route2_per_wheel", model_r2)),
        "lin_eq4": (runs.linear_model_run, (path, table_s, "eq4", model_eq4)),
        "lin_route2_mimo": (runs.linear_model_run, (path, table_s, "route2_mimo", model_r2)),
        "step_small": (runs.step_run, (path, STEP_SMALL_M)),
        "step_large": (runs.step_run, (path, STEP_LARGE_M)),
        "step_small_nofriction": (runs.step_run, (path, STEP_SMALL_M, False)),
        "step_large_nofriction": (runs.step_run, (path, STEP_LARGE_M, False)),
    }
    names = list(job_table)
    t_start = time.perf_counter()
    done = []

    def on_done(i: int, _result) -> None:
        done.append(i)
        _say(progress, f"validate: [{len(done)}/{len(names)}] {names[i]} done "
                       f"({time.perf_counter() - t_start:.1f} s)")

    out = run_jobs(list(job_table.values()), workers=workers, on_done=on_done)
    results = dict(zip(names, out))

    _say(progress, "validate: route 3, H1 estimate and rational fits; comparing")
    return _assemble(sc.name, params, lin, r1, results, table_s, ident_s, wall0, rig.dt_s)


def _assemble(name, params, lin, r1, results, table_s, ident_s, wall0, rig_dt_s) -> ValidateResult:
    f_bode = np.geomspace(BODE_RANGE_HZ[0], BODE_RANGE_HZ[1], 400)
    f_cmp = np.geomspace(BODE_RANGE_HZ[0], COMPARE_MAX_HZ, 400)
    h2_bode = lin.frequency_response(f_bode)
    h2_cmp = lin.frequency_response(f_cmp)
    route2 = sections.route2_section(lin, f_bode, h2_bode)
    route1, h1_bode = sections.route1_section(r1, f_cmp, h2_cmp, f_bode)
    budget, budget_curves = sections.budget_section(params, lin, r1, f_cmp, h2_cmp)
    ident = results["ident"]
    r3 = route3(ident.record, lin, f_cmp, h2_cmp)
    r3_nf = route3(results["ident_nofriction"].record, lin, f_cmp, h2_cmp)
    eq4 = [r1[i]["static_mean"][0] for i in range(len(CORNERS))]
    steps, step_curves = sections.steps_section(
        {k: results[f"step_{k}"] for k in sections.STEP_SIZES}, lin, eq4, r3.fits)
    friction_off = sections.friction_off_section(
        r3_nf, {k: results[f"step_{k}_nofriction"] for k in sections.STEP_SIZES}, lin)
    est = r3.estimate
    curves = ValidateCurves(f_bode_hz=f_bode, h_route1=h1_bode, h_route2=h2_bode, f_compare_hz=f_cmp,
                            h_route2_compare=h2_cmp, budget=budget_curves, f_ident_hz=est.f_hz, h_ident=est.h,
                            coherence=est.coherence, h_route2_at_ident=lin.frequency_response(est.f_hz),
                            fits=r3.fits, steps=step_curves)
    kept = {k: results[k].result for k in ("road", "rig") if results[k].result is not None}
    return ValidateResult(
        scenario=name, duration_s=table_s, ident_duration_s=ident_s, timestep_s=rig_dt_s,
        integrator=RIG_INTEGRATOR_NAME, linear_timestep_s=lin.dt_s,
        route1=route1, route2=route2, route3=sections.route3_section(r3, ident, ident_s),
        departure_budget=budget, steps=steps, table1=sections.table1_section(results),
        diagnostics_friction_off=friction_off, wall_time_s=round(time.perf_counter() - wall0, 2),
        curves=curves, runs=kept)
