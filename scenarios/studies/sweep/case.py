"""One case of a sweep: road run, rig run, output correction and the row of scores.

:func:`evaluate_case` is the whole per-case evaluation; :func:`evaluate_payload` is what a worker
process runs (plain, picklable arguments in, a JSON-ready record out, errors caught and recorded).

The correction (:func:`corrected_forces`): each wheel's rig force is filtered by ``T_a^-1 T_F``
(:mod:`correction.filters`, :mod:`correction.apply`), ``T_a`` being the paper's eq. 4 from the
scenario's actuator parameters (:func:`hydraulics.linearization.eq4_coefficients`), linearized at
that wheel's static actuator load (mean tire force plus the pan's weight), with the wheel station's
tire stiffness from the compiled truck (front: one tire, rear: the dual pair) and the rig's pan
mass. The reference for the corrected force is the road force through the same band limit
(:func:`correction.apply.band_limit`): a corrected force can at best equal the road force through
``T_F``. Samples inside the correction's transients (both ends in zero-phase mode, the start in
causal mode) are left out of every band-limited score.
"""

from __future__ import annotations

import math
import pathlib
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["CorrectedForces", "corrected_forces", "evaluate_case", "evaluate_payload", "tire_stiffness",
           "METRIC_COLUMNS", "EVENT_NAMES"]

#: Hydraulic events counted per case (output samples, summed over the four wheels).
EVENT_NAMES = ("spool_saturation", "cavitation", "overpressure")

#: The scores of one case, in the order of ``results.csv``.
METRIC_COLUMNS = (
    "dlc_road", "dlc_rig", "dlc_corrected", "dlc_road_band", "dlc_rig_band",
    "nrmse_rig", "nrmse_corrected", "scored_s",
    *(f"{e}_samples" for e in EVENT_NAMES),
)

_MIN_SCORED_S = 0.25  # s; fewer settled seconds than this cannot give a meaningful DLC


@dataclass(frozen=True)
class CorrectedForces:
    """The corrected rig forces and their reference, per wheel.

    Attributes
    ----------
    corrected_N : numpy.ndarray, N, shape (n, 4)
        Rig tire forces filtered by ``T_a^-1 T_F``.
    road_band_N, rig_band_N : numpy.ndarray, N, shape (n, 4)
        Road and rig tire forces through ``T_F`` alone (same mode).
    settled : numpy.ndarray of bool, shape (n,)
        Samples outside every filter's transients (the scored samples).
    description : str
        One line: low-pass, mode, linearization.
    """

    corrected_N: np.ndarray
    road_band_N: np.ndarray
    rig_band_N: np.ndarray
    settled: np.ndarray
    description: str


def tire_stiffness(vehicle) -> np.ndarray:
    """Tire stiffness (N/m) of each wheel station of the truck variant, in ``CORNERS`` order.

    Read from the model as built (``biasprm[1] = -k`` of each ``tire_<corner>`` actuator), so it
    is the value the simulation uses, overrides included.
    """
    from mjcf.build import CORNERS, build_spec

    spec = build_spec(vehicle, scene=False)
    return np.array([-float(spec.actuator(f"tire_{c}").biasprm[1]) for c in CORNERS])


def corrected_forces(scenario, road, rig, *, lowpass: str = "regularized", correction_mode: str = "zerophase",
                     settling_tolerance: float = 1e-2) -> CorrectedForces:
    """Correct the rig forces of ``rig`` and band-limit the road forces of ``road``.

    Parameters
    ----------
    scenario : Scenario
        The case (actuator parameters, truck variant).
    road, rig : RunResult
        The road-mode and rig-mode runs of ``scenario`` (same time axis).
    lowpass : {"regularized", "paper"}
    correction_mode : {"zerophase", "causal"}
    settling_tolerance : float, 1
        Tolerance of the filters' transients (:func:`correction.filters.design_correction`).

    Returns
    -------
    CorrectedForces
    """
    from correction.apply import band_limit, correct
    from correction.filters import design_correction, reference_filter
    from hydraulics.linearization import eq4_coefficients
    from hydraulics.params import GRAVITY_M_S2
    from scenarios.core.rig import actuator_params

    params = actuator_params(scenario)
    fs = float(scenario.output_rate_hz)
    f_rig = np.asarray(rig.signals["tire_force_N"])
    f_road = np.asarray(road.signals["tire_force_N"])
    n = f_rig.shape[0]
    kt = tire_stiffness(scenario.vehicle)
    mp = scenario.vehicle.pan_mass_kg if scenario.vehicle.pan_mass_kg is not None else params.pan_mass_kg
    corrected = np.empty_like(f_rig)
    settled = np.ones(n, dtype=bool)
    for i in range(f_rig.shape[1]):
        load = float(np.mean(f_rig[:, i])) + mp * GRAVITY_M_S2  # static actuator load of this wheel
        num, den = eq4_coefficients(params, float(kt[i]), load, mass_kg=mp)
        filt = design_correction((num, den), fs, lowpass, settling_tolerance=settling_tolerance)
        corrected[:, i] = correct(f_rig[:, i], filt, correction_mode)
        settled &= filt.transient_mask(n, correction_mode)
    ref = reference_filter(fs, lowpass, settling_tolerance=settling_tolerance)
    settled &= ref.transient_mask(n, correction_mode)
    return CorrectedForces(
        corrected_N=corrected,
        road_band_N=band_limit(f_road, fs, lowpass, correction_mode),
        rig_band_N=band_limit(f_rig, fs, lowpass, correction_mode),
        settled=settled,
        description=f"T_a eq. 4 at the static load per wheel, low-pass {lowpass}, {correction_mode}",
    )


