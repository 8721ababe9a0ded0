"""One case of a sweep: road run, rig run, and their score by the one scoring of the project.

:func:`evaluate_case` runs a scenario on the road and on the rig and scores the pair with
:func:`rigsim.scenarios.studies.scoring.score_pair` (the scoring of ``rigsim paper`` too), by the one
method the sweep's :class:`~rigsim.scenarios.studies.sweep.settings.EvalSettings` name, with their
measurement noise (seeded by the scenario's seed). :func:`evaluate_payload` is what a worker
process runs: plain, picklable arguments in, a JSON-ready record out, errors caught and recorded.
"""

from __future__ import annotations

import math
import pathlib
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rigsim.scenarios.core.pool import keep_heap_memory
from rigsim.scenarios.studies.sweep.settings import EvalSettings

__all__ = ["CaseResult", "evaluate_case", "evaluate_payload", "METRIC_COLUMNS", "EVENT_NAMES"]

#: Hydraulic events counted per case (output samples, summed over the four wheels).
EVENT_NAMES = ("spool_saturation", "cavitation", "overpressure")

#: The figures of one method (:attr:`rigsim.scenarios.studies.scoring.MethodScore.figures`), by name.
_FIGURES = ("dlc_corrected", "dlc_road_band", "dlc_rig_band", "nrmse_rig", "nrmse_corrected",
            "stress_factor_road", "stress_factor_rig", "stress_factor_corrected", "del_road_N", "del_rig_N",
            "del_corrected_N")

#: The scores of one case, in the order of ``results.csv``.
METRIC_COLUMNS = (
    "dlc_road", "dlc_rig", "dlc_corrected", "dlc_road_band", "dlc_rig_band",
    "nrmse_rig", "nrmse_corrected", "stress_factor_road", "stress_factor_rig", "stress_factor_corrected",
    "del_road_N", "del_rig_N", "del_corrected_N", "scored_s",
    *(f"{e}_samples" for e in EVENT_NAMES),
)


@dataclass(frozen=True)
class CaseResult:
    """The scores of one case (means over the four wheels unless stated).

    Attributes
    ----------
    dlc_road : float, 1
        DLC of the road-test tire force, whole record.
    dlc_rig : float, 1
        DLC of the measured rig force (with the measurement noise), whole record.
    dlc_corrected, dlc_road_band, dlc_rig_band : float, 1
        DLC of the corrected rig force, and of the road and measured rig forces through the
        correction's band limit T_F, on the settled samples.
    nrmse_rig, nrmse_corrected : float, 1
        NRMSE of the band-limited rig force and of the corrected force against the
        band-limited road force, on the settled samples.
    stress_factor_road, stress_factor_rig, stress_factor_corrected : float, 1
        Dynamic load stress factor E[(F/F_static)^4] of the road, measured rig and corrected
        forces on the settled samples (pavement damage, fourth-power law; rigsim.correction.metrics.damage).
    del_road_N, del_rig_N, del_corrected_N : float, N
        Damage-equivalent load range (Woehler exponent 5, one cycle per second) of the same.
    scored_s : float, s
        Settled (scored) time.
    events : Mapping[str, int]
        ``<event>_samples`` for each of :data:`EVENT_NAMES`: output samples of the rig run with
        that hydraulic event, summed over the wheels.
    wheels : Mapping[str, Mapping[str, float]]
        Per corner, the DLCs and NRMSEs above (1).
    event_detail : Mapping
        The rig run's events per corner (samples, first time in s).
    method : str
        The scoring method's name (``best``, ``paper`` or ``custom``).
    correction : str
        The method in one line.
    noise_N : float, N
        rms of the measurement noise.

    No wall time: the same case and seed give the same result, byte for byte (the worker's
    wall time travels beside it, :func:`evaluate_payload`).
    """

    dlc_road: float
    dlc_rig: float
    dlc_corrected: float
    dlc_road_band: float
    dlc_rig_band: float
    nrmse_rig: float
    nrmse_corrected: float
    stress_factor_road: float
    stress_factor_rig: float
    stress_factor_corrected: float
    del_road_N: float
    del_rig_N: float
    del_corrected_N: float
    scored_s: float
    events: Mapping[str, int]
    wheels: Mapping[str, Mapping[str, float]]
    event_detail: Mapping
    method: str
    correction: str
    noise_N: float

    @classmethod
    def from_score(cls, pair, events: Mapping) -> CaseResult:
        """The result from a one-method :class:`~rigsim.scenarios.studies.scoring.PairScore` and the
        rig run's ``events``."""
        (ms,) = pair.methods.values()
        per = {"dlc_road": pair.dlc_road, "dlc_rig": pair.dlc_rig, **{k: ms.figures[k] for k in _FIGURES}}
        counts = {f"{e}_samples": int(sum(int(v.get("samples", 0)) for v in (events.get(e) or {}).values()))
                  for e in EVENT_NAMES}
        return cls(**{k: float(np.mean(v)) for k, v in per.items()}, scored_s=float(ms.scored_s), events=counts,
                   wheels={c: {k: float(v[i]) for k, v in per.items()} for i, c in enumerate(pair.corners)},
                   event_detail=dict(events), method=ms.method.name, correction=ms.method.description,
                   noise_N=float(pair.noise_N))

    def to_dict(self) -> dict[str, Any]:
        """The case file's ``result``: :data:`METRIC_COLUMNS` flat, then the details."""
        row: dict[str, Any] = {k: self.events[k] if k in self.events else getattr(self, k) for k in METRIC_COLUMNS}
        row.update(wheels={c: dict(v) for c, v in self.wheels.items()}, events=dict(self.event_detail),
                   method=self.method, correction=self.correction, noise_N=self.noise_N)
        return row


