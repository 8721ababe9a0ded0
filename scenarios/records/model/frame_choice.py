"""Whether a described truck's frame twists and bends, its engine sits on mounts and its dampers are
digressive: the plain truck's fit, then each structure's fields fitted from it where they could win,
the better fit kept.

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
and the scan's best frame, and kept where that fit's mean squared model error over the wheels (its
fit NRMSE beyond the load cells' noise, :func:`~.cab_choice.excess_square`: the noise, which no
structure removes, would make a clear gain look small on a truck whose forces are small) is at
least :data:`~.cab_choice.MIN_GAIN` below the rigid one's and neither mode stopped at its search
range's bottom (3 Hz: a fit that wandered off). A frame fitted to the range's top (20 Hz) is
practically rigid: kept only where it is still clearly better (a better minimum of the other values).

The engine (:data:`~.family.ENGINE_FITTED`) is chosen the same way after the frame, from the
calibration kept: at its optimum the truck is run with an engine of
:data:`rigsim.mjcf.engine.ENGINE_MASS_KG` on mounts at each of :data:`ENGINE_SCAN_HZ`; where one
could win, the mount's frequency and the engine's mass are fitted with everything else from that
optimum and the scan's best mount, and kept where the fit is :data:`~.cab_choice.MIN_GAIN` better in
mean square and the mount did not stop at its range's bottom (5 Hz).

A frame's bending and an engine's bounce a hertz or two apart share the chassis' motion: a truck
can need both where neither fitted alone is clearly better (the fleet suite's development draw,
fleet19: bending 8.4 Hz beside a 1.26 t engine on 7.4 Hz mounts; the frame fitted alone left a model
error of 0.182 against the rigid frame's 0.190, the engine alone 0.181, both together 0.081). So
where the frame and the engine were each fitted and neither kept, both are fitted together, started
at their scans' best values, and kept (:func:`choose_frame_engine`) as each is.

A described truck's spring dampers are held nearly linear through those fits
(:func:`~rigsim.scenarios.records.model.first_guess.damper_guess`: a knee at 0.15 m/s, where a
vehicle damper's blow-off valves open, a slope beyond it of 0.95 of the one below, and twice as hard
in rebound as in bump), and then their knee, slope and rebound (:data:`~.family.DAMPER_FITTED`) are
always fitted with everything else, from those values and the kept calibration's optimum. A spec
sheet does not say whether a truck's dampers are new and digressive (beyond the knee a fifth to a
half of the slope below) or worn and linear, nor how much harder they are in rebound, and the
record says the first faintly: the pans miss the drive most at the wheel-hop modes, where the
dampers' speeds on the road are largest, so on the rig the dampers run mostly below their knee
where on the road they run beyond it. A digressive damper lowers the fit's squared residual by a
few percent to a third, well under what a frame or an engine must win, while it moves the road's
DLC by a percent: the correction, which maps the model's residual on the rig to the road linearly,
cannot put back a damping that depends on the amplitude, so the model's dampers decide how a
truck's hop is damped on the road. So the fitted dampers are kept (:func:`choose_damper`) wherever
the fit is no worse in mean square to the least squares' resolution (:data:`DAMPER_MIN_GAIN`: the
held dampers are in the fitted family, so only a search stopped short is clearly worse) and the
knee did not stop at its range's bottom (0.05 m/s: a damper whose saturating part acts as friction,
which the fitted friction already is).

The catalogue truck keeps the XML's rigid chassis (no frame or engine is fitted or scanned), as
does a calibration whose fitted fields the caller names.
"""

from __future__ import annotations

import contextlib
import dataclasses
import time

import numpy as np

from rigsim.mjcf.engine import ENGINE_MASS_KG
from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.pool import local_executor
from rigsim.scenarios.core.watch import SimulationError
from rigsim.scenarios.records.model.cab_choice import (AUTO, EDGE, MIN_GAIN, SCAN_TRUSTED, best_scan, calibrate_cab,
                                                       excess_square, scan_error)
from rigsim.scenarios.records.model.calibrate import FTOL, calibrate, with_sigma
from rigsim.scenarios.records.model.family import DAMPER_FITTED, ENGINE_FITTED, FRAME_FITTED
from rigsim.scenarios.records.model.first_guess import damper_guess, description, engine_guess, frame_guess
from rigsim.scenarios.records.model.result import Calibration

__all__ = ["SCAN_HZ", "ENGINE_SCAN_HZ", "DAMPER_MIN_GAIN", "frame_scan", "engine_scan",
           "choose_frame", "choose_engine", "choose_frame_engine", "choose_damper",
           "calibrate_truck"]

