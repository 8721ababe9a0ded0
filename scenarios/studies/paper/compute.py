"""The paper's cases: each run on the road and on the rig, the rig force corrected and scored.

The main job of the project. The three shipped scenarios (``scenarios/data/paper/*.toml``) run
in road and rig mode on all cores (:mod:`rigsim.scenarios.core.pool`); each pair is scored by
:func:`rigsim.scenarios.studies.scoring.score_pair` with the paper's method and this project's; the
result (:class:`PaperResult`) holds everything ``paper.json``, the terminal table, the report
and the recording need.
"""

from __future__ import annotations

import concurrent.futures as cf
import copy
import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rigsim.scenarios.core.config import Scenario, load_scenario
from rigsim.scenarios.core.pool import local_executor, worker_count
from rigsim.scenarios.core.results import RunResult
from rigsim.scenarios.core.rig import Rig
from rigsim.scenarios.core.run import run
from rigsim.scenarios.studies.identify.compute import RigIdentification, identify_rig
from rigsim.scenarios.studies.paper.table import PAPER_TABLE2
from rigsim.scenarios.studies.scoring import METHODS, NOISE_N, PairScore, score_pair

__all__ = ["PaperCase", "PaperResult", "run_paper", "ROW_KEYS", "case_scenario", "run_job", "identify_job", "case_job"]

#: paper.json's figures of a case (means over the wheels and per wheel) -> PairScore keys.
ROW_KEYS = {
    "dlc_road": "dlc_road",
    "dlc_rig": "dlc_rig",
    "dlc_corrected_paper": "dlc_corrected_paper",
    "dlc_corrected": "dlc_corrected_best",
    "dlc_road_settled": "dlc_road_settled_best",
    "dlc_road_lowpassed": "dlc_road_band_best",
    "nrmse_corrected": "nrmse_corrected_best",
    "dlc_road_lowpassed_paper": "dlc_road_band_paper",
    "dlc_road_settled_paper": "dlc_road_settled_paper",
    "stress_factor_road": "stress_factor_road_best",
    "stress_factor_rig": "stress_factor_rig_best",
    "stress_factor_corrected": "stress_factor_corrected_best",
    "del_road_N": "del_road_N_best",
    "del_rig_N": "del_rig_N_best",
    "del_corrected_N": "del_corrected_N_best",
    "nrmse_corrected_paper": "nrmse_corrected_paper",
}


@dataclass(frozen=True)
class PaperCase:
    """One case: its road and rig runs and their score.

    Attributes
    ----------
    scenario : Scenario
    road, rig : RunResult
    identification : RigIdentification
        T_a per corner from independent random drives before the test (the "best" method's).
    score : PairScore
        The rig force measured (with noise) and corrected by both methods.
    """

    scenario: Scenario
    road: RunResult
    rig: RunResult
    identification: RigIdentification
    score: PairScore

    @property
    def name(self) -> str:
        return self.scenario.name

    def spatial_correlation(self, dx_m: float = 0.5) -> dict:
        """Spatial repeatability for pavements (Cole & Cebon): the correlation coefficient of the
        road's spatial load profile (force on a ``dx_m`` grid along the road, the speed known) with
        the measured rig's and the corrected one's, per wheel, on the best method's settled samples."""
        from rigsim.correction.metrics.damage import spatial_correlation, spatial_profile

        best = self.score.methods["best"]
        s = best.settled
        fs = 1.0 / float(self.score.t_s[1] - self.score.t_s[0])
        v = self.scenario.speed_mps
        road = spatial_profile(self.score.road_N[s], v, fs, dx_m)[1]
        out = {}
        for name, f in (("rig", self.score.rig_N[s]), ("corrected", best.corrected_N[s])):
            prof = spatial_profile(f, v, fs, dx_m)[1]
            out[name] = {c: round(float(spatial_correlation(road[:, i], prof[:, i])), 4)
                         for i, c in enumerate(self.score.corners)}
        return out

    def row(self) -> dict:
        """paper.json's entry: DLC (1) and NRMSE (1) means over the wheels, per wheel, the
        paper's values, the noise (N) and the seconds each method scored (s)."""
        m, w = self.score.mean, self.score.wheels
        row = {"case": self.name}
        row.update({k: round(m[v], 6) for k, v in ROW_KEYS.items()})
        row["wheels"] = {c: {k: round(wc[v], 6) for k, v in ROW_KEYS.items()} for c, wc in w.items()}
        row["paper"] = dict(PAPER_TABLE2.get(self.name, {}))
        row["noise_N"] = self.score.noise_N
        row["analysed_s"] = {k: round(ms.scored_s, 3) for k, ms in self.score.methods.items()}
        row["spatial_correlation"] = self.spatial_correlation()
        row["identification"] = {c: {"orders": list(f.orders), "bandwidth_hz": round(f.bandwidth_hz, 3),
                                     "held_out_error": round(f.held_out_error, 5)}
                                 for c, f in self.identification.fits.items()}
        return row


