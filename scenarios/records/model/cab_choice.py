"""Whether the truck's cab sits on soft mounts: held, fitted where it could win, the better fit kept.

A cab on its own mounts (``TruckVariant.cab_mount_hz``, a 1.5-3 Hz mode next to the body's
bounce and pitch) loads the front wheels; a model with a rigid cab absorbs it into the front tire
and leaf-friction values and misses the front wheels' road DLC by 1-6 % (docs/model_correction.md).
Fitted on every record, the mount frequency is not always pinned: on a smooth road at low speed
(generalization case gen00, class A at 30 km/h) a rigid-cab truck's fit goes from the 2.5 Hz
guess to the range's bottom, 1.0 Hz, into a local minimum worse than the rigid cab's fit.

So by default (:data:`AUTO`) :func:`calibrate_cab` calibrates both model families, the cab held
(rigid, or at the scenario's ``cab_mount_hz``) and the cab fitted, and keeps the fitted cab only
where it is clearly the better model of this record: its fit's mean squared NRMSE over the wheels
(:attr:`Calibration.fit_nrmse`, unweighted, load-cell noise included) at least :data:`MIN_GAIN`
below the held cab's, and the mount frequency not at its search range's bottom
(:meth:`Calibration.at_edge`: a fit that wandered off). At the range's top (30 Hz) the cab is
practically rigid, and a fit that is still clearly better there found a better minimum of the
truck's other values than the cab-held fit did: it is kept. Convergence is not
part of the choice: the chosen calibration's is checked where every calibration's is (a fit that did not converge falls back to the linear
correction, :func:`~rigsim.scenarios.records.model.fallback.fallback_reason`). Measured on generalization cases (30 s, docs/model_correction.md): a
truck with its cab on 2 Hz mounts fits 0.10 against the rigid cab's 0.50 (front wheels), a
rigid-cab truck 0.095 held against 0.35 fitted (gen00) or 0.057 against 0.057 (gen05, the mount
at the range's top, 30 Hz): the two families are far apart where the cab matters and level where
it does not, so the choice does not hinge on the exact threshold.

The price is a second calibration, from the same first guess; ``benchmarks/model_cost.py`` times
both against the cab held alone. Each fit's uncertainties (a finite-difference Jacobian at its
optimum, one truck run per fitted value) are computed only for the calibration kept
(:func:`~rigsim.scenarios.records.model.calibrate.with_sigma`), and for the cab-held one where the scan
needs its Jacobian. Started instead where the cab-held one ended
(``calibrate(start=...)``), it cost more on that benchmark's rigid-cab truck, not less (the
mount's crawl from its 2.5 Hz guess went on to the range's top). It is skipped where a cab could
not win (:func:`cab_scan`): at the cab-held optimum the truck is run once more with the cab on
each of :data:`SCAN_HZ`, and the residual those runs add is projected out of the held fit's
Jacobian; the largest share of the held fit's squared residual that such a cab would remove,
beyond what the held parameters can, is the cab's possible gain. Under half of :data:`MIN_GAIN`
the cab stays held, without the second calibration (a few seconds of model runs instead).

The scan is a first-order answer, trusted only where the cab-held model already reproduces the
record (its model error, :attr:`Calibration.excess_nrmse`, within :data:`SCAN_TRUSTED` on all
fitted wheels but one: a cab loads both wheels of an axle, and one wheel alone far off, a broken
channel say, is that wheel's own matter, ``fallback.outlier_wheel``). Where it does not, a cab
can open another basin that no small step shows: on the paper suite's stiffening tire (medium
72 km/h case, the tire +50 % over 2 cm, a mismatch the family lacks) the held fit leaves model
errors of 0.20-0.21 on the front wheels and the scan finds no gain at any mount (0 %), yet the
calibration with the cab fitted from the first guess finds a far better truck (its mounts at
8.4 Hz: fit NRMSE 0.058 against 0.155) and brings the front wheels to 0.15 of the linear floor
(``benchmarks/model_correction.py --suite paper``). There the second calibration runs without a
scan.
"""

from __future__ import annotations

import contextlib
import dataclasses
import time

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.pool import local_executor
from rigsim.scenarios.core.watch import SimulationError
from rigsim.scenarios.records.model.calibrate import calibrate, with_sigma
from rigsim.scenarios.records.model.fallback import HYBRID_LIMIT
from rigsim.scenarios.records.model.family import DEFAULT_NAMES, STATION_FITTED
from rigsim.scenarios.records.model.result import Calibration, model_error