#: The frames tried at the rigid fit's optimum (:func:`frame_scan`), Hz, torsion and bending alike:
#: 4-16 Hz a quarter octave apart, around the 5-12 Hz of a laden frame's first modes and inside the
#: fitted frame's search range (3-20 Hz, :data:`rigsim.mjcf.frame.BOUNDS`).
SCAN_HZ = tuple(float(v) for v in np.round(4.0 * 2.0 ** (np.arange(9) / 4.0), 2))
#: The engine mounts tried at the kept fit's optimum (:func:`engine_scan`), Hz: 5-14 Hz a quarter
#: octave apart, around a truck engine's 6-12 Hz bounce, from the fitted mount's range's bottom
#: (5-20 Hz, :data:`rigsim.mjcf.engine.BOUNDS`).
ENGINE_SCAN_HZ = tuple(float(v) for v in np.round(5.0 * 2.0 ** (np.arange(7) / 4.0), 2))
#: Least relative reduction of the fit's mean squared model error for the fitted dampers to be kept,
#: 1: minus the least squares' own stopping tolerance (:data:`~.calibrate.FTOL`, a step that lowers the
#: sum of squares by less than this fraction of it ends the fit), so a fit that ends as good as the
#: held dampers to the fit's resolution is kept (the module's description); one clearly worse is a
#: search stopped short. fleet14 of the fresh draw of seed 1330537794: the dampers' fit found x0.52
#: beyond 0.20 m/s, rebound x2.23 (the plant's x0.41 beyond 0.18 m/s, x2.42) and ended 0.011 %
#: worse in mean square; held, its rear wheels were 1.3 and 1.7 % below the road's DLC, kept, every
#: wheel within 0.4 %.
DAMPER_MIN_GAIN = -FTOL


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


def engine_scan(state, hz=ENGINE_SCAN_HZ, mass_kg: float = ENGINE_MASS_KG) -> tuple[float, float]:
    """The most an engine of ``mass_kg`` (kg) on its own mounts could reduce the squared residual of a
    fit whose engine is in the chassis, to first order: the largest gain (1) over the mounts ``hz``
    (Hz, each one truck run per window) and the mount that gives it (Hz)."""
    return best_scan(state, ("engine_mount_hz",), hz, {"engine_mass_kg": float(mass_kg)})


def _choose(what: str, plain: Calibration, fitted: Calibration, fields, edge, min_gain: float):
    """(the calibration to use, one sentence why, without its verdict) of ``plain`` and ``fitted``
    (``fields`` fitted too, ``what`` their sentence with their values): ``fitted`` where it is
    ``min_gain`` better in mean square (of the fit beyond the noise, :func:`~.cab_choice.excess_square`)
    and none of ``edge`` stopped at its range's bottom."""
    ms_p, ms_f = excess_square(plain), excess_square(fitted)
    gain = 1.0 - ms_f / ms_p if ms_p > 0 else 0.0
    values, bounds = fitted.values(), dict(zip(fitted.names, fitted.bounds))
    text = (f"{what.format(*(f'{values[k]:.3g}' for k in fields))} leaves a model error of {np.sqrt(ms_f):.3f} (the "
            f"fit NRMSE beyond the load cells' noise, rms of the wheels), without it {np.sqrt(ms_p):.3f}")
    low = [k for k in edge if fitted.at_edge(k, EDGE) and values[k] - bounds[k][0] < bounds[k][1] - values[k]]
    if low:
        return plain, f"{text}, but {low[0]} stopped at its search range's bottom."
    if gain < min_gain:
        return plain, f"{text}, " + (f"less than {min_gain:.0%} better in mean square." if min_gain > 0 else
                                     f"more than {-min_gain:.1%} worse in mean square." if min_gain < 0 else
                                     "worse in mean square.")
    return fitted, f"{text}."


def choose_frame(rigid: Calibration, framed: Calibration, min_gain: float = MIN_GAIN) -> tuple[Calibration, str]:
    """The calibration to use of the frame rigid and the frame fitted, and one sentence why."""
    chosen, why = _choose("the frame fitted (torsion/bending {}/{} Hz)", rigid, framed, FRAME_FITTED, FRAME_FITTED,
                          min_gain)
    return chosen, ("frame rigid: " if chosen is rigid else "frame fitted: ") + why


def choose_engine(plain: Calibration, engined: Calibration, min_gain: float = MIN_GAIN) -> tuple[Calibration, str]:
    """The calibration to use of the engine in the chassis and the engine on its mounts, and one sentence why."""
    chosen, why = _choose("the engine fitted ({} Hz mounts, {} kg)", plain, engined, ENGINE_FITTED,
                          ("engine_mount_hz",), min_gain)
    return chosen, ("engine in the chassis: " if chosen is plain else "engine on its mounts: ") + why