@dataclass(frozen=True)
class PaperResult:
    """The Table 2 analogue.

    Attributes
    ----------
    cases : tuple of PaperCase
        In the paper's order (medium 72 km/h, high 48 km/h, high 72 km/h).
    noise_N : float, N
        rms of the measurement noise added to the rig forces.
    models : tuple of rigsim.scenarios.studies.paper.model.ModelScore, optional
        With ``rigsim paper --model``: the third method, one per case in the same order.
    configuration : str
        The cases' configuration (:data:`rigsim.scenarios.core.config.PAPER_CONFIGURATIONS`):
        ``"design"`` or ``"dyntrac"`` (``rigsim paper --rig``).
    """

    cases: tuple
    noise_N: float
    models: tuple | None = None
    configuration: str = "design"

    def rows(self) -> list[dict]:
        """paper.json's entry of each case (:meth:`PaperCase.row`), worked out once per result: the
        tables, the report and paper.json all read them (a copy each, to change at will)."""
        if "_rows" not in self.__dict__:
            object.__setattr__(self, "_rows", [c.row() for c in self.cases])
        return copy.deepcopy(self.__dict__["_rows"])

    def model_table(self) -> str | None:
        """The third method's table (``--model``), or None."""
        if self.models is None:
            return None
        from rigsim.scenarios.studies.paper.model import model_table

        return model_table(self.models)

    def to_dict(self) -> dict:
        """Everything of ``paper.json``."""
        return {
            "configuration": self.configuration,
            "cases": self.rows(),
            "methods": {m.name: m.description for m in METHODS},
            "note": ("means over the four wheels (per wheel under 'wheels'); the unfiltered road and rig DLC "
                     "over the whole record, every corrected figure over the samples where that method's "
                     "filters have settled ('analysed_s' per method); 'paper': Table 2 of the reference paper"),
            **({"model_correction": list(self.models)} if self.models is not None else {}),
        }

    def damage_table(self) -> str:
        """Damage figures: stress factor E[(F/F_static)^4] and the damage-equivalent
        load (m = 5, 1 Hz), road / rig / corrected, means over the wheels, errors against the road."""
        head = (f"{'case':28s} {'stress factor n=4: road':>24s} {'rig':>15s} {'corrected':>15s}   "
                f"{'DEL m=5 (kN): road':>19s} {'rig':>15s} {'corrected':>15s}   {'spatial r: rig':>14s} {'corr.':>6s}")
        lines = [head, "-" * len(head)]
        for r in self.rows():
            sr, dr = r["stress_factor_road"], r["del_road_N"]
            lines.append(
                f"{r['case']:28s} {sr:24.4f} {r['stress_factor_rig']:7.4f} ({100 * (r['stress_factor_rig'] / sr - 1):+5.1f}%) "
                f"{r['stress_factor_corrected']:7.4f} ({100 * (r['stress_factor_corrected'] / sr - 1):+5.1f}%)   "
                f"{dr / 1e3:19.2f} {r['del_rig_N'] / 1e3:7.2f} ({100 * (r['del_rig_N'] / dr - 1):+5.1f}%) "
                f"{r['del_corrected_N'] / 1e3:7.2f} ({100 * (r['del_corrected_N'] / dr - 1):+5.1f}%)   "
                f"{np.mean(list(r['spatial_correlation']['rig'].values())):14.4f} "
                f"{np.mean(list(r['spatial_correlation']['corrected'].values())):6.4f}")
        lines.append("On the samples where the correction has settled; the rig force is the measured one (with noise);")
        lines.append("spatial r: correlation of the load profile along the road with the road's (0.5 m grid), mean of the wheels.")
        return "\n".join(lines)

    def table(self) -> str:
        """Table 2 analogue for the terminal: means over the four wheels, the paper's values in brackets.

        ``ceiling``: the road force through the paper's low-pass T_F alone, the most the paper's
        method can give back (a perfect inverse of T_a under T_F). A corrected value above it (marked
        ``^``) is an over-correction by eq. 4 (its T_a lags more than the rig's); the paper's own
        corrected value is marked likewise where it exceeds even its road, which lies above any
        T_F ceiling."""
        head = (f"{'case':28s} {'road':>15s} {'rig':>15s} {'corr. paper':>17s} {'ceiling':>8s} {'corrected':>10s} "
                f"{'road LP':>8s} {'NRMSE':>6s}")
        lines = [head, "-" * len(head)]
        for r in self.rows():
            ref = r["paper"]
            ceiling = r["dlc_road_lowpassed_paper"]
            over = "^" if r["dlc_corrected_paper"] > ceiling else " "
            ref_over = "^" if ref["corrected"] > ref["road"] else " "
            lines.append(
                f"{r['case']:28s} {r['dlc_road']:7.4f} ({ref['road']:.4f}) {r['dlc_rig']:7.4f} ({ref['rig']:.4f}) "
                f"{r['dlc_corrected_paper']:7.4f}{over}({ref['corrected']:.4f}{ref_over}) {ceiling:8.4f} "
                f"{r['dlc_corrected']:10.4f} {r['dlc_road_lowpassed']:8.4f} {r['nrmse_corrected']:6.3f}")
        lines.append("DLC = std/mean of the wheel force, mean of the four wheels; (paper's Table 2). corr. paper: eq. 4 and")
        lines.append("the paper's 16/24 Hz low-pass T_F; ceiling: the road force through T_F alone, the most that method can")
        lines.append("give back; ^: above it (the paper's value: above its road), eq. 4 over-corrected. corrected: T_a identified")
        lines.append("per corner (rigsim identify), 30 Hz low-pass; road LP: the road force through the same low-pass;")
        lines.append("NRMSE = rms(corrected - road LP) / std(road LP). Configuration: "
                     + ("the simulated DYNTRAC fitted to the paper (--rig dyntrac)." if self.configuration == "dyntrac"
                        else "the project's design rig (--rig design)."))
        return "\n".join(lines)


