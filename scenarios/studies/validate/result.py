"""The result of ``rigsim validate``: what ``validate.json`` holds, plus the curves for the figures.

:class:`ValidateResult` is written by :func:`rigsim.scenarios.core.files.write_json` through its
:meth:`ValidateResult.to_dict` (the document's one builder); :class:`ValidateCurves` and the
kept runs stay out of the JSON.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.studies.validate.routes import nanmax
from rigsim.scenarios.studies.validate.settings import (BODE_RANGE_HZ, COHERENCE_MIN, COMPARE_MAX_HZ, GOAL_FRF_DB,
                                                        GOAL_FRF_DEG, GOAL_TABLE1_PCT)

__all__ = ["ValidateCurves", "ValidateResult"]

STEP_MODELS = {"headline": "step_max_error_*: route 2 against the nonlinear rig; *_eq4: eq. 4",
               "route2": "the whole linearized plant (all four inputs stepped: cross-coupling included)",
               "route1": "eq. 4 per wheel", "route3": "rational fit per wheel (own path only)"}


@dataclass(frozen=True)
class ValidateCurves:
    """The curves behind the figures (not written to JSON). Complex responses are x_a / x_ref (m/m).

    Attributes
    ----------
    f_bode_hz : numpy.ndarray, Hz, (nb,)
        Bode grid over :data:`BODE_RANGE_HZ`.
    h_route1 : Mapping[str, numpy.ndarray]
        Eq. 4 per corner at ``f_bode_hz``, complex (nb,).
    h_route2 : numpy.ndarray, complex, (nb, 4, 4)
        Route 2 at ``f_bode_hz`` [output, input].
    f_compare_hz : numpy.ndarray, Hz, (nc,)
        Comparison grid, 0.1 Hz to :data:`COMPARE_MAX_HZ`.
    h_route2_compare : numpy.ndarray, complex, (nc, 4, 4)
        Route 2 at ``f_compare_hz``.
    budget : Mapping[str, Mapping[str, numpy.ndarray]]
        Per corner, each stage of the departure budget at ``f_compare_hz``, complex (nc,).
    f_ident_hz : numpy.ndarray, Hz, (ni,)
        Frequencies of the H1 estimate.
    h_ident : numpy.ndarray, complex, (ni, 4, 4)
        Route 3's H1 estimate.
    coherence : numpy.ndarray, 1, (ni, 4)
        Its multiple coherence.
    h_route2_at_ident : numpy.ndarray, complex, (ni, 4, 4)
        Route 2 at ``f_ident_hz``.
    fits : list of control.TransferFunction
        Route 3's rational fit per corner (s in rad/s).
    steps : Mapping[str, Mapping[str, numpy.ndarray]]
        "small" / "large": ``t_s`` (s, (n,)), ``nonlinear``, ``route1``, ``route2``, ``route3``
        pan displacements (m, (n, 4)).
    """

    f_bode_hz: np.ndarray
    h_route1: Mapping
    h_route2: np.ndarray
    f_compare_hz: np.ndarray
    h_route2_compare: np.ndarray
    budget: Mapping
    f_ident_hz: np.ndarray
    h_ident: np.ndarray
    coherence: np.ndarray
    h_route2_at_ident: np.ndarray
    fits: list
    steps: Mapping


@dataclass(frozen=True)
class ValidateResult:
    """Everything ``rigsim validate`` computed.

    Attributes
    ----------
    scenario : str
        Name of the Table 1 scenario.
    duration_s : float, s
        Analysed duration of the Table 1 runs.
    ident_duration_s : float, s
        Analysed duration of the identification record.
    timestep_s : float, s
        The rig and road tests' time step (the drive held at mid-step).
    integrator : str
        Their integrator, as MuJoCo names it without its prefix ("RK4").
    linear_timestep_s : float, s
        The linearization's time step (explicit Euler).
    route1, route2, route3 : Mapping
        The routes (:mod:`rigsim.scenarios.studies.validate.sections`): bandwidths in Hz, errors
        against route 2 in dB and deg up to :data:`COMPARE_MAX_HZ`, poles and zeros in rad/s.
    departure_budget : Mapping
        Each step from eq. 4 to route 2 against route 2, dB and deg.
    steps : Mapping
        Figure 7: "small" / "large" step (m) against each linear model, errors in mm and %.
    table1 : Mapping
        Table 1: DLC (1) of road, rig and linearized-model runs, departures from the rig (%).
    diagnostics_friction_off : Mapping
        Route 3 (dB, deg) and the steps (mm, %) without leaf-spring friction.
    wall_time_s : float, s
        Wall time of the whole validation.
    curves : ValidateCurves
        For the figures; not in the JSON.
    runs : Mapping[str, rigsim.scenarios.core.results.RunResult]
        The Table 1 "road" and "rig" runs kept for a recording (empty unless asked); not in the JSON.
    """

    scenario: str
    duration_s: float
    ident_duration_s: float
    timestep_s: float
    integrator: str
    linear_timestep_s: float
    route1: Mapping
    route2: Mapping
    route3: Mapping
    departure_budget: Mapping
    steps: Mapping
    table1: Mapping
    diagnostics_friction_off: Mapping
    wall_time_s: float
    curves: ValidateCurves = field(repr=False)
    runs: Mapping = field(default_factory=dict, repr=False)

    @property
    def bandwidth_hz(self) -> dict:
        """-3 dB bandwidth (Hz) per route and corner (route 3: its rational fit)."""
        return {"route1": self.route1["bandwidth_hz"], "route2": self.route2["bandwidth_hz"],
                "route3": self.route3["bandwidth_hz"]}

    def _frf_max_error(self, unit: str) -> dict:
        return {"route1": self.route1["variants"]["static_mean"][f"frf_max_error_{unit}"],
                "route3": nanmax(self.route3["corners"][c][f"frf_max_error_{unit}"] for c in CORNERS)}

    @property
    def frf_max_error_db(self) -> dict:
        """Largest |error| (dB) against route 2 up to :data:`COMPARE_MAX_HZ`: route 1 (eq. 4) and
        route 3 (H1 where coherence > :data:`COHERENCE_MIN`), over all wheels."""
        return self._frf_max_error("db")

    @property
    def frf_max_error_deg(self) -> dict:
        """Largest |error| (deg) against route 2, as :attr:`frf_max_error_db`."""
        return self._frf_max_error("deg")

    @property
    def goals(self) -> dict:
        """The validation's goals met (bool): route 3 within :data:`GOAL_FRF_DB` dB / :data:`GOAL_FRF_DEG`
        deg, the linearized model within :data:`GOAL_TABLE1_PCT` % of the rig, road above rig."""
        t1 = self.table1
        return {
            "route3_within_0p5db_5deg_to_30hz": bool(self.frf_max_error_db["route3"] <= GOAL_FRF_DB
                                                     and self.frf_max_error_deg["route3"] <= GOAL_FRF_DEG),
            "table1_linearized_within_2pct_of_rig": bool(abs(t1["linearized_vs_rig_pct"]) <= GOAL_TABLE1_PCT),
            "table1_road_above_rig": bool(t1["road_test"] > t1["rig_test"]),
        }

    def to_dict(self) -> dict:
        """The ``validate.json`` document (NaN stays NaN here; :func:`rigsim.scenarios.core.files.to_json`
        writes it as null)."""
        steps = self.steps
        return {
            "scenario": self.scenario,
            "duration_s": self.duration_s,
            "ident_duration_s": self.ident_duration_s,
            "timestep_s": self.timestep_s,
            "integrator": self.integrator,
            "linear_timestep_s": self.linear_timestep_s,
            "compare_range_hz": [BODE_RANGE_HZ[0], COMPARE_MAX_HZ],
            "coherence_min": COHERENCE_MIN,
            "route2": self.route2,
            "route1": self.route1,
            "departure_budget": self.departure_budget,
            "route3": self.route3,
            "bandwidth_hz": self.bandwidth_hz,
            "frf_max_error_db": self.frf_max_error_db,
            "frf_max_error_deg": self.frf_max_error_deg,
            "steps": steps,
            "step_models": dict(STEP_MODELS),
            "step_max_error_small_mm": steps["small"]["route2"]["max_error_mm"],
            "step_max_error_small_pct": steps["small"]["route2"]["max_error_pct"],
            "step_max_error_large_mm": steps["large"]["route2"]["max_error_mm"],
            "step_max_error_large_pct": steps["large"]["route2"]["max_error_pct"],
            "step_max_error_small_pct_eq4": steps["small"]["route1"]["max_error_pct"],
            "step_max_error_large_pct_eq4": steps["large"]["route1"]["max_error_pct"],
            "table1": self.table1,
            "diagnostics_friction_off": self.diagnostics_friction_off,
            "goals": self.goals,
            "wall_time_s": self.wall_time_s,
        }