def held_dampers(plain: Calibration) -> str:
    """How ``plain`` holds its spring dampers, the start of its damper sentence: linear, or digressive at
    the values it holds (a described truck's, :func:`~rigsim.scenarios.records.model.first_guess.damper_guess`)."""
    held = plain.values()
    knee, ratio = held.get("damper_digressive_knee_m_per_s"), held.get("damper_digressive_ratio")
    rebound = held.get("damper_rebound_ratio") or 1.0
    if knee is None or ratio is None or ratio >= 1.0:
        return "dampers linear" + (f" (rebound x{rebound:.3g})" if rebound != 1.0 else "")
    return f"dampers held digressive (knee {knee:.3g} m/s, slope beyond it x{ratio:.3g}, rebound x{rebound:.3g})"


def choose_damper(plain: Calibration, digressive: Calibration,
                  min_gain: float = DAMPER_MIN_GAIN) -> tuple[Calibration, str]:
    """The calibration to use of the dampers held (:func:`held_dampers`) and the dampers' knee, slope and
    rebound fitted (kept where no worse, :data:`DAMPER_MIN_GAIN`: the module's description), and one
    sentence why."""
    chosen, why = _choose("digressive dampers fitted (knee {} m/s, slope beyond it x{}, rebound x{})", plain,
                          digressive, DAMPER_FITTED, ("damper_digressive_knee_m_per_s",), min_gain)
    return chosen, (f"{held_dampers(plain)}: " if chosen is plain else "dampers digressive: ") + why


def choose_frame_engine(apart: Calibration, together: Calibration,
                        min_gain: float = MIN_GAIN) -> tuple[Calibration, str]:
    """The calibration to use of the frame and the engine as chosen apart (neither kept) and both fitted
    together, and one sentence why."""
    chosen, why = _choose("the frame and the engine fitted together (torsion/bending {}/{} Hz, {} Hz mounts, {} kg)",
                          apart, together, FRAME_FITTED + ENGINE_FITTED, FRAME_FITTED + ("engine_mount_hz",), min_gain)
    return chosen, ("frame and engine apart: " if chosen is apart else "frame fitted with the engine: ") + why


def calibrate_truck(t_s, x_a_m, force_N, *, cab: str = AUTO, fitted_guess: dict | None = None,
                    workers: int | None = None, executor=None, **cab_kw) -> Calibration:
    """Calibrate the truck model: the cab chosen (:func:`~.cab_choice.calibrate_cab`), then on a
    described truck the frame, the engine and the dampers (the module's description).

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
        fitted and no frame, engine or digressive damper is added.

    Returns
    -------
    Calibration
        The one used; on a described truck its :attr:`~Calibration.frame_choice`,
        :attr:`~Calibration.engine_choice` and :attr:`~Calibration.damper_choice` say whether each was
        fitted and why, and its
        :attr:`~Calibration.wall_time_s` (s) and :attr:`~Calibration.evaluations` count every
        calibration and scan run.

    Raises
    ------
    ScenarioError
        What ``calibrate_cab`` refuses (before any model run).
    """
    desc = description(cab_kw["base_scenario"])
    dampers = damper_guess(desc)  # a described truck's dampers held nearly linear until they are fitted
    if cab_kw.get("names") is None and dampers:
        fitted_guess = dampers | (fitted_guess or {})
    with local_executor(workers) if executor is None else contextlib.nullcontext(executor) as ex:
        cal, state = calibrate_cab(t_s, x_a_m, force_N, cab=cab, fitted_guess=fitted_guess, executor=ex,
                                   with_state=True, **cab_kw)
        if cab_kw.get("names") is not None or state is None or not frame_guess(desc):  # none on the catalogue truck
            return cal
        kw = {k: v for k, v in cab_kw.items() if k not in ("defer", "symmetric", "start")}

        def fit(names, start):
            return calibrate(t_s, x_a_m, force_N, names=names, fitted_guess=fitted_guess, start=start, executor=ex,
                             with_state=True, sigma=False, **kw)

        tried = {}  # the structures fitted apart and not kept: the scan's best value each was started at
        if not set(FRAME_FITTED) & set(cal.names):
            cal, state, why = _structure(cal, state, fit, "a frame that twists and bends", "frame rigid",
                                         FRAME_FITTED, frame_scan,
                                         lambda hz: dict.fromkeys(FRAME_FITTED, hz),
                                         frame_guess(desc)[FRAME_FITTED[0]], choose_frame, tried=tried, key="frame")
            cal = dataclasses.replace(cal, frame_choice=why)
        if not set(ENGINE_FITTED) & set(cal.names):
            guess = engine_guess(desc)
            cal, state, why = _structure(cal, state, fit, "an engine on its own mounts", "engine in the chassis",
                                         ENGINE_FITTED, lambda st: engine_scan(st, mass_kg=guess["engine_mass_kg"]),
                                         lambda hz: guess | {"engine_mount_hz": hz}, guess["engine_mount_hz"],
                                         choose_engine, tried=tried, key="engine")
            cal = dataclasses.replace(cal, engine_choice=why)
        if {"frame", "engine"} <= set(tried) and not set(FRAME_FITTED + ENGINE_FITTED) & set(cal.names):
            guess = engine_guess(desc)
            cal, state, why = _structure(cal, state, fit, "the frame and the engine together", "frame and engine apart",
                                         FRAME_FITTED + ENGINE_FITTED, None,
                                         lambda hz: dict.fromkeys(FRAME_FITTED, hz) | guess
                                         | {"engine_mount_hz": tried["engine"]}, tried["frame"], choose_frame_engine)
            together = set(FRAME_FITTED) <= set(cal.names)
            cal = dataclasses.replace(cal, frame_choice=why if together else cal.frame_choice,
                                      engine_choice=("engine on its mounts: fitted with the frame (the frame's choice "
                                                     "says why)." if together else f"{cal.engine_choice} {why}"))
        if not set(DAMPER_FITTED) & set(cal.names):  # always fitted: the record's faint word on them decides
            held = dampers | {k: v for k, v in fitted_guess.items() if k in DAMPER_FITTED and v is not None}
            cal, state, why = _structure(cal, state, fit, "the dampers' knee, slope and rebound fitted",
                                         held_dampers(cal), DAMPER_FITTED, None, lambda knee: held,
                                         held["damper_digressive_knee_m_per_s"], choose_damper, unit="m/s")
            cal = dataclasses.replace(cal, damper_choice=why)
    return cal