def case_scenario(path, duration_s: float | None, truck: Mapping | None = None):
    """The scenario at ``path``, with ``duration_s`` (s) in place of its own if given, and ``truck``'s
    :class:`~rigsim.mjcf.variant.TruckVariant` fields over its ``[vehicle]`` (a lab's own truck on the case's
    road and payload; None: the case's truck)."""
    scenario = load_scenario(path)
    if truck:
        scenario = dataclasses.replace(scenario, vehicle=dataclasses.replace(scenario.vehicle, **truck))
    return scenario if duration_s is None else dataclasses.replace(scenario, duration_s=duration_s)


def run_job(path: str, mode: str, duration_s: float | None = None, pose_rate_hz: float | None = None,
            finish_run: Callable | None = None, truck: Mapping | None = None) -> RunResult:
    """Worker: load and run one scenario in one mode (in its own process), then ``finish_run(result)``."""
    scenario = case_scenario(path, duration_s, truck)
    result = run(scenario, mode, pose_rate_hz=pose_rate_hz)
    if finish_run is not None:
        finish_run(result)
    return result


def identify_job(path: str, duration_s: float | None = None, truck: Mapping | None = None) -> RigIdentification:
    """Worker: identify the rig of one scenario (its test drive sets the rms), in its own process."""
    scenario = case_scenario(path, duration_s, truck)
    return identify_rig(scenario)


def case_job(path: str, duration_s: float | None, noise_N: float, road: RunResult, rig: RunResult,
             ident: RigIdentification, finish: Callable | None, truck: Mapping | None = None) -> PairScore:
    """Worker: score one case (and ``finish(case)``, e.g. its files), as soon as its runs are in."""
    scenario = case_scenario(path, duration_s, truck)
    score = score_pair(road, rig, Rig(scenario), methods=METHODS, identified=ident.actuators(),
                       noise_N=noise_N, seed=scenario.seed)
    if finish is not None:
        finish(PaperCase(scenario=scenario, road=road, rig=rig, identification=ident, score=score))
    return score


def _tire_forces(result: RunResult) -> RunResult:
    """What a run's scoring reads of it: the time axis and the tire forces. A case job is sent
    this much (a sixth of a rig run's signals); the whole runs stay in the parent."""
    return dataclasses.replace(result, signals={"tire_force_N": result.signals["tire_force_N"]}, poses=None)


def _scoring_job(path: str, duration_s: float | None, noise_N: float, road: RunResult, rig: RunResult,
                 ident: RigIdentification, finish: Callable | None, case_jobs: Callable | None,
                 truck: Mapping | None = None) -> tuple:
    """Worker: :func:`case_job`; returns the score and the calls ``case_jobs(case)`` asks for."""
    follow_ups = []

    def done(case: PaperCase) -> None:
        if finish is not None:
            finish(case)
        if case_jobs is not None:
            follow_ups.extend(case_jobs(case))

    return case_job(path, duration_s, noise_N, road, rig, ident, done, truck), follow_ups


