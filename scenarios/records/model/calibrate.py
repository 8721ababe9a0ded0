"""Calibrating the truck model from the rig's own signals (x_a and F_rig), never the road run.

The fields fitted, their units and search ranges: :mod:`rigsim.scenarios.records.model.family`.

First guess: :mod:`rigsim.scenarios.records.model.first_guess` (payload from the record's
static loads, the rest a catalogue guess that never reads a plant).

The fit: ``scipy.optimize.least_squares`` (trust-region reflective, bounded) of the residual
(F_model(x_a) - F_rig) / std(F_rig) per wheel over a few windows of the record (each run starts
from rest with a lead-in of measured x_a before its scored span, so the unknown truck state at
the window's start has decayed). Given the drive x_ref, the residual is weighted towards the
frequencies where the pans miss the drive (:mod:`rigsim.scenarios.records.model.weighting`):
what the differential correction takes from the model. With the plant in the model family it
changes nothing; with a structural mismatch it keeps the mismatch from bending the parameters
where the correction needs them. The leaves' dry friction is MuJoCo's ``frictionloss``, a soft
constraint (smoothed), so the forces are smooth in the parameters and a forward-difference
Jacobian (step :data:`~rigsim.scenarios.records.model.problem.FD_STEP` of each scaled parameter) works; its
perturbed runs go to the worker pool (:func:`rigsim.scenarios.core.pool.run_jobs`) together, one model
run per window and variant. The problem itself (its scaling, residual, Jacobian reuse and the load
cells' mass): :mod:`rigsim.scenarios.records.model.problem`.

Results: ``benchmarks/model_correction.py`` measures the calibration on the paper's cases and the
generalization suite (fitted values and their 1-sigma, fit and corrected NRMSE per wheel against
the linear floor, DLC, wall time); docs/model_correction.md discusses them.
"""

from __future__ import annotations

import contextlib
import dataclasses
import time

import numpy as np

from rigsim.correction.identification.noise import noise_rms
from rigsim.mjcf.names import CORNERS, FRONT, REAR
from rigsim.mjcf.variant import BOUNDS
from rigsim.scenarios.core.config import Scenario, ScenarioError
from rigsim.scenarios.core.pool import local_executor
from rigsim.scenarios.records.model.band_error import band_errors
from rigsim.scenarios.records.model.cell_mass import band_acceleration
from rigsim.scenarios.records.model.family import (ADDITIVE, DAMPER_FITTED, DEFAULT_NAMES, EMPTY_STAND_IN,
                                                   ENGINE_FITTED, FITTED, FRAME_FITTED, RANGES, STATION_FITTED, UNITS)
from rigsim.scenarios.records.model.joined import join
from rigsim.scenarios.records.model.first_guess import (catalogue, damper_guess, description, engine_guess,
                                                        frame_guess, is_light, spring_fields, static_guess, PAYLOAD_X_LIMIT_M,
                                                        static_lateral, xml_nominal)
from rigsim.scenarios.records.model.model_runs import check_record
from rigsim.scenarios.records.model.onset_load import ONSET_RATIO, ONSET_STIFFNESS, TOP, load_guess, load_range
from rigsim.scenarios.records.model.problem import FitProblem, FitState
from rigsim.scenarios.records.model.result import Calibration
from rigsim.scenarios.records.model.uncertainty import uncertainties
from rigsim.scenarios.records.model.weighting import differential_kernel

__all__ = ["fit_windows", "calibrate", "with_sigma", "DESCRIBED_ROLL", "WINDOWS", "WINDOW_S", "WINDOW_LEAD_S", "MAX_NFEV", "FTOL",
           "BLOCK_S"]

