"""A calibration refused for its model error, searched again: from the leaf springs sliding, then
with each axle's left and right stations held alike.

The leaf springs' interleaf friction (``spring_friction_front_N``, ``spring_friction_rear_N``) is the
model family's one strong nonlinearity: a spring whose friction exceeds the forces it carries does
not slide, and then neither its friction nor the parameters behind it (the axle's mass, its tires'
damping) move its wheel force much. From the catalogue's first guess the search can settle in such a
locked state far from the truck on the rig: an empty truck on a class D road at 100 km/h, in the
model family (the generalization suite's gen15 case, benchmarks/model_correction.py), fits to a
model error of 0.45 on its rear wheels with the rear axle 29 % light, its tire damping at half the
plant's and its friction at twice it. Started with both springs sliding
(:data:`SLIDING_START` times the first guess) the same record fits to the load cells' noise. Only a
fit the correction would refuse is searched again (its model error above the correction's limit),
so a record that fits costs nothing more; the better of the two fits is kept (mean square fit NRMSE
over the wheels, :func:`~rigsim.scenarios.records.model.cab_choice.mean_square`), and says so
(:attr:`Calibration.second_start <rigsim.scenarios.records.model.result.Calibration.second_start>`).

Where the kept fit is still refused, the truck is fitted once more with each axle's left and right
wheel stations held alike (:data:`~rigsim.scenarios.records.model.family.STATION_FITTED` not fitted, the
symmetric family): eight values fewer to wander along. The same suite's gen15 case on its plant
outside the family (tires stiffening +50 % over 2 cm, symmetric) fits to a model error of 0.38 on
its rear wheels from both starts with the stations free (an axle's left spring 26 % stiffer than
its right, its friction 65 % higher), and to 0.016 with them held alike. A record that fits, or
whose truck is asymmetric and fits with the stations free, costs nothing more.
"""

from __future__ import annotations

import dataclasses

from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.watch import SimulationError
from rigsim.scenarios.records.model.cab_choice import mean_square
from rigsim.scenarios.records.model.fallback import past_limit
from rigsim.scenarios.records.model.family import STATION_FITTED
from rigsim.scenarios.records.model.result import Calibration

__all__ = ["SLIDING_START", "FRICTION", "ORDINALS", "sliding_start", "calibrate_again"]

#: The leaf friction's second start, times its first guess (1): a quarter of the catalogue's
#: friction, well inside its search range (0.05-8 times), slides on every road of the suites.
SLIDING_START = 0.25
#: The fitted fields the second start moves.
FRICTION = ("spring_friction_front_N", "spring_friction_rear_N")
#: The fits' names in the sentence that says which was kept.
ORDINALS = ("first", "second", "third")


def sliding_start(cal: Calibration, factor: float = SLIDING_START) -> dict:
    """The second start (SI, by field): each fitted leaf friction at ``factor`` times its first guess;
    empty if the calibration fitted no friction."""
    return {k: factor * v for k, v in zip(cal.names, cal.initial) if k in FRICTION}


def calibrate_again(cal: Calibration, run, excess_limit: float) -> Calibration:
    """``cal``, or a better fit where ``cal``'s model error exceeds ``excess_limit``: from
    :func:`sliding_start`, then, where the better of those is refused too and ``cal`` fitted left
    and right stations apart, with them held alike.

    Parameters
    ----------
    cal : Calibration
        The first fit.
    run : callable
        ``run(start=..., symmetric=...)`` -> Calibration: the same calibration of the same record
        from ``start`` (SI values by field, :func:`~rigsim.scenarios.records.model.calibrate.calibrate`'s
        ``start``; None: the first guess), with ``symmetric`` each axle's left and right stations
        held alike (:func:`~rigsim.scenarios.records.model.cab_choice.calibrate_cab`'s ``symmetric``). A
        search it refuses (ScenarioError) or whose model run fails (SimulationError) is skipped.
    excess_limit : float, 1
        The correction's limit on the model error (:attr:`Calibration.excess_nrmse`).

    Returns
    -------
    Calibration
        The kept fit: the best converged one (mean square fit NRMSE over the wheels); where more
        than one was searched, it carries all their evaluations and wall time, and its
        :attr:`~Calibration.second_start` says what was searched and which is kept.
    """
    def refused(c: Calibration) -> bool:
        return past_limit(c, excess_limit)

    def best() -> Calibration:  # the first fit, or a converged search's that fits better (ties: the first)
        return min([cal, *(f for f in fits[1:] if f.converged)], key=mean_square)

    if not refused(cal):
        return cal
    fits, tried, searches = [cal], [], []
    start = sliding_start(cal)
    if start:
        searches.append((f"from the leaf springs sliding (friction {SLIDING_START:g} x its first guess)",
                         {"start": start, "symmetric": False}))
    if set(cal.names) & set(STATION_FITTED):
        searches.append(("with each axle's left and right wheel stations held alike", {"start": None, "symmetric": True}))
    for what, kw in searches:
        if not refused(best()):
            break
        try:
            again = run(**kw)
        except (ScenarioError, SimulationError):
            continue
        fits.append(again)
        tried.append(f"{what}: fit NRMSE {max(again.fit_nrmse):.3f}")
    if len(fits) == 1:
        return cal
    kept = best()
    said = (f"the first fit refused (model error {max(cal.excess_nrmse):.3f}), searched again {', then '.join(tried)}, "
            f"against {max(cal.fit_nrmse):.3f} (worst wheel): the {ORDINALS[fits.index(kept)]} fit kept")
    return dataclasses.replace(kept, evaluations=sum(f.evaluations for f in fits),
                               wall_time_s=round(sum(f.wall_time_s for f in fits), 3), second_start=said)
