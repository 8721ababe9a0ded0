"""One plant of the mismatch suite corrected as a user would, and judged against its road test.

The rig test is measured through the lab's chain (:func:`rigsim.scenarios.core.lab.measure`) and, with
``align``, its force and LVDT channels aligned as a lab that knows its anti-alias filters and
converter skew aligns them (:func:`rigsim.scenarios.core.lab.aligned`, ``rigsim correct --force-filter
... --lvdt-filter ...``); the rig's T_a is identified on the same rig before the test, its LVDTs
measured (and aligned) the same way (``rigsim identify``); the measured forces are corrected linearly by it (``rigsim correct
--actuators``) and by the truck model calibrated on the record (``rigsim correct --model``: the
model where its fallback keeps it, else the linear correction, with its reason). Beside them: the
model correction forced where the fallback refused it (was the refusal right?) and the plant's
linear floor (the best any per-wheel linear filter of the measured force can do, fitted on the
road force itself). Every figure per wheel, on the samples where every method has settled.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from rigsim.correction.output.apply import band_limit
from rigsim.correction.output.denoise import DRIFT_HZ
from rigsim.correction.output.floor import linear_floor
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE
from rigsim.scenarios.core.lab import LabChain, aligned, measure
from rigsim.scenarios.records.model.cell_mass import without_cell_mass
from rigsim.scenarios.records.model.family import DAMPER_FITTED, ENGINE_FITTED, FRAME_FITTED
from rigsim.scenarios.records.model.differential import (correct_with_model, hybrid_correction, model_force_pair,
                                                   settled_mask)
from rigsim.scenarios.studies.correction_score import band_rows, score_correction
from rigsim.scenarios.studies.scoring import best_linear

__all__ = ["FLOOR_TAPS", "MASS_SCAN_KG", "PlantScore", "score_plant"]

#: The linear floor's FIR, samples ahead and behind at 1 kHz (benchmarks/nrmse_decomposition.py's).
FLOOR_TAPS = (50, 400)
#: kg: the load cells' masses about the fitted one at which the hybrid correction is scored again
#: (:attr:`PlantScore.mass_scan`): the fitted masses of a lab's trucks spread over several kilograms
#: about its cells' own. The hybrid is linear in the mass, so a score's square is quadratic in it and
#: three masses give it at any other (:func:`~rigsim.scenarios.studies.model_suite.lab_mass.hybrid_at_mass`).
MASS_SCAN_KG = (-10.0, 0.0, 10.0)


@dataclass(frozen=True)
class PlantScore:
    """One plant's corrections against its road test, per wheel (``fl fr rl rr``).

    Attributes
    ----------
    name : str
        The case's name.
    plant : Mapping[str, float]
        The plant truck's TruckVariant fields.
    method : {"model", "linear"}
        What ``rigsim correct --model`` delivered.
    reason : str
        Why it fell back ("" when the model was kept).
    nrmse, dlc_error : Mapping[str, numpy.ndarray]
        Per correction (``linear``, ``delivered``, and where a calibration exists ``forced``, the
        differential model correction F_rig + F_model(x_ref) - F_model(x_a) whatever the fallback
        said, and ``hybrid``, :data:`~rigsim.scenarios.records.model.differential.HYBRID_FORMULA` with L the linear correction:
        the model's residual corrected for the actuators too), per wheel:
        NRMSE against the band-limited road force (1) and DLC error against the road's (1).
    floor : numpy.ndarray, (4,)
        The linear floor's NRMSE per wheel (1).
    wall_s, cpu_s : float, s
        Calibration plus correction by the model: wall time and CPU (this process and its workers).
    scored_s : float, s
        Length of the scored samples.
    fit_nrmse : numpy.ndarray or None, (4,)
        The calibrated model's fit against the measured force (1), None without a calibration.
    model_error : numpy.ndarray or None, (4,)
        What the fallback reads (:attr:`~rigsim.scenarios.records.model.result.Calibration.excess_nrmse`:
        the dynamic residual in the correction's band beyond the noise there, 1), None without a
        calibration.
    frame_hz : tuple of float or None, Hz
        The model's frame modes (torsion, bending) where the calibration fitted its frame
        (:mod:`~rigsim.scenarios.records.model.frame_choice`), None where it kept the frame rigid.
    engine : tuple of float or None, (Hz, kg)
        The model's engine mount frequency and mass where the calibration fitted its engine on mounts
        (the same module), None where it kept the engine in the chassis.
    damper : tuple of float or None, (m/s, 1, 1)
        The model's digressive dampers' knee, slope ratio and rebound ratio where the calibration
        fitted them (the same module), None where it did not.
    record_error : numpy.ndarray or None, (4,)
        The model error over the whole run the correction used
        (:attr:`~rigsim.scenarios.records.model.result.ModelCorrection.record_error`, 1), None where the
        model did not run on the record.
    cell_mass_kg : float or None, kg
        The load cells' uncompensated mass the calibration fitted, None without a calibration.
    mass_scan : Mapping[str, numpy.ndarray] or None
        The hybrid correction with the load cells' mass taken as others than the fitted one
        (:data:`MASS_SCAN_KG` about it): ``mass_kg`` (kg, (3,)), ``dlc_error`` and ``nrmse`` (1, (3, 4)),
        for :func:`~rigsim.scenarios.studies.model_suite.lab_mass.hybrid_at_mass`; None without a calibration.
    """

    name: str
    plant: Mapping[str, float]
    method: str
    reason: str
    nrmse: Mapping[str, np.ndarray]
    dlc_error: Mapping[str, np.ndarray]
    floor: np.ndarray
    wall_s: float
    cpu_s: float
    scored_s: float
    fit_nrmse: np.ndarray | None = None
    model_error: np.ndarray | None = None
    timings: Mapping[str, float] = field(default_factory=dict)
    frame_hz: tuple[float, float] | None = None
    engine: tuple[float, float] | None = None
    damper: tuple[float, ...] | None = None
    record_error: np.ndarray | None = None
    cell_mass_kg: float | None = None
    mass_scan: Mapping[str, np.ndarray] | None = None

    def to_dict(self) -> dict:
        return {"name": self.name, "plant": dict(self.plant), "method": self.method, "reason": self.reason,
                "nrmse": {k: v.tolist() for k, v in self.nrmse.items()},
                "dlc_error": {k: v.tolist() for k, v in self.dlc_error.items()}, "floor": self.floor.tolist(),
                "wall_s": self.wall_s, "cpu_s": self.cpu_s, "scored_s": self.scored_s,
                "fit_nrmse": None if self.fit_nrmse is None else self.fit_nrmse.tolist(),
                "model_error": None if self.model_error is None else self.model_error.tolist(),
                "timings": dict(self.timings), "frame_hz": None if self.frame_hz is None else list(self.frame_hz),
                "engine": None if self.engine is None else list(self.engine),
                "damper": None if self.damper is None else list(self.damper),
                "record_error": None if self.record_error is None else self.record_error.tolist(),
                "cell_mass_kg": self.cell_mass_kg,
                "mass_scan": None if self.mass_scan is None else {k: v.tolist() for k, v in self.mass_scan.items()}}

    @classmethod
    def from_dict(cls, d: Mapping) -> "PlantScore":
        """The score :meth:`to_dict` wrote."""
        def arrays(m):
            return {k: np.asarray(v, dtype=float) for k, v in m.items()}

        return cls(name=d["name"], plant=dict(d["plant"]), method=d["method"], reason=d["reason"],
                   nrmse=arrays(d["nrmse"]), dlc_error=arrays(d["dlc_error"]), floor=np.asarray(d["floor"], float),
                   wall_s=d["wall_s"], cpu_s=d["cpu_s"], scored_s=d["scored_s"], fit_nrmse=_array_or_none(d["fit_nrmse"]),
                   model_error=_array_or_none(d["model_error"]), timings=dict(d.get("timings", {})),
                   frame_hz=None if d.get("frame_hz") is None else tuple(d["frame_hz"]),
                   engine=None if d.get("engine") is None else tuple(d["engine"]),
                   damper=None if d.get("damper") is None else tuple(d["damper"]),
                   record_error=_array_or_none(d.get("record_error")), cell_mass_kg=d.get("cell_mass_kg"),
                   mass_scan=None if d.get("mass_scan") is None else arrays(d["mass_scan"]))


def _array_or_none(v) -> np.ndarray | None:
    """``v`` as a float array, None kept."""
    return None if v is None else np.asarray(v, dtype=float)


def _cpu_s() -> float:
    import resource

    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def score_plant(name: str, plant: Mapping[str, float], base_scenario, road, rig, identification, *, lab: LabChain,
                noise_N: float, seed: int, workers: int | None = None, cab: str = "auto",
                align: "bool | LabChain" = False, drift_hz: float | None = DRIFT_HZ) -> PlantScore:
    """Correct one plant's rig test as a user would and judge it (see the module's description).

    Parameters
    ----------
    name : str
    plant : Mapping[str, float]
    base_scenario : Scenario
        The case with the plant (its rig and rate; the model never reads its truck).
    road, rig : rigsim.scenarios.core.results.RunResult
        The road test (the reference) and the rig test.
    identification : rigsim.scenarios.studies.identify.compute.RigIdentification
        T_a per corner identified before the test.
    lab : LabChain
        How the lab measures the rig test.
    noise_N : float, N
        White load-cell noise.
    seed : int
        The noises' seed.
    workers : int, optional
        The model calibration's worker processes.
    cab : {"auto", "held", "fitted"}
        The model's cab mode.
    align : bool or LabChain
        Take the lab's known anti-alias filters' phase and delays out of the force and LVDT
        channels before correcting (:func:`rigsim.scenarios.core.lab.aligned`; the identification given
        should be aligned alike): True, with ``lab``'s own settings; a LabChain, with its settings
        (the lab's nominal ones, where ``lab`` is the chain as it was). The linear floor is fitted on the channels as measured.
    drift_hz : float or None, Hz
        The model correction's drift cut (:func:`~rigsim.scenarios.records.model.differential.hybrid_correction`);
        None: none.
    """
    fs = float(rig.rate_hz)
    raw = measure(rig, lab, noise_N, seed)
    measured = aligned(raw, fs, align if isinstance(align, LabChain) else lab) if align else raw
    road_N = np.asarray(road.signals["tire_force_N"], dtype=float)
    lin = best_linear(identification.actuators(), fs)
    linear_N, linear_settled = lin(measured.force_N)
    wall0, cpu0 = time.perf_counter(), _cpu_s()
    mc = correct_with_model(rig.t_s, rig.signals["profile_m"], measured.pan_m, measured.force_N,
                            base_scenario=base_scenario, workers=workers, cab=cab, linear=lin, drift_hz=drift_hz)
    wall, cpu = time.perf_counter() - wall0, _cpu_s() - cpu0
    started = settled_mask(rig.t_s)
    rows = band_rows(road_N.shape[0], fs) & np.asarray(linear_settled, dtype=bool) & started
    scores = {"linear": score_correction(linear_N, road_N, fs, rows)}
    mass_scan = None
    if mc.calibration is not None:  # the model's two runs: the correction's, else run for the forced forms
        f_ref, f_a = mc.model_N or model_force_pair(mc.calibration.variant(), rig.t_s, rig.signals["profile_m"],
                                                    measured.pan_m, force_N=measured.force_N,
                                                    base_scenario=base_scenario, workers=workers)

        def hybrid_at(mass_kg):
            force = without_cell_mass(measured.force_N, measured.pan_m, fs, mass_kg)
            return force, hybrid_correction(force, f_ref, f_a, lin, fs, started, drift_hz=drift_hz)[0]

        force, hybrid = hybrid_at(mc.calibration.cell_mass_kg)
        scores["forced"] = score_correction(force + f_ref - f_a, road_N, fs, rows)
        scores["hybrid"] = score_correction(hybrid, road_N, fs, rows)
        masses = mc.calibration.cell_mass_kg + np.asarray(MASS_SCAN_KG, dtype=float)
        scanned = [scores["hybrid"] if d == 0.0 else score_correction(hybrid_at(m)[1], road_N, fs, rows)
                   for m, d in zip(masses, MASS_SCAN_KG)]
        mass_scan = {"mass_kg": masses, "dlc_error": np.array([np.asarray(c["dlc_error"]) for c in scanned]),
                     "nrmse": np.array([np.asarray(c["nrmse"]) for c in scanned])}
    scores["delivered"] = (score_correction(mc.corrected_N, road_N, fs, rows) if mc.method == "model"
                           else scores["linear"])
    floor = linear_floor(raw.force_N, band_limit(road_N, fs, BAND_LOWPASS, BAND_MODE), *FLOOR_TAPS, rows=rows).nrmse
    cal = mc.calibration
    fit = None if cal is None else np.asarray(cal.fit_nrmse, dtype=float)
    error = None if cal is None else np.asarray(cal.excess_nrmse, dtype=float)
    fitted = {} if cal is None else dict(zip(cal.names, cal.fitted))
    frame = tuple(float(fitted[k]) for k in FRAME_FITTED) if all(k in fitted for k in FRAME_FITTED) else None
    engine = tuple(float(fitted[k]) for k in ENGINE_FITTED) if all(k in fitted for k in ENGINE_FITTED) else None
    damper = tuple(float(fitted[k]) for k in DAMPER_FITTED) if all(k in fitted for k in DAMPER_FITTED) else None
    return PlantScore(name=name, plant=dict(plant), method=mc.method, reason=mc.reason,
                      nrmse={k: np.asarray(v["nrmse"]) for k, v in scores.items()},
                      dlc_error={k: np.asarray(v["dlc_error"]) for k, v in scores.items()},
                      floor=np.asarray(floor, dtype=float), wall_s=round(wall, 1), cpu_s=round(cpu, 1),
                      scored_s=float(scores["linear"]["scored_s"]), fit_nrmse=fit, model_error=error,
                      timings=dict(mc.timings), frame_hz=frame, engine=engine,
                      damper=damper, record_error=_array_or_none(mc.record_error),
                      cell_mass_kg=None if cal is None else float(cal.cell_mass_kg), mass_scan=mass_scan)