__all__ = ["AUTO", "HELD", "FITTED_CAB", "CAB_CHOICES", "MIN_GAIN", "EDGE", "SCAN_HZ", "SCAN_TRUSTED", "mean_square", "excess_square", "scan_error",
           "cab_scan", "best_scan", "scan_gains", "choose", "check_cab", "calibrate_cab"]

#: The fields of the calibration with the cab's mount frequency fitted: the default ones and the cab's.
WITH_CAB = DEFAULT_NAMES + ("cab_mount_hz",)

#: The cab modes: choose by the fits (default), hold the cab (rigid or the scenario's mount), fit it.
AUTO, HELD, FITTED_CAB = "auto", "held", "fitted"
CAB_CHOICES = (AUTO, HELD, FITTED_CAB)
#: Least relative reduction of the mean squared fit NRMSE over the wheels for the fitted cab to be
#: kept, 1. The fits measured differ by 0 % (cab irrelevant) or by 70-96 % (cab on, or a fit
#: wandering off): 0.2 sits far from both.
MIN_GAIN = 0.2
#: A mount frequency within this fraction of an end of its search range is at the edge (1).
EDGE = 0.02
#: The cab mounts tried at the cab-held optimum (:func:`cab_scan`), Hz: 1-8 Hz a quarter octave
#: apart, around a suspended cab's 1.5-3 Hz (``rigsim.mjcf.variant.BOUNDS``) from the fitted cab's
#: search range's bottom.
SCAN_HZ = tuple(float(v) for v in np.round(1.0 * 2.0 ** (np.arange(13) / 4.0), 2))
#: Largest model error of the cab-held fit (:attr:`Calibration.excess_nrmse` of its second-worst
#: fitted wheel, :func:`scan_error`) at which :func:`cab_scan` decides, 1: half the hybrid
#: correction's limit on it (:data:`~rigsim.scenarios.records.model.fallback.HYBRID_LIMIT`, 0.25),
#: above every fit of a truck in the model's family (at most 0.062 on the paper and generalization
#: cases) and below the paper suite's stiffening tire, whose held fit (0.20-0.21) the scan
#: misjudges. Above it both calibrations run.
SCAN_TRUSTED = HYBRID_LIMIT / 2


def mean_square(cal: Calibration) -> float:
    """Mean square fit NRMSE of the wheels the calibration fitted (:attr:`Calibration.wheels`), 1."""
    return float(np.mean([e * e for c, e in zip(CORNERS, cal.fit_nrmse) if c in cal.wheels]))


def excess_square(cal: Calibration) -> float:
    """Mean square over the wheels the calibration fitted of the fit NRMSE beyond the load cells' noise
    (:func:`~rigsim.scenarios.records.model.result.model_error` of :attr:`Calibration.fit_nrmse` and
    :attr:`Calibration.noise_nrmse`; the fit NRMSE itself where the noise was not estimated), 1: what
    the model itself misses, which a structure added to it can remove (the noise it cannot)."""
    errors = model_error(cal.fit_nrmse, cal.noise_nrmse) if cal.noise_nrmse else cal.fit_nrmse
    return float(np.mean([e * e for c, e in zip(CORNERS, errors) if c in cal.wheels]))


def scan_error(cal: Calibration) -> float:
    """The model error (1) that decides whether :func:`cab_scan` is trusted: the second largest of
    :attr:`Calibration.excess_nrmse` over the wheels the calibration fitted (the largest where it
    fitted one)."""
    errors = sorted(e for c, e in zip(CORNERS, cal.excess_nrmse) if c in cal.wheels)
    return float(errors[-2] if len(errors) > 1 else errors[-1])


def cab_scan(state, hz=SCAN_HZ) -> tuple[float, float]:
    """The most a cab on its own mounts could reduce a cab-held fit's squared residual, to first order.

    Parameters
    ----------
    state : FitState
        The cab-held fit (:func:`~rigsim.scenarios.records.model.calibrate.calibrate` ``with_state``), its
        worker pool running.
    hz : sequence of float, Hz
        The mount frequencies tried, each one truck run per window at the optimum with the cab on them.

    Returns
    -------
    (float, float)
        The largest gain (1, a share of the residual's sum of squares: the part of it along the
        cab's added residual once the held fit's Jacobian columns are projected out of both) and the
        mount frequency that gives it (Hz).
    """
    return best_scan(state, ("cab_mount_hz",), hz)


