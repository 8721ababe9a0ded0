"""Settings of ``rigsim validate``: frequency ranges, goals, step sizes, identification record.

One home for the numbers every module of :mod:`rigsim.scenarios.studies.validate` shares, and for the
scenario the validation runs (the paper's Table 1 case). The identification drive itself
(RMS, spectrum, band, seed, fade-in) and what of its record is analysed (``IDENT_SKIP_S``) live
with the other drives in :mod:`rigsim.scenarios.core.drive`.
"""

from __future__ import annotations

import dataclasses
import pathlib

from rigsim.correction.output.lowpass import BAND_HZ
from rigsim.scenarios.core.config import PAPER_CONFIGURATIONS, Scenario, load_scenario, paper_scenarios

__all__ = [
    "BODE_RANGE_HZ", "COMPARE_MAX_HZ", "COHERENCE_MIN", "GOAL_FRF_DB", "GOAL_FRF_DEG", "GOAL_TABLE1_PCT",
    "STEP_SMALL_M", "STEP_LARGE_M", "STEP_RUN_S", "STEP_AT_S", "IDENT_RATE_HZ",
    "MIN_IDENT_S", "FIT_ORDERS", "MAX_WORKERS", "TABLE1_SCENARIO", "table1_scenario_path", "validation_scenario",
]

#: Frequency range of the Bode plots, Hz.
BODE_RANGE_HZ = (0.1, 50.0)
#: Upper end of the FRF comparisons against route 2, Hz: the correction's band limit.
COMPARE_MAX_HZ = BAND_HZ
#: Multiple coherence (1) above which an identified FRF point counts.
COHERENCE_MIN = 0.95
#: The validation's goals: route 3 within GOAL_FRF_DB (dB) and GOAL_FRF_DEG (deg) of route 2 up to
#: COMPARE_MAX_HZ, and the linearized-model DLC within GOAL_TABLE1_PCT (%) of the rig's.
GOAL_FRF_DB, GOAL_FRF_DEG, GOAL_TABLE1_PCT = 0.5, 5.0, 2.0
#: Step sizes of the Figure 7 analogue, m (about 1 mm and 1 cm).
STEP_SMALL_M, STEP_LARGE_M = 1.0e-3, 1.0e-2
#: Duration of the step runs and the time of the step, s.
STEP_RUN_S, STEP_AT_S = 2.0, 0.05
#: Rate at which the identification record is kept, Hz (the drive has nothing above 60 Hz).
IDENT_RATE_HZ = 1000.0
#: Shortest default identification record, s (default: twice the Table 1 duration).
MIN_IDENT_S = 10.0
#: Orders of the rational fit of route 3 (numerator, denominator): six poles for eq. 4's four
#: plus the spool's pair, three zeros for eq. 4's one and the vehicle's dips.
FIT_ORDERS = (3, 6)
#: Most worker processes: the first batch of runs holds eight independent rig runs.
MAX_WORKERS = 8
#: File name of the shipped Table 1 scenario (high roughness, 72 km/h, 3640 kg).
TABLE1_SCENARIO = "high_72kmh_3640kg.toml"


def table1_scenario_path(configuration: str = "design") -> pathlib.Path:
    """The shipped scenario of the paper's Table 1 (high roughness, 72 km/h, 3640 kg) in a
    configuration of :data:`rigsim.scenarios.core.config.PAPER_CONFIGURATIONS` (``"design"`` or ``"dyntrac"``)."""
    for p in paper_scenarios(configuration):
        if p.name == TABLE1_SCENARIO:
            return p
    raise FileNotFoundError(f"scenarios/data/{PAPER_CONFIGURATIONS[configuration]}/{TABLE1_SCENARIO} "
                            "is missing")  # pragma: no cover


def validation_scenario(path, duration_s: float | None = None, *, friction: bool = True) -> Scenario:
    """The scenario at ``path``, optionally with another duration or without leaf-spring friction.

    Parameters
    ----------
    path : str or pathlib.Path
        Scenario TOML file.
    duration_s : float, s, optional
        Analysed duration replacing the scenario's.
    friction : bool
        False: the leaf springs' dry friction (``spring_friction_*_N``) set to 0 N, as in
        route 2's linearization.
    """
    sc = load_scenario(path)
    if duration_s is not None:
        sc = dataclasses.replace(sc, duration_s=float(duration_s))
    if not friction:
        sc = dataclasses.replace(sc, vehicle=dataclasses.replace(
            sc.vehicle, spring_friction_front_N=0.0, spring_friction_rear_N=0.0))
    return sc