def _structure(cal: Calibration, state, fit, what: str, kept: str, fields, scan, start_of, hz0: float, choose,
               unit: str = "Hz", tried: dict | None = None, key: str = ""):
    """One structure's choice (the module's description) from the calibration ``cal`` and its fit's
    ``state`` (Jacobian computed, pool running): (the calibration kept, its state, one sentence why).
    ``fit(names, start)`` calibrates with ``names`` from the values ``start``; ``scan(state)`` gives
    (gain, value), or None to fit the structure without a scan; ``start_of(hz)`` the structure's fields
    at the scan's best value ``hz`` (in ``unit``; ``hz0`` where the scan would not run or there is none);
    ``choose(cal, fitted)`` keeps one and says why; ``kept`` starts the sentence where the structure is
    not fitted. The structures chosen before keep their sentences. A structure whose fit cannot run (a
    truck it cannot be built into) leaves ``cal`` as it is and says why. A structure fitted and not
    kept puts the scan's best value in ``tried[key]``."""
    w0, runs0 = time.perf_counter(), state.problem.evaluations
    gain, hz = 1.0, hz0
    if scan is not None:
        with contextlib.suppress(ScenarioError, SimulationError):  # a structure that would not run: fit it
            gain, hz = scan(state)
    error = scan_error(cal)
    scanned = state.problem.evaluations - runs0
    if gain < MIN_GAIN / 2 and error <= SCAN_TRUSTED:
        return dataclasses.replace(cal, evaluations=cal.evaluations + scanned,
                                   wall_time_s=round(cal.wall_time_s + time.perf_counter() - w0, 3)), state, (
            f"{kept}: {what} would remove at most {gain:.0%} of the fit's squared residual (at {hz:.3g} {unit}, to "
            f"first order; the fit's model error {error:.3f} on its second-worst wheel), less than "
            f"{MIN_GAIN / 2:.0%}, so it was not fitted.")
    try:
        fitted, fitted_state = fit(cal.names + fields, dict(zip(cal.names, cal.fitted)) | start_of(hz))
    except (ScenarioError, SimulationError) as exc:  # the calibration without it stands
        return dataclasses.replace(cal, evaluations=cal.evaluations + scanned,
                                   wall_time_s=round(cal.wall_time_s + time.perf_counter() - w0, 3)), state, (
            f"{kept}: {what} could not be fitted ({str(exc).rstrip('.')}).")
    chosen, why = choose(cal, fitted)
    chosen_state = state
    if chosen is cal and tried is not None:
        tried[key] = hz
    if chosen is fitted:
        chosen, chosen_state = with_sigma(fitted, fitted_state)
        chosen = dataclasses.replace(chosen, cab_choice=cal.cab_choice, second_start=cal.second_start,
                                     frame_choice=cal.frame_choice, engine_choice=cal.engine_choice)
    evaluations = cal.evaluations + scanned + fitted_state.problem.evaluations
    wall = round(cal.wall_time_s + time.perf_counter() - w0, 3)
    return dataclasses.replace(chosen, evaluations=evaluations, wall_time_s=wall), chosen_state, why