#: Windows of the record fitted: how many, scored seconds each, measured lead-in before each (s).
#: The lead-in: a model run started at rest on a moving truck's record carries the start's state
#: error for several seconds (the leaf springs' dry friction holds it: the spring's offset changes
#: only while it slides), and a fit that scores it moves the truck's values to explain it. Measured
#: at the plant's own values (generalization suite, gen23's rigid plant, class D at 90 km/h, 30 s):
#: fit NRMSE of the rear wheels 0.064 after 2.5 s of lead-in, 0.010 after 6 s, 0.0063 (the load
#: cells' noise) after 12 s. Two windows of 5 s after 5 s each are 20 s of model run per variant;
#: calibrated in full they give that plant's rear wheels 0.018 x the linear floor and +0.04 % DLC,
#: where three windows of 4 s after 2.5 s (19.5 s of run) give 0.094 x and +0.29 % (gen06's rigid
#: plant: 0.04 x against 0.13 x; gen14's progressive tire, rear wheels: 0.06 x against 0.13 x).
WINDOWS, WINDOW_S, WINDOW_LEAD_S = 2, 5.0, 5.0
#: Most residual evaluations of the least squares (the Jacobians come on top, one per iteration).
#: 60: with each axle's stiffening fitted (12 values), a cap of 30 leaves two of the generalization
#: suite's 72 calibrations (30 s, cab held) unconverged, and they fall back to the linear
#: correction: gen17's rigid plant (its front tires sit past any onset, kt and ratio crawl along
#: their valley) and gen04's gradual stiffening; at 60 both converge (0.07-0.09 x and 0.10 x the
#: floor, DLC within 0.24 %). A cap changes nothing for a fit that converges below it (the same
#: trajectory).
MAX_NFEV = 60
#: The least squares stop where a step lowers the sum of squares by less than this fraction of it
#: (``least_squares``' ftol, 1): the fits' last steps each take a finite-difference Jacobian for a
#: gain the correction does not see. Measured on a 60 s record of the paper's high case (2 cores,
#: ``benchmarks/model_cost.py``'s records): 1e-4 took 141 truck variants on the rigid-cab truck and
#: 249 on the 2 Hz cab truck (both fits), 1e-3 109 and 174, every wheel's NRMSE against the road
#: within 0.0006 and its DLC error within 0.02 % of the 1e-4 fits'.
FTOL = 1e-3
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


#: Fitted on a described truck beside the body's pitch: the chassis' roll inertia. A spec sheet gives
#: none (tanks, body, cab and engine on their mounts), and on soft air springs or worn dampers the
#: body's roll mode sits low (0.3-0.7 Hz: the springs' roll stiffness less the load's height times
#: its weight), lightly damped, where the road's cross-slope excites it: a roll inertia held at the
#: catalogue's puts that mode off the truck's, and the front wheels' slow force with it. Searched
#: 0.75-2 times the catalogue's (:data:`~rigsim.scenarios.records.model.family.RANGES`). The catalogue truck
#: holds the XML's.
DESCRIBED_ROLL = "chassis_roll_inertia_kg_m2"


def _spring_names(names: tuple[str, ...], desc) -> tuple[str, ...]:
    """``names`` on the described truck (:func:`~.first_guess.spring_fields`): where ``names`` fit an
    axle's friction, its spring rate and damper are fitted too (an air axle's friction is its
    bushings' and dampers' seals'); where they fit the body's pitch (the payload's height or its
    stand-in), its roll inertia too (:data:`DESCRIBED_ROLL`); the catalogue truck's names as given."""
    fit, drop = spring_fields(desc)
    out = []
    for k in names:
        if k not in drop:
            out.append(k)
        if k.startswith("spring_friction_") and not k.startswith("spring_friction_factor"):
            out += [f for f in fit if k.split("_")[2] in f]
        if fit and k in ("payload_z_m", *EMPTY_STAND_IN.values()):
            out.append(DESCRIBED_ROLL)
    return tuple(dict.fromkeys(out))


