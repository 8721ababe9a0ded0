"""Whether the truck's cab sits on soft mounts: two calibrations, the clearly better fit kept.

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
below the held cab's, and the mount frequency not at its search range's edge
(:meth:`Calibration.at_edge`). Convergence is not part of the choice: the chosen calibration's is
checked where every calibration's is (a fit that did not converge falls back to the linear
correction, :func:`~scenarios.records.model.differential.fallback_reason`). Measured on generalization cases (30 s, docs/model_correction.md): a
truck with its cab on 2 Hz mounts fits 0.10 against the rigid cab's 0.50 (front wheels), a
rigid-cab truck 0.095 held against 0.35 fitted (gen00) or 0.057 against 0.057 (gen05, the mount
at the range's top, 30 Hz): the two families are far apart where the cab matters and level where
it does not, so the choice does not hinge on the exact threshold.

The price is a second calibration, from the same first guess; ``benchmarks/model_cost.py`` times
both against the cab held alone. Started instead where the cab-held one ended
(``calibrate(start=...)``), it cost more on that benchmark's rigid-cab truck, not less (the
mount's crawl from its 2.5 Hz guess went on to the range's top): 70.7 s wall against 52.9 s.
"""

from __future__ import annotations

import contextlib
import dataclasses

import numpy as np

from mjcf.names import CORNERS
from scenarios.core.config import ScenarioError
from scenarios.core.pool import local_executor
from scenarios.records.model.calibrate import calibrate
from scenarios.records.model.family import DEFAULT_NAMES
from scenarios.records.model.result import Calibration

__all__ = ["AUTO", "HELD", "FITTED_CAB", "CAB_CHOICES", "MIN_GAIN", "EDGE", "mean_square", "choose", "check_cab", "calibrate_cab"]

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


def mean_square(cal: Calibration) -> float:
    """Mean square fit NRMSE of the wheels the calibration fitted (:attr:`Calibration.wheels`), 1."""
    return float(np.mean([e * e for c, e in zip(CORNERS, cal.fit_nrmse) if c in cal.wheels]))


def choose(held: Calibration, fitted: Calibration, min_gain: float = MIN_GAIN) -> tuple[Calibration, str]:
    """The calibration to use of the cab held and the cab fitted, and one sentence why."""
    ms_h, ms_f = mean_square(held), mean_square(fitted)
    hz = fitted.fitted_cab_hz
    gain = 1.0 - ms_f / ms_h if ms_h > 0 else 0.0
    what = (f"the cab fitted on {hz:.3g} Hz mounts reproduces the measured forces to fit NRMSE "
            f"{np.sqrt(ms_f):.3f} (rms of the wheels), the cab held to {np.sqrt(ms_h):.3f}")
    if fitted.at_edge("cab_mount_hz", EDGE):
        return held, f"cab held: {what}, but the mount frequency stopped at its search range's edge."
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
                  workers: int | None = None, executor=None, **calibrate_kw) -> Calibration:
    """Calibrate the truck model with the cab held, fitted, or (default) whichever fits clearly better.

    Parameters
    ----------
    t_s, x_a_m, force_N
        The record, as for :func:`~scenarios.records.model.calibrate.calibrate`: time
        (s), measured pan displacement (m, (n, 4)), measured wheel force (N, (n, 4)).
    cab : {"auto", "held", "fitted"}
        "held": :data:`~scenarios.records.model.family.DEFAULT_NAMES` (the cab rigid,
        or at ``fitted_guess["cab_mount_hz"]``); "fitted": the cab's mount frequency fitted too
        (from that value or 2.5 Hz); "auto": both, and :func:`choose`.
    fitted_guess : dict, optional
        First guesses (SI), as for ``calibrate``.
    workers : int, optional
        Worker processes (default: all cores), one pool for both calibrations.
    executor : concurrent.futures.Executor, optional
        A running pool to use instead.
    **calibrate_kw
        Passed to ``calibrate`` (``base_scenario`` required; ``x_ref_m``, ``windows``, ``max_nfev``...);
        ``names`` (with ``cab`` "auto" only): exactly these fields, one calibration, no choice.

    Returns
    -------
    Calibration
        The one used; with "auto", :attr:`Calibration.cab_choice` says which and why, and its
        :attr:`~Calibration.wall_time_s` (s) is both calibrations'.

    Raises
    ------
    ScenarioError
        An unknown ``cab``, or what ``calibrate`` refuses (before any model run).
    """
    names = calibrate_kw.pop("names", None)
    check_cab(cab, names)
    with local_executor(workers) if executor is None else contextlib.nullcontext(executor) as ex:
        def run(names) -> Calibration:
            return calibrate(t_s, x_a_m, force_N, names=names, fitted_guess=fitted_guess, executor=ex, **calibrate_kw)

        if names is not None:
            return run(names)
        if cab != AUTO:
            return run(WITH_CAB if cab == FITTED_CAB else DEFAULT_NAMES)
        held = run(DEFAULT_NAMES)
        fitted = run(WITH_CAB)
    chosen, why = choose(held, fitted)
    return dataclasses.replace(chosen, cab_choice=why, evaluations=held.evaluations + fitted.evaluations,
                               wall_time_s=round(held.wall_time_s + fitted.wall_time_s, 3))
