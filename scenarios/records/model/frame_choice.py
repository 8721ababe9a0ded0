"""Whether a described truck's frame twists and bends: the rigid frame's fit, then the frame's modes
fitted from it where they could win, the better fit kept.

A ladder frame with the cab, body, tanks and load bolted on has its first torsion and bending modes
at 5-12 Hz, among the wheel-hop modes, where the rig excites the truck; a spec sheet gives none of
them (:mod:`~rigsim.scenarios.records.model.family`, :data:`~.family.FRAME_FITTED`). A model with a
rigid frame puts a flexible frame's twist and bend into the tires, the friction and the masses and
misses the wheels the frame loads. Fitted with everything else from the first guess (the frame at
9 Hz), the frame's modes sometimes open a far better fit and sometimes stop in a worse minimum than
the rigid frame's, beside an engine on mounts and a suspended cab whose modes are near.

So on a described truck, with the fields the correction fits by default,
:func:`calibrate_truck` first calibrates the rigid-frame model (the cab chosen as
:func:`~rigsim.scenarios.records.model.cab_choice.calibrate_cab` chooses it); at that optimum it
runs the truck once per window with the frame on each of :data:`SCAN_HZ` (both modes alike) and
measures, to first order, how much of the fit's squared residual such a frame would remove beyond
what the fitted values can (:func:`~.cab_choice.scan_gains`). Where no frame could make the fit
clearly better (under half of :data:`~.cab_choice.MIN_GAIN`) and that first-order answer is trusted
(the rigid fit's model error within :data:`~.cab_choice.SCAN_TRUSTED`), the frame stays rigid.
Otherwise the frame's modes are fitted with everything else, started from the rigid fit's optimum
and the scan's best frame, and kept where that fit's mean squared fit NRMSE over the wheels is at
least :data:`~.cab_choice.MIN_GAIN` below the rigid one's and neither mode stopped at its search
range's bottom (3 Hz: a fit that wandered off). A frame fitted to the range's top (20 Hz) is
practically rigid: kept only where it is still clearly better (a better minimum of the other values).

The catalogue truck keeps the XML's rigid chassis (no frame is fitted or scanned), as does a
calibration whose fitted fields the caller names.
"""

from __future__ import annotations

import contextlib
import dataclasses
import time

import numpy as np

from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.pool import local_executor
from rigsim.scenarios.core.watch import SimulationError
from rigsim.scenarios.records.model.cab_choice import (AUTO, EDGE, MIN_GAIN, SCAN_TRUSTED, best_scan, calibrate_cab,
                                                       mean_square, scan_error)
from rigsim.scenarios.records.model.calibrate import calibrate, with_sigma
from rigsim.scenarios.records.model.family import FRAME_FITTED
from rigsim.scenarios.records.model.first_guess import description, frame_guess
from rigsim.scenarios.records.model.result import Calibration

__all__ = ["SCAN_HZ", "frame_scan", "choose_frame", "calibrate_truck"]

#: The frames tried at the rigid fit's optimum (:func:`frame_scan`), Hz, torsion and bending alike:
#: 4-16 Hz a quarter octave apart, around the 5-12 Hz of a laden frame's first modes and inside the
#: fitted frame's search range (3-20 Hz, :data:`rigsim.mjcf.frame.BOUNDS`).
SCAN_HZ = tuple(float(v) for v in np.round(4.0 * 2.0 ** (np.arange(9) / 4.0), 2))


def frame_scan(state, hz=SCAN_HZ) -> tuple[float, float]:
    """The most a flexible frame could reduce a rigid-frame fit's squared residual, to first order.

    Parameters
    ----------
    state : FitState
        The rigid-frame fit, its Jacobian computed and its worker pool running.
    hz : sequence of float, Hz
        The frames tried (torsion and bending modes alike), each one truck run per window.

    Returns
    -------
    (float, float)
        The largest gain (1, :func:`~rigsim.scenarios.records.model.cab_choice.scan_gains`) and the
        frame's modes that give it (Hz): :func:`~rigsim.scenarios.records.model.cab_choice.best_scan`.
    """
    return best_scan(state, FRAME_FITTED, hz)