def evaluate_case(scenario, settings: EvalSettings = EvalSettings()) -> CaseResult:
    """Run a scenario on the road and on the rig, correct the rig forces, and score them.

    Parameters
    ----------
    scenario : Scenario
    settings : EvalSettings
        The method (actuator, low-pass, mode), the measurement noise (N rms) and the
        settling tolerance; the defaults are the paper study's ``best`` method and noise.

    Returns
    -------
    CaseResult

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
    from rigsim.scenarios.core.rig import Rig
    from rigsim.scenarios.core.run import run
    from rigsim.scenarios.studies.scoring import score_pair

    road = run(scenario, "road")
    rig = run(scenario, "rig")
    model = Rig(scenario, hydraulic=True)
    identified = None
    if settings.method.actuator == "identified":  # characterize the rig as a lab does before the test
        from rigsim.scenarios.studies.identify.compute import identify_rig

        identified = identify_rig(scenario, rig=model).actuators()
    pair = score_pair(road, rig, model, methods=(settings.method,), identified=identified,
                      noise_N=settings.noise_N, seed=scenario.seed, settling_tolerance=settings.settling_tolerance)
    return CaseResult.from_score(pair, rig.events)


def _one_sentence(exc: BaseException) -> str:
    try:
        text = " ".join(str(exc).split())
    except Exception:  # noqa: BLE001 - an exception whose str() fails still has a name
        text = ""
    text = text or type(exc).__name__
    return text if len(text) <= 400 else text[:397] + "..."


def _plain(value: Any) -> Any:
    """``value`` as plain str, float, int, bool, None, list and dict (what any pickle or JSON reader
    takes back without this package's classes); raises TypeError for anything else."""
    if value is None or isinstance(value, (str, bool)):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain(v) for v in value]
    raise TypeError(f"a case result holds a {type(value).__name__}")


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
        :meth:`EvalSettings.as_dict` of the sweep.

    Returns
    -------
    dict
        ``{"case_id", "status": "ok" | "failed", "error": str | None, "retry": bool,
        "result": dict | None (CaseResult.to_dict()), "wall_time_s": float (s)}``, plain types
        only (str, float, int, bool, None, dict, list), so the record always travels back to the
        client (an exception object, which may refuse to be pickled, never does). ``retry`` is
        True for errors that are not a property of the case (an unexpected exception, also a
        BaseException other than KeyboardInterrupt and SystemExit), so a resumed sweep runs it
        again. ``wall_time_s`` is the worker's wall time; it is kept out of the case file.
    """
    keep_heap_memory()  # a Dask worker's MALLOC_TRIM_THRESHOLD_ would cost ~20 % (rigsim.scenarios.core.pool)
    from rigsim.scenarios.core.config import ScenarioError, parse_scenario
    from rigsim.scenarios.core.watch import SimulationError

    wall0 = time.perf_counter()
    record: dict[str, Any] = {"case_id": case_id, "status": "ok", "error": None, "retry": False, "result": None}
    try:
        scenario = parse_scenario(doc, source=pathlib.Path(source) if source else None)
        record["result"] = evaluate_case(scenario, EvalSettings(**settings)).to_dict()
    except (ScenarioError, SimulationError, ValueError, ArithmeticError) as exc:
        record.update(status="failed", error=_one_sentence(exc))
    except (KeyboardInterrupt, SystemExit):
        raise
    except BaseException as exc:  # noqa: BLE001 - any other error of one case must not stop the sweep
        record.update(status="failed", error=f"{type(exc).__name__}: {_one_sentence(exc)}", retry=True)
    record["wall_time_s"] = round(time.perf_counter() - wall0, 3)
    try:
        record["result"] = _plain(record["result"])
    except TypeError as exc:
        record.update(status="failed", error=_one_sentence(exc), retry=True, result=None)
    if record["result"] is not None and not all(math.isfinite(record["result"][k]) for k in METRIC_COLUMNS):
        record.update(status="failed", error="a score is not finite (NaN or infinity)")
    return record