def _dlc(f: np.ndarray) -> np.ndarray:
    from correction.dlc import dlc

    return dlc(f, axis=0)


def _nrmse(f: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """RMS of ``f - ref`` over the standard deviation of ``ref`` (the dynamic load), per column."""
    return np.sqrt(np.mean((f - ref) ** 2, axis=0)) / np.std(ref, axis=0)


def _event_counts(events) -> dict[str, int]:
    out = {}
    for name in EVENT_NAMES:
        per_corner = events.get(name, {}) or {}
        out[f"{name}_samples"] = int(sum(int(v.get("samples", 0)) for v in per_corner.values()))
    return out


def evaluate_case(scenario, *, lowpass: str = "regularized", correction_mode: str = "zerophase",
                  settling_tolerance: float = 1e-2) -> dict[str, Any]:
    """Run a scenario on the road and on the rig, correct the rig forces, and score them.

    Parameters
    ----------
    scenario : Scenario
    lowpass : {"regularized", "paper"}
        The correction's low-pass ``T_F`` (:mod:`correction.lowpass`).
    correction_mode : {"zerophase", "causal"}
    settling_tolerance : float, 1
        Samples inside the filters' transients at this tolerance are not scored.

    Returns
    -------
    dict
        :data:`METRIC_COLUMNS` (means over the four wheels; DLC and NRMSE dimensionless,
        ``scored_s`` in s, event counts in output samples), ``wall_time_s`` (s), and ``wheels``:
        per wheel the same DLC and NRMSE values.

    Raises
    ------
    ScenarioError
        Bad input found when the case starts (e.g. a drive beyond the stroke, an unstable rig),
        or a record too short to score beyond the correction's transients.
    SimulationError
        A MuJoCo warning or divergence, naming the simulated time.
    ValueError
        The correction filter cannot be designed for this actuator (one sentence).
    """
    from mjcf.build import CORNERS
    from scenarios.core.config import ScenarioError
    from scenarios.core.runner import run

    wall0 = time.perf_counter()
    road = run(scenario, "road")
    rig = run(scenario, "rig")
    cf = corrected_forces(scenario, road, rig, lowpass=lowpass, correction_mode=correction_mode,
                          settling_tolerance=settling_tolerance)
    m = cf.settled
    scored_s = float(np.count_nonzero(m)) / float(scenario.output_rate_hz)
    if scored_s < _MIN_SCORED_S:
        lost = (m.size - np.count_nonzero(m)) / float(scenario.output_rate_hz)
        raise ScenarioError(
            f"duration_s = {scenario.duration_s:g} s leaves {scored_s:.2f} s to score after the correction's "
            f"transients ({lost:.2f} s); use duration_s >= {lost + 1.0:.0f} s")
    f_road = np.asarray(road.signals["tire_force_N"])
    f_rig = np.asarray(rig.signals["tire_force_N"])
    per = {
        "dlc_road": _dlc(f_road),
        "dlc_rig": _dlc(f_rig),
        "dlc_corrected": _dlc(cf.corrected_N[m]),
        "dlc_road_band": _dlc(cf.road_band_N[m]),
        "dlc_rig_band": _dlc(cf.rig_band_N[m]),
        "nrmse_rig": _nrmse(cf.rig_band_N[m], cf.road_band_N[m]),
        "nrmse_corrected": _nrmse(cf.corrected_N[m], cf.road_band_N[m]),
    }
    row: dict[str, Any] = {k: float(np.mean(v)) for k, v in per.items()}
    row["scored_s"] = scored_s
    row.update(_event_counts(rig.events))
    row["wheels"] = {c: {k: float(v[i]) for k, v in per.items()} for i, c in enumerate(CORNERS)}
    row["events"] = dict(rig.events)
    row["correction"] = cf.description
    row["wall_time_s"] = round(time.perf_counter() - wall0, 3)
    return row


def _one_sentence(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 400 else text[:397] + "..."


def evaluate_payload(case_id: str, doc: dict, source: str | None, settings: dict) -> dict[str, Any]:
    """Worker entry point: parse, evaluate and wrap one case; never raises for a bad case.

    Parameters
    ----------
    case_id : str
    doc : dict
        The case's scenario document (plain TOML types, picklable).
    source : str or None
        Path relative scenario paths are resolved against.
    settings : dict
        Keyword arguments of :func:`evaluate_case`.

    Returns
    -------
    dict
        ``{"case_id", "status": "ok" | "failed", "error": str | None, "retry": bool,
        "result": dict | None, "wall_time_s": float}``. ``retry`` is True for errors that are not
        a property of the case (an unexpected exception), so a resumed sweep runs it again.
    """
    from scenarios.core.config import ScenarioError, parse_scenario
    from scenarios.core.runner import SimulationError

    wall0 = time.perf_counter()
    record: dict[str, Any] = {"case_id": case_id, "status": "ok", "error": None, "retry": False, "result": None}
    try:
        scenario = parse_scenario(doc, source=pathlib.Path(source) if source else None)
        record["result"] = evaluate_case(scenario, **settings)
    except (ScenarioError, SimulationError, ValueError, ArithmeticError) as exc:
        record.update(status="failed", error=_one_sentence(exc))
    except Exception as exc:  # noqa: BLE001 - any other error of one case must not stop the sweep
        record.update(status="failed", error=f"{type(exc).__name__}: {_one_sentence(exc)}", retry=True)
    record["wall_time_s"] = round(time.perf_counter() - wall0, 3)
    if record["result"] is not None and not all(
            math.isfinite(record["result"][k]) for k in METRIC_COLUMNS):
        record.update(status="failed", error="a score is not finite (NaN or infinity)")
    return record