def choose_frame(rigid: Calibration, framed: Calibration, min_gain: float = MIN_GAIN) -> tuple[Calibration, str]:
    """The calibration to use of the frame rigid and the frame fitted, and one sentence why."""
    ms_r, ms_f = mean_square(rigid), mean_square(framed)
    gain = 1.0 - ms_f / ms_r if ms_r > 0 else 0.0
    values, bounds = framed.values(), dict(zip(framed.names, framed.bounds))
    modes = "/".join(f"{values[k]:.3g}" for k in FRAME_FITTED)
    what = (f"the frame fitted (torsion/bending {modes} Hz) reproduces the measured forces to fit NRMSE "
            f"{np.sqrt(ms_f):.3f} (rms of the wheels), the rigid frame to {np.sqrt(ms_r):.3f}")
    low = [k for k in FRAME_FITTED if framed.at_edge(k, EDGE) and values[k] - bounds[k][0] < bounds[k][1] - values[k]]
    if low:
        return rigid, f"frame rigid: {what}, but {low[0]} stopped at its search range's bottom."
    if gain < min_gain:
        return rigid, f"frame rigid: {what}, less than {min_gain:.0%} better in mean square."
    return framed, f"frame fitted: {what}."


def calibrate_truck(t_s, x_a_m, force_N, *, cab: str = AUTO, fitted_guess: dict | None = None,
                    workers: int | None = None, executor=None, **cab_kw) -> Calibration:
    """Calibrate the truck model: the cab chosen (:func:`~.cab_choice.calibrate_cab`), then on a
    described truck the frame (the module's description).

    Parameters
    ----------
    t_s, x_a_m, force_N
        The record: time (s), measured pan displacement (m, (n, 4)), measured wheel force (N, (n, 4)).
    cab : {"auto", "held", "fitted"}
        The cab's mode (:func:`~.cab_choice.calibrate_cab`).
    fitted_guess : dict, optional
        First guesses (SI), as for :func:`~rigsim.scenarios.records.model.calibrate.calibrate`.
    workers : int, optional
        Worker processes (default: all cores), one pool for every calibration.
    executor : concurrent.futures.Executor, optional
        A running pool to use instead.
    **cab_kw
        Passed to ``calibrate_cab`` (``base_scenario`` required; ``defer``, ``symmetric``,
        ``x_ref_m``, ``windows``, ``start``, ``names``...). Given ``names``, exactly these fields are
        fitted and no frame is added.

    Returns
    -------
    Calibration
        The one used; on a described truck its :attr:`~Calibration.frame_choice` says whether the
        frame was fitted and why, and its :attr:`~Calibration.wall_time_s` (s) and
        :attr:`~Calibration.evaluations` count every calibration and scan run.

    Raises
    ------
    ScenarioError
        What ``calibrate_cab`` refuses (before any model run).
    """
    with local_executor(workers) if executor is None else contextlib.nullcontext(executor) as ex:
        cal, state = calibrate_cab(t_s, x_a_m, force_N, cab=cab, fitted_guess=fitted_guess, executor=ex,
                                   with_state=True, **cab_kw)
        guess = frame_guess(description(cab_kw["base_scenario"]))  # none on the catalogue truck
        if cab_kw.get("names") is not None or state is None or set(FRAME_FITTED) & set(cal.names) or not guess:
            return cal
        w0, runs0 = time.perf_counter(), state.problem.evaluations
        gain, hz = 1.0, guess[FRAME_FITTED[0]]
        with contextlib.suppress(ScenarioError, SimulationError):  # a frame that would not run: fit it
            gain, hz = frame_scan(state)
        error = scan_error(cal)
        scanned = state.problem.evaluations - runs0
        if gain < MIN_GAIN / 2 and error <= SCAN_TRUSTED:
            return dataclasses.replace(cal, frame_choice=(
                f"frame rigid: a frame that twists and bends would remove at most {gain:.0%} of the rigid fit's "
                f"squared residual (at {hz:.3g} Hz, to first order; the rigid fit's model error {error:.3f} on its "
                f"second-worst wheel), less than {MIN_GAIN / 2:.0%}, so it was not fitted."),
                evaluations=cal.evaluations + scanned,
                wall_time_s=round(cal.wall_time_s + time.perf_counter() - w0, 3))
        kw = {k: v for k, v in cab_kw.items() if k not in ("defer", "symmetric", "start")}
        start = dict(zip(cal.names, cal.fitted)) | dict.fromkeys(FRAME_FITTED, hz)
        framed, framed_state = calibrate(t_s, x_a_m, force_N, names=cal.names + FRAME_FITTED,
                                         fitted_guess=fitted_guess, start=start, executor=ex, with_state=True,
                                         sigma=False, **kw)
        chosen, why = choose_frame(cal, framed)
        if chosen is framed:
            chosen = dataclasses.replace(with_sigma(framed, framed_state)[0], cab_choice=cal.cab_choice,
                                         second_start=cal.second_start)
        evaluations = cal.evaluations + scanned + framed_state.problem.evaluations
        wall = round(cal.wall_time_s + time.perf_counter() - w0, 3)
    return dataclasses.replace(chosen, frame_choice=why, evaluations=evaluations, wall_time_s=wall)
