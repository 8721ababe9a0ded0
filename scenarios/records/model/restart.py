"""A calibration refused for its model error, searched once more from the leaf springs sliding.

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
over the wheels, :func:`~scenarios.records.model.cab_choice.mean_square`), and says so
(:attr:`Calibration.second_start <scenarios.records.model.result.Calibration.second_start>`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from scenarios.records.model.cab_choice import mean_square
from scenarios.records.model.result import Calibration

__all__ = ["SLIDING_START", "FRICTION", "sliding_start", "calibrate_again"]

#: The leaf friction's second start, times its first guess (1): a quarter of the catalogue's
#: friction, well inside its search range (0.05-8 times), slides on every road of the suites.
SLIDING_START = 0.25
#: The fitted fields the second start moves.
FRICTION = ("spring_friction_front_N", "spring_friction_rear_N")


def sliding_start(cal: Calibration, factor: float = SLIDING_START) -> dict:
    """The second start (SI, by field): each fitted leaf friction at ``factor`` times its first guess;
    empty if the calibration fitted no friction."""
    return {k: factor * v for k, v in zip(cal.names, cal.initial) if k in FRICTION}


def calibrate_again(cal: Calibration, run, excess_limit: float) -> Calibration:
    """``cal``, or the fit from :func:`sliding_start` where ``cal``'s model error exceeds ``excess_limit``
    and the new fit is the better one.

    Parameters
    ----------
    cal : Calibration
        The first fit.
    run : callable
        ``run(start)`` -> Calibration: the same calibration of the same record from ``start`` (SI
        values by field, :func:`~scenarios.records.model.calibrate.calibrate`'s ``start``).
    excess_limit : float, 1
        The correction's limit on the model error (:attr:`Calibration.excess_nrmse`).

    Returns
    -------
    Calibration
        The kept fit; a second fit kept carries both fits' evaluations and wall time.
    """
    start = sliding_start(cal)
    if not start or float(np.max(cal.excess_nrmse)) <= excess_limit:
        return cal
    again = run(start)
    better = again.converged and mean_square(again) < mean_square(cal)
    kept = again if better else cal
    said = (f"the first fit refused (model error {max(cal.excess_nrmse):.3f}), searched again from the leaf springs "
            f"sliding (friction {SLIDING_START:g} x its first guess): fit NRMSE {max(again.fit_nrmse):.3f} against "
            f"{max(cal.fit_nrmse):.3f} (worst wheel), the {'second' if better else 'first'} fit kept")
    return dataclasses.replace(kept, evaluations=cal.evaluations + again.evaluations,
                               wall_time_s=round(cal.wall_time_s + again.wall_time_s, 3), second_start=said)
