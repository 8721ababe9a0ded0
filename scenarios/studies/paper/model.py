"""``rigsim paper --model``: the third method, output correction by a rig-calibrated truck model.

For each case, after its road and rig runs and the project's linear correction: the truck model is
calibrated on the rig record's own signals (drive x_ref, LVDT x_a and the measured force F_rig
with its load-cell noise; never the road run, never the plant's parameters) and the record is
corrected by it, F_model(x_ref) + L(W(F_rig - F_model(x_a))) with W the residual's white noise taken
out (:mod:`rigsim.correction.output.denoise`), and its slow part where the case's load cells drift
(:func:`drift_corner`), and L the project's linear correction
by the identified T_a (:func:`rigsim.scenarios.records.model.differential.correct_with_model`). Where the
model cannot be trusted on a wheel that wheel keeps the linear correction, and one sentence says why. Scored like the other
methods against the road force: DLC on the unfiltered force, NRMSE against the band-limited one,
on the samples where both the model's start-up and the linear method's filters have settled.

The calibration needs a process pool of its own, so it runs in the parent after the paper's pool
has finished, case by case, on all of ``workers``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from rigsim.correction.output.denoise import DRIFT_HZ
from rigsim.scenarios.core.lab import LabChain, measure_lvdt
from rigsim.scenarios.records.model.differential import HYBRID_FORMULA, correct_with_model
from rigsim.scenarios.records.model.fallback import HYBRID_LIMIT
from rigsim.scenarios.records.model.result import ModelCorrection
from rigsim.scenarios.studies.correction_score import score_correction
from rigsim.scenarios.studies.scoring import best_linear

__all__ = ["ModelScore", "drift_corner", "model_scores", "model_table"]


def drift_corner(lab: LabChain) -> float | None:
    """The model correction's drift cut for a case measured by ``lab`` (Hz, or None: no cut).

    :data:`~rigsim.correction.output.denoise.DRIFT_HZ` where the lab's load cells drift
    (``lab.drift_noise_N`` > 0), None where they do not, as a lab that knows its cells passes
    ``rigsim correct --model --drift-cut-hz 0``: on a drift-free record the cut only takes out the
    slow part of the model's own error (the leaf springs' friction state, which the model's run
    from rest does not share with the truck), which the residual would have corrected."""
    return DRIFT_HZ if lab.drift_noise_N > 0 else None


@dataclass(frozen=True)
class ModelScore:
    """The model correction of one paper case.

    Attributes
    ----------
    case : str
        Scenario name.
    correction : ModelCorrection
        The calibration, the corrected forces (or the fallback's reason) and timings.
    figures : Mapping or None
        Per wheel (corners fl fr rl rr), each (4,): ``nrmse`` (1), ``dlc`` and ``dlc_road`` (1),
        ``dlc_error`` (1, relative), ``scored_s`` (s); None when the linear correction is used.
    linear_nrmse : numpy.ndarray, (4,)
        The project's linear correction's NRMSE on the same case, for comparison.
    """

    case: str
    correction: ModelCorrection
    figures: Mapping | None
    linear_nrmse: np.ndarray

    @property
    def used(self) -> bool:
        """True when the model correction was used (False: the linear one, :attr:`reason`)."""
        return self.figures is not None

    @property
    def reason(self) -> str:
        return self.correction.reason

    def to_dict(self) -> dict:
        """paper.json's ``model`` entry of a case: means and per-wheel figures, the calibration."""
        out = {"case": self.case, "method": self.correction.method, "reason": self.correction.reason,
               "linear_nrmse": [round(float(v), 6) for v in self.linear_nrmse],
               "correction": self.correction}
        if self.figures is not None:
            out["mean"] = {k: round(float(np.mean(v)), 6) for k, v in self.figures.items() if k != "scored_s"}
            out["wheels"] = {k: [round(float(x), 6) for x in np.atleast_1d(v)] for k, v in self.figures.items()}
        return out


def _score_case(case, workers: int | None) -> ModelScore:
    rig, road, score = case.rig, case.road, case.score
    best = score.methods["best"]
    lvdt = measure_lvdt(rig.signals["pan_m"], rig.rate_hz, case.scenario.lab, case.scenario.seed)
    linear = best_linear(case.identification.actuators(), rig.rate_hz)
    mc = correct_with_model(rig.t_s, rig.signals["profile_m"], lvdt, score.rig_N,
                            base_scenario=case.scenario, workers=workers, linear=linear,
                            drift_hz=drift_corner(case.scenario.lab))
    figures = None
    if not mc.use_linear:
        figures = score_correction(mc.corrected_N, road.signals["tire_force_N"], rig.rate_hz,
                                   rows=mc.settled & best.settled)
    return ModelScore(case=case.name, correction=mc, figures=figures,
                      linear_nrmse=np.asarray(best.figures["nrmse_corrected"], dtype=float))


def model_scores(result, *, workers: int | None = None,
                 progress: Callable[[str], None] | None = None) -> tuple[ModelScore, ...]:
    """The model correction of every case of ``result`` (a PaperResult), in its order.

    Parameters
    ----------
    result : rigsim.scenarios.studies.paper.compute.PaperResult
    workers : int, optional
        Worker processes for each calibration (default: all cores).
    progress : callable, optional
        ``progress(line)`` after each case.
    """
    out = []
    for case in result.cases:
        ms = _score_case(case, workers)
        out.append(ms)
        if progress is not None:
            what = (f"NRMSE {np.mean(ms.figures['nrmse']):.3f}" if ms.used else ms.reason)
            progress(f"model correction {case.name}: {what} ({ms.correction.wall_time_s:.0f} s)")
    return tuple(out)


def model_table(scores) -> str:
    """Table 2's third method for the terminal and report.md: DLC and its error against the road,
    NRMSE beside the linear correction's, the calibration's fit, means over the wheels."""
    head = (f"{'case':28s} {'road':>7s} {'model-corr.':>11s} {'error':>7s} {'NRMSE model':>11s} "
            f"{'linear':>7s} {'fit NRMSE':>9s} {'model err.':>10s} {'cab':>5s} {'time s':>7s}")
    lines = [head, "-" * len(head)]
    for s in scores:
        cal = s.correction.calibration
        fit = f"{np.mean(cal.fit_nrmse):9.3f}" if cal is not None else f"{'-':>9s}"
        err = f"{max(cal.excess_nrmse):10.3f}" if cal is not None else f"{'-':>10s}"
        cab = "-" if cal is None else ("held" if cal.fitted_cab_hz is None else "fit")
        if s.used:
            f = s.figures
            lines.append(f"{s.case:28s} {np.mean(f['dlc_road']):7.4f} {np.mean(f['dlc']):11.4f} "
                         f"{100 * np.mean(f['dlc_error']):+6.1f}% {np.mean(f['nrmse']):11.3f} "
                         f"{np.mean(s.linear_nrmse):7.3f} {fit} {err} {cab:>5s} {s.correction.wall_time_s:7.0f}")
            if s.reason:
                lines.append(f"{'':28s} {s.reason}")
        else:
            lines.append(f"{s.case:28s} linear correction kept: {s.reason}")
    lines.append(f"model-corr.: {HYBRID_FORMULA}, L the linear correction, the truck model calibrated on the rig")
    lines.append("record's own signals; DLC and its error against the road on the same samples; linear: L's NRMSE;")
    lines.append("fit NRMSE: the calibrated model, pans following x_a, against the measured F_rig (mean of the wheels);")
    lines.append("model err.: the worst wheel's dynamic fit NRMSE in the correction's band beyond the load cells' noise")
    lines.append(f"(past {HYBRID_LIMIT:g} the fit is searched again; which wheels keep the model is weighed on the record, "
                 "scenarios/records/model/fallback.py); cab: held rigid or fitted on its mounts.")
    return "\n".join(lines)