def best_scan(state, fields, hz, fixed: dict | None = None) -> tuple[float, float]:
    """The largest of :func:`scan_gains` (1) over ``hz`` (Hz) given to every one of ``fields`` at the
    fit's optimum (with the fields of ``fixed`` at its values, SI), and the frequency that gives it
    (Hz): :func:`cab_scan`'s, and the frame's and the engine's scans'."""
    gains = scan_gains(state, [dict.fromkeys(fields, float(f)) | (fixed or {}) for f in hz])
    best = int(np.argmax(gains))
    return gains[best], float(hz[best])


def scan_gains(state, changes) -> list[float]:
    """Per change of the truck at a fit's optimum, the share of the fit's squared residual it would
    remove beyond what the fitted values can, to first order (:func:`cab_scan`'s measure).

    Parameters
    ----------
    state : FitState
        The fit, its Jacobian computed and its worker pool running.
    changes : sequence of dict
        Each a set of ``TruckVariant`` fields (SI) given at the optimum: one truck run per window.

    Returns
    -------
    list of float, 1
    """
    prob, r0 = state.problem, np.asarray(state.residual, float)
    base = prob.variant(state.theta)
    runs = prob.runs([dataclasses.replace(base, **c) for c in changes])
    q, _ = np.linalg.qr(np.asarray(state.jacobian, float))
    r = r0 - q @ (q.T @ r0)
    total = float(r0 @ r0)
    gains = []
    for m in runs:
        d = prob.residual(m) - r0
        d = d - q @ (q.T @ d)
        dd = float(d @ d)
        gains.append(float((d @ r) ** 2 / dd / total) if dd > 0.0 and total > 0.0 else 0.0)
    return gains


def choose(held: Calibration, fitted: Calibration, min_gain: float = MIN_GAIN) -> tuple[Calibration, str]:
    """The calibration to use of the cab held and the cab fitted, and one sentence why."""
    ms_h, ms_f = mean_square(held), mean_square(fitted)
    hz = fitted.fitted_cab_hz
    gain = 1.0 - ms_f / ms_h if ms_h > 0 else 0.0
    what = (f"the cab fitted on {hz:.3g} Hz mounts reproduces the measured forces to fit NRMSE "
            f"{np.sqrt(ms_f):.3f} (rms of the wheels), the cab held to {np.sqrt(ms_h):.3f}")
    if fitted.at_edge("cab_mount_hz", EDGE):
        lo, hi = fitted.bounds[fitted.names.index("cab_mount_hz")]
        if hz - lo < hi - hz:
            return held, f"cab held: {what}, but the mount frequency stopped at its search range's bottom."
        if gain >= min_gain:  # mounts so stiff the cab is rigid
            return fitted, (f"cab fitted: {what}; mounts that stiff make the cab practically rigid, and the fit "
                            "with them found the better truck.")
    if gain < min_gain:
        return held, f"cab held: {what}, less than {min_gain:.0%} better in mean square."
    return fitted, f"cab fitted: {what}."


def check_cab(cab: str, names=None) -> None:
    """Refuse (one sentence) an unknown cab mode, or a mode beside an explicit list of fitted fields."""
    if cab not in CAB_CHOICES:
        raise ScenarioError(f"cab must be one of {', '.join(CAB_CHOICES)}, got {cab!r}")
    if names is not None and cab != AUTO:
        raise ScenarioError(f"give the fitted fields (names) or the cab mode (cab={cab!r}), not both")


