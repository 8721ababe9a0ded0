"""The progressive tire's onset fitted as the wheel load where the tire stiffens, not as a deflection.

The calibrated model's tire is bilinear (``TruckVariant.tire_progressive_ratio``): stiffness kt up
to the onset deflection, (1 + ratio) kt beyond it, so the tire stiffens at the wheel load
F_on = kt x onset. The calibration searches F_on (N) instead of the onset (m), within the loads
its windows measure on that axle (:func:`load_range`), and hands MuJoCo onset = F_on / kt:

* an onset whose load lies beyond every measured load changes no model force, so neither it nor
  the ratio has a gradient, and a fit that wanders there stays there: searched in metres, the
  generalization suite's gen00 and gen12 (30 s, a +25 % tire at 2 cm, rear static deflection
  1.95 cm) start from the catalogue's 2 cm at the catalogue's rear kt (2.07 MN/m: 41 kN, above the
  largest rear load of 36-38 kN), never move the rear ratio, and end linear at the range's top
  (4 cm), their rear wheels at 0.51-0.56 of the linear floor;
* a load range does not move when kt does: a bound in metres would;
* every bilinear tire is still representable on the measured loads: one stiffening below the
  smallest load is the same there as one at that load, one beyond the largest the same as a
  linear tire.

The first guess is the axle's median measured load, its static load, where the kink has
measured loads on both sides; an onset given in metres (a lab's ``[vehicle]`` value) is taken at
the first-guess kt where that load lies inside the range, and replaced by the median where not.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ONSET_STIFFNESS", "ONSET_RATIO", "ONSET_WHEELS", "TOP", "load_range", "load_guess"]

#: Each fitted onset and the linear stiffness whose load it is: the all-wheel onset is the front
#: tires' (the rear take it too when their own is not given, at the front's load).
ONSET_STIFFNESS = {"tire_progressive_onset_m": "tire_stiffness_front_N_per_m",
                   "tire_progressive_onset_rear_m": "tire_stiffness_rear_N_per_m"}
#: Each onset's ratio.
ONSET_RATIO = {"tire_progressive_onset_m": "tire_progressive_ratio",
               "tire_progressive_onset_rear_m": "tire_progressive_ratio_rear"}
#: An onset fitted within this fraction (1) of its load range's top has no measured load beyond it
#: to show its ratio, which the fit leaves wherever it wandered: :func:`calibrate` sets that ratio
#: to 0, a tire linear over every load the record shows, rather than extrapolate a stiffening it
#: never saw to the larger loads of the drive (the walk-through's front tires, linear in truth, fit
#: ratio 0.70 at 4.18 cm, past their largest load; their corrected DEL5 comes out 28.90 kN against
#: 28.38 kN with the ratio set to 0).
TOP = 0.02
#: The record's columns (corners fl, fr, rl, rr) whose loads bound each onset.
ONSET_WHEELS = {"tire_progressive_onset_m": (0, 1), "tire_progressive_onset_rear_m": (2, 3)}


def _loads(force_N, windows, name: str) -> np.ndarray:
    cols = list(ONSET_WHEELS[name])
    return np.concatenate([np.asarray(force_N, float)[s:e, cols].ravel() for _, s, e in windows])


def _range(loads: np.ndarray) -> tuple[float, float]:
    return max(float(loads.min()), 0.0), max(float(loads.max()), 0.0)


def load_range(force_N, windows, name: str) -> tuple[float, float]:
    """(smallest, largest) measured load of onset ``name``'s wheels on the scored samples of
    ``windows`` ((run start, scored start, end) sample triples), N; neither below 0: a wheel off
    the ground reads 0 and the load cells' noise about it (generalization case gen03, an empty
    truck on a class D road, reads below 0 at the front, and a negative onset is refused)."""
    return _range(_loads(force_N, windows, name))


def load_guess(force_N, windows, name: str, onset_m: float | None, kt_N_per_m: float) -> float:
    """First guess of the load at onset ``name``, N: ``onset_m`` (m) at ``kt_N_per_m`` (N/m) where
    that load lies strictly inside :func:`load_range`; otherwise (or None) the wheels' median load:
    an onset at or beyond the measured loads would start the fit where its ratio has no gradient."""
    loads = _loads(force_N, windows, name)
    lo, hi = _range(loads)
    if onset_m is not None and lo < onset_m * kt_N_per_m < hi:
        return float(onset_m * kt_N_per_m)
    return float(np.clip(np.median(loads), lo, hi))