def calibrate(t_s, x_a_m, force_N, *, base_scenario: Scenario, x_ref_m=None, names=DEFAULT_NAMES,
              fitted_guess: dict | None = None, start: dict | None = None, wheels=CORNERS,
              windows: int = WINDOWS, window_s: float = WINDOW_S, lead_s: float = WINDOW_LEAD_S,
              workers: int | None = None, max_nfev: int = MAX_NFEV, executor=None, cell_mass: bool = True,
              with_state: bool = False, sigma: bool = True, more=()):
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
        model (:mod:`rigsim.scenarios.records.model.weighting`); None: unweighted.
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
        See :func:`fit_windows`; ``windows`` of each record.
    workers : int, optional
        Worker processes (default: all cores).
    max_nfev : int
        Most residual evaluations.
    executor : concurrent.futures.Executor, optional
        A running pool to use instead of starting one.
    cell_mass : bool
        Fit the load cells' uncompensated mass too (:mod:`~rigsim.scenarios.records.model.cell_mass`,
        default); False holds it at 0 (a lab whose mass compensation is known to be exact).
    with_state : bool
        Return the fit's :class:`~rigsim.scenarios.records.model.problem.FitState` too (for model runs
        at the optimum through the same residual, with ``executor`` still running).
    sigma : bool
        Compute the fitted values' uncertainties (default): one more Jacobian at the optimum, by
        finite differences, unless the fit's last one was. False (with ``with_state``) leaves
        :attr:`Calibration.sigma` NaN and the state's Jacobian None, for :func:`with_sigma` to
        complete where the calibration is kept (of two compared, say).
    more : sequence of (t_s, x_a_m, force_N, x_ref_m), optional
        Other records of the same truck on the rig (s, m, N, m; ``x_ref_m`` where the record's is
        given, else None), at the record's rate: ``windows`` windows of each are fitted too
        (:mod:`~rigsim.scenarios.records.model.joined`), and :attr:`Calibration.window_records` says
        which record each window is of (0: this one, whose windows come first).

    Returns
    -------
    Calibration, or (Calibration, FitState) with ``with_state``

    Raises
    ------
    ScenarioError
        A bad record, static loads that imply no truck, or ``sigma=False`` without ``with_state``
        (before any model run).
    """
    from scipy.optimize import least_squares

    wall0 = time.perf_counter()
    if not sigma and not with_state:
        raise ScenarioError("sigma=False leaves the uncertainties for with_sigma, which needs the fit's state: "
                            "pass with_state=True too")
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
    joined = join((t_s, x_a_m, force_N, x_ref_m), more, check_record)
    t, x_a, force = joined.t_s, joined.x_a_m, joined.force_N
    fs = 1.0 / (t[1] - t[0])
    kernel = None if x_ref_m is None else differential_kernel(joined.x_ref_m, x_a, fs)
    wins, owners = joined.windows(windows, window_s, lead_s, fit_windows)
    payload, x = static_guess(force, base_scenario)
    given = "payload_kg" in (fitted_guess or {})
    if not given and is_light(payload, base_scenario):  # a light payload's height barely matters: the stand-in
        names = tuple(dict.fromkeys(EMPTY_STAND_IN.get(k, k) for k in names))
    if payload == 0.0 and not given:  # an empty truck: nothing to fit there
        names = tuple(k for k in names if k not in ("payload_kg", "payload_x_m"))
        if not names:
            raise ScenarioError("the measured loads are those of an empty truck, which has no payload to fit; "
                                "name other fields to fit")
    # The payload's centre across the truck: pinned by the measured left/right moment (held, not fitted).
    y = static_lateral(force, base_scenario, payload, x)
    desc = description(base_scenario)
    nominal = xml_nominal(desc)
    names = _spring_names(names, desc)
    guess = {"payload_kg": payload, "payload_x_m": x, "payload_y_m": y, "payload_z_m": nominal["payload_z_m"],
             "chassis_pitch_inertia_kg_m2": nominal["chassis_pitch_inertia_kg_m2"],
             "chassis_roll_inertia_kg_m2": nominal["chassis_roll_inertia_kg_m2"], **catalogue(desc),
             **dict.fromkeys(STATION_FITTED, 1.0), **frame_guess(desc), **engine_guess(desc), **damper_guess(desc),
             **(fitted_guess or {})}
    held = [k for k in FITTED if k in ("cab_mount_hz", "chassis_roll_inertia_kg_m2", *EMPTY_STAND_IN.values())
            or k.startswith("tire_progressive")
            or k in STATION_FITTED or (k in FRAME_FITTED + ENGINE_FITTED + DAMPER_FITTED and k in guess)]
    for k in held:  # held: rigid cab and frame, engine in the chassis, dampers as given (linear where not), linear tire, stations alike, the XML's chassis
        if k not in names and k not in (fitted_guess or {}):
            guess[k] = None
    lower, upper, loads = [], [], {}
    fixed = {k: None if v is None else (v if isinstance(v, str) else float(v)) for k, v in guess.items()
             if k not in names}
    for k in names:
        if k not in guess:
            raise ScenarioError(f"{k} is fitted on a described truck only (the catalogue truck's springs and frame are "
                                "held at truck_rig.xml's); describe the truck in [vehicle] or leave it out of names")
        if guess[k] is None:
            raise ScenarioError(f"fitted_guess gives no value for {k}, which is fitted; give a number or leave it out "
                                "of names")
        if k in ONSET_STIFFNESS:  # searched as the load where the tire stiffens (onset_load), N
            kt = guess[ONSET_STIFFNESS[k]]
            (a, b), load = load_range(force, wins, k), load_guess(force, wins, k, (fitted_guess or {}).get(k), kt)
            b = max(b, a + 1.0)  # a range, however narrow (least squares needs lower < upper)
            loads[k], guess[k] = (load, b - a), load / kt
        else:
            lo, hi = BOUNDS.get(k, (-PAYLOAD_X_LIMIT_M, PAYLOAD_X_LIMIT_M) if k == "payload_x_m" else (0.0, np.inf))[:2]
            r = RANGES[k]
            a, b = (guess[k] - r, guess[k] + r) if k in ADDITIVE else (guess[k] * r[0], guess[k] * r[1])
            a, b = max(a, lo), min(b, hi)
        lower.append(a)
        upper.append(b)
    with local_executor(workers) if executor is None else contextlib.nullcontext(executor) as ex:
        acc = joined.each(lambda x: band_acceleration(x, fs), x_a) if cell_mass else None
        prob = FitProblem(names, t, x_a, force, wins, base_scenario, guess, fixed, ex, kernel, loads, use, acc)
        lb, ub = prob.thetas(lower, upper)
        theta0 = prob.theta_of(start or {}, lb, ub)
        prob.fun(theta0)
        block = int(round(BLOCK_S * fs))
        m0 = prob.cache[tuple(theta0)][1]
        m_init = prob.as_measured(m0, prob.cell_mass(m0, block)[0])
        res = least_squares(prob.fun, theta0, jac=lambda th: prob.jac(th, ub), bounds=(lb, ub), method="trf",
                            x_scale=1.0, ftol=FTOL, xtol=1e-4, gtol=1e-6, max_nfev=max_nfev)
        jac = prob.final_jac(res.x, ub) if sigma else None
        f_opt, m_run = prob.fun(res.x), prob.cache[tuple(np.asarray(res.x, float))][1]
        mass, mass_1s = prob.cell_mass(m_run, block)
        m_opt = prob.as_measured(m_run, mass)
    sig, robust = _sigmas(prob, res.x, jac, f_opt) if sigma else (np.full(len(names), np.nan),) * 2
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

    # the load cells' white noise (whole record; of several, their mean square by length), N
    sizes = np.diff(joined.starts)
    noise = noise_rms(force, fs) if not more else np.sqrt(
        sum(n * noise_rms(force[a:a + n], fs) ** 2 for a, n in zip(joined.starts, sizes)) / sizes.sum())
    band, band_noise = band_errors(m_opt, force, wins, fs, noise)

    cal = Calibration(names=names, units=tuple(UNITS[k] for k in names),
                       initial=tuple(float(guess[k]) for k in names), fitted=tuple(float(v) for v in fitted),
                       sigma=tuple(float(s) for s in sig), sigma_robust=tuple(float(s) for s in robust), fixed=fixed, fit_nrmse=per_wheel(m_opt),
                       initial_nrmse=per_wheel(m_init), weighted=kernel is not None,
                       windows_s=joined.window_times(wins, owners, fs), window_records=owners if more else (),
                       evaluations=int(prob.evaluations), converged=bool(res.status > 0),
                       message=str(res.message) + "".join(f"; {k} set to 0 (its onset lies beyond every measured load)"
                                                          for k in linear), wall_time_s=round(time.perf_counter() - wall0, 3),
                       bounds=tuple((float(a), float(b)) for a, b in zip(lower, upper)),
                       noise_nrmse=tuple(float(v) for v in noise / prob.norm), band_nrmse=band,
                       band_noise_nrmse=band_noise, wheels=tuple(c for c in CORNERS if c in wheels),
                       cell_mass_kg=float(mass), cell_mass_sigma_kg=mass_1s)
    state = FitState(prob, np.asarray(res.x, float), jac, f_opt, ub)
    return (cal, state) if with_state else cal


def _sigmas(prob: FitProblem, theta, jac, residual) -> tuple[np.ndarray, np.ndarray]:
    """The fitted values' formal and block-robust 1-sigma (SI) at ``theta`` from the residual's
    ``jac`` and ``residual`` there (:func:`~rigsim.scenarios.records.model.uncertainty.uncertainties`, blocks
    of :data:`BLOCK_S`)."""
    block = int(round(BLOCK_S / (prob.t[1] - prob.t[0])))
    return uncertainties(jac, residual, block, prob.mapping(theta), int(prob.use.sum()))


def with_sigma(cal: Calibration, state: FitState) -> tuple[Calibration, FitState]:
    """A calibration made with ``sigma=False`` completed: its fitted values' uncertainties from a
    finite-difference Jacobian at the optimum (the fit's worker pool still running); one already
    complete is returned as it is.

    Returns
    -------
    (Calibration, FitState)
        With :attr:`Calibration.sigma` and :attr:`~Calibration.sigma_robust` (SI), the state's Jacobian set.
    """
    if state.jacobian is not None:
        return cal, state
    prob = state.problem
    t0 = time.perf_counter()
    jac = prob.final_jac(state.theta, state.upper)
    sig, robust = _sigmas(prob, state.theta, jac, state.residual)
    cal = dataclasses.replace(cal, sigma=tuple(float(s) for s in sig), sigma_robust=tuple(float(s) for s in robust),
                              evaluations=int(prob.evaluations),
                              wall_time_s=round(cal.wall_time_s + time.perf_counter() - t0, 3))
    return cal, dataclasses.replace(state, jacobian=jac)