def calibrate_cab(t_s, x_a_m, force_N, *, cab: str = AUTO, fitted_guess: dict | None = None,
                  workers: int | None = None, executor=None, defer=None, symmetric: bool = False,
                  with_state: bool = False, **calibrate_kw):
    """Calibrate the truck model with the cab held, fitted, or (default) whichever fits clearly better.

    Parameters
    ----------
    t_s, x_a_m, force_N
        The record, as for :func:`~rigsim.scenarios.records.model.calibrate.calibrate`: time
        (s), measured pan displacement (m, (n, 4)), measured wheel force (N, (n, 4)).
    cab : {"auto", "held", "fitted"}
        "held": :data:`~rigsim.scenarios.records.model.family.DEFAULT_NAMES` (the cab rigid,
        or at ``fitted_guess["cab_mount_hz"]``); "fitted": the cab's mount frequency fitted too
        (from that value or 2.5 Hz); "auto": both, and :func:`choose`.
    fitted_guess : dict, optional
        First guesses (SI), as for ``calibrate``.
    workers : int, optional
        Worker processes (default: all cores), one pool for every calibration.
    executor : concurrent.futures.Executor, optional
        A running pool to use instead.
    defer : callable, optional
        ``defer(held)`` -> str: with "auto", why the cab-held calibration is to be redone before the
        cab is chosen ("" where it is not), e.g. one wheel far off every other, to be left out
        (``fallback.outlier_wheel``); where it gives a reason the held calibration is returned
        as it is, its :attr:`~Calibration.cab_choice` saying so.
    symmetric : bool
        Hold each axle's left and right wheel stations alike: the fields of
        :data:`~rigsim.scenarios.records.model.family.STATION_FITTED` left out of every calibration
        (``names`` included).
    with_state : bool
        Return the kept fit's :class:`~rigsim.scenarios.records.model.problem.FitState` too, its
        Jacobian computed (for runs at the optimum with ``executor`` still running); None where
        ``defer`` gave a reason.
    **calibrate_kw
        Passed to ``calibrate`` (``base_scenario`` required; ``x_ref_m``, ``windows``, ``max_nfev``...);
        ``names`` (with ``cab`` "auto" only): exactly these fields, one calibration, no choice.

    Returns
    -------
    Calibration, or (Calibration, FitState or None) with ``with_state``
        The one used; with "auto", :attr:`Calibration.cab_choice` says which and why, and its
        :attr:`~Calibration.wall_time_s` (s) is both calibrations' (the cab-fitted one run only
        where it could be clearly better, :func:`cab_scan`).

    Raises
    ------
    ScenarioError
        An unknown ``cab``, or what ``calibrate`` refuses (before any model run).
    """
    names = calibrate_kw.pop("names", None)
    check_cab(cab, names)
    with local_executor(workers) if executor is None else contextlib.nullcontext(executor) as ex:
        def run(names, **kw):
            names = tuple(k for k in names if not (symmetric and k in STATION_FITTED))
            return calibrate(t_s, x_a_m, force_N, names=names, fitted_guess=fitted_guess, executor=ex,
                             **(calibrate_kw | kw))

        if names is not None or cab != AUTO:
            return run(names or (WITH_CAB if cab == FITTED_CAB else DEFAULT_NAMES), with_state=with_state)
        # Each fit's uncertainties (a Jacobian at its optimum) are computed only where it is kept.
        w0 = time.perf_counter()
        held, state = run(DEFAULT_NAMES, with_state=True, sigma=False)
        later = defer(held) if defer is not None else ""
        if later:
            held = dataclasses.replace(with_sigma(held, state)[0],
                                       cab_choice=f"cab held, not chosen on this calibration: {later}")
            return (held, None) if with_state else held
        error = scan_error(held)
        gain, hz = 1.0, None  # a model far off, or a cab variant that would not run: the scan cannot tell
        if error <= SCAN_TRUSTED:
            held, state = with_sigma(held, state)  # the scan projects out the held fit's Jacobian
            with contextlib.suppress(ScenarioError, SimulationError):
                gain, hz = cab_scan(state)
        if gain < MIN_GAIN / 2:  # no cab could make the fit clearly better (the scan ran: its Jacobian computed)
            held = dataclasses.replace(held, cab_choice=(
                f"cab held: a cab on its own mounts would remove at most {gain:.0%} of the cab-held fit's squared "
                f"residual (on {hz:.3g} Hz mounts, to first order; the held fit's model error {error:.3f} on its "
                f"second-worst wheel), less than {MIN_GAIN / 2:.0%}, so it was not fitted."),
                evaluations=state.problem.evaluations, wall_time_s=round(time.perf_counter() - w0, 3))
            return (held, state) if with_state else held
        fitted, fitted_state = run(WITH_CAB, with_state=True, sigma=False)
        chosen, why = choose(held, fitted)
        chosen, kept = with_sigma(chosen, state if chosen is held else fitted_state)
        evaluations = state.problem.evaluations + fitted_state.problem.evaluations
        wall = round(time.perf_counter() - w0, 3)
    chosen = dataclasses.replace(chosen, cab_choice=why, evaluations=evaluations, wall_time_s=wall)
    return (chosen, kept) if with_state else chosen