def run_paper(paths: Sequence, *, workers: int | None = None, duration_s: float | None = None,
              noise_N: float = NOISE_N, pose_rate_hz: float | None = None,
              on_done: Callable[[RunResult], None] | None = None, finish: Callable | None = None,
              finish_run: Callable | None = None, case_jobs: Callable | None = None,
              on_scored: Callable | None = None, configuration: str = "design",
              truck: Mapping | None = None) -> PaperResult:
    """Run the cases of ``paths`` on the road and on the rig, and score each pair.

    The three runs of every case (identification, road, rig) are jobs of one process pool; a
    case's scoring (and ``finish``) is a job of the same pool, started as soon as that case's
    runs are in, so it overlaps the other cases' runs; the jobs ``case_jobs`` asks for follow it.

    Parameters
    ----------
    paths : sequence of path
        Scenario files (validated here before anything runs).
    workers : int, optional
        Worker processes (default: all cores).
    duration_s : float, s, optional
        Overrides every case's duration.
    noise_N : float, N
        rms of the white measurement noise added to the rig force; seeded by the scenario's seed.
    pose_rate_hz : float, Hz, optional
        Also record body poses for a recording.
    on_done : callable, optional
        ``on_done(run_result)`` as each run finishes (progress).
    finish : callable, optional
        ``finish(case)`` with each :class:`PaperCase`, in the worker that scored it (picklable: a
        module-level function or a ``functools.partial`` of one; e.g. writing the case's figures).
        The case's road and rig runs there hold the time axis and the tire forces only.
    case_jobs : callable, optional
        ``case_jobs(case)``, likewise: returns calls ``[(fn, args), ...]`` (picklable) that run as
        further jobs of the pool, each on the next free worker (e.g. drawing the case's figures:
        those of the last case scored then share the cores).
    on_scored : callable, optional
        ``on_scored(result)`` in the parent as soon as every case is scored, with the
        :class:`PaperResult` returned at the end, while the jobs ``case_jobs`` asked for may still
        run (e.g. rendering the report meanwhile).
    finish_run : callable, optional
        ``finish_run(run_result)`` with each road and rig run, in the worker that ran it, as soon as
        it is done (picklable; e.g. writing the run's files while other runs go on).
    configuration : str
        The configuration ``paths`` belong to, recorded in the result
        (:attr:`PaperResult.configuration`).
    truck : Mapping, optional
        :class:`~rigsim.mjcf.variant.TruckVariant` fields over every case's ``[vehicle]`` (a lab's own truck
        on the paper's roads and payloads; ``rigsim paper --truck``).
    """
    scenarios = [case_scenario(p, duration_s, truck) for p in paths]
    calls = []
    for p in paths:
        calls += [(identify_job, (str(p), duration_s, truck))]
        calls += [(run_job, (str(p), mode, duration_s, pose_rate_hz, finish_run, truck)) for mode in ("road", "rig")]
    runs: list = [None] * len(calls)
    scores: list = [None] * len(paths)
    result = None

    def assembled() -> PaperResult:
        cases = [PaperCase(scenario=sc, road=runs[3 * c + 1], rig=runs[3 * c + 2], identification=runs[3 * c],
                           score=scores[c]) for c, sc in enumerate(scenarios)]
        return PaperResult(cases=tuple(cases), noise_N=float(noise_N),
                           configuration=configuration)

    with local_executor(worker_count(workers, len(calls))) as ex:
        jobs = {ex.submit(fn, *args): ("run", i) for i, (fn, args) in enumerate(calls)}
        pending = set(jobs)
        while pending:
            done, pending = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for fut in done:
                kind, i = jobs[fut]
                if kind == "follow-up":
                    fut.result()
                    continue
                if kind == "case":
                    scores[i], follow_ups = fut.result()
                    for fn, args in follow_ups:
                        job = ex.submit(fn, *args)
                        jobs[job] = ("follow-up", i)
                        pending.add(job)
                    if on_scored is not None and all(s is not None for s in scores):
                        result = assembled()
                        on_scored(result)
                    continue
                runs[i] = fut.result()
                if on_done is not None and isinstance(runs[i], RunResult):
                    on_done(runs[i])
                c = i // 3
                if all(r is not None for r in runs[3 * c:3 * c + 3]):
                    ident, road, rig = runs[3 * c:3 * c + 3]
                    case = ex.submit(_scoring_job, str(paths[c]), duration_s, noise_N, _tire_forces(road),
                                     _tire_forces(rig), ident, finish, case_jobs, truck)
                    jobs[case] = ("case", c)
                    pending.add(case)
    return result if result is not None else assembled()
