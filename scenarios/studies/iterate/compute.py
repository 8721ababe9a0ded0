"""Input correction (drive-file iteration) on the simulated nonlinear rig, set against the output correction.

Sequence of :func:`iterate_scenario` (every rig run is :meth:`rigsim.scenarios.core.rig.Rig.run` of one
``Rig(scenario)``, which accepts any drive; nothing here steps MuJoCo itself):

1. road run and rig run with the original drive (the road profile), both
   :func:`rigsim.scenarios.core.run.run`: the road run is the target of the force iteration and the
   reference of every comparison; the rig run is the iteration's step 0 and the output
   correction's only rig run;
2. identification run: four independent broadband drives
   (:func:`rigsim.scenarios.core.drive.identification_drive`, from t = 0), the first
   :data:`~rigsim.scenarios.core.drive.IDENT_SKIP_S` left out, the H1 FRF matrix drive -> pan
   displacement (``displacement``) or drive -> tire force (``force``),
   :func:`rigsim.correction.input.frf.identify_frf`;
3. the iteration :func:`rigsim.correction.input.iterate.iterate_drive` on the analysed record (t >= 0, the
   output rate; the lead-in's fade-in stays as it is, the update is tapered to zero at both
   ends), starting from the road profile: Moran's target (pan = profile) or the RPC-style target
   (tire force = the road run's tire force); the drive may not leave the actuator's half stroke;
4. the scoring :func:`rigsim.scenarios.studies.scoring.score_pair` of the original rig run (the output
   correction, both methods), and the comparison table.

Compared samples: every row of the comparison (road, rig with the original drive, rig with the
iterated drive, output-corrected) is scored on the same samples: outside the iteration's 0.5 s
tapers at both ends (where the iterated drive fades back to the original one) and where the
``best`` method's correction filters and its band-limit filter have settled on the original rig
run (``score.methods["best"].settled``). DLC
(std / mean, :func:`rigsim.correction.metrics.dlc.dlc`) and NRMSE against the unfiltered road force
(:func:`rigsim.correction.metrics.dlc.nrmse`) are per wheel, then averaged over the four wheels. Rig forces are
the measured ones (:func:`rigsim.scenarios.studies.scoring.measured_force`: plus the load-cell noise of
the scenario's seed; the same noise realisation for the original and the iterated run). If the
output correction cannot be made, the table has no ``output_corrected`` row and the samples
compared are those 1 s inside both ends (the tapers plus 0.5 s).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rigsim.correction.input.convergence import IterationStabilityError
from rigsim.correction.metrics.dlc import dlc, nrmse
from rigsim.correction.input.frf import FRF, identify_frf
from rigsim.correction.input.iterate import IterationResult, iterate_drive
from rigsim.correction.output.lowpass import BAND_HZ
from rigsim.scenarios.core.config import Scenario, ScenarioError
from rigsim.scenarios.core.drive import IDENT_MIN_S, IDENT_SKIP_S, Drive, identification_drive
from rigsim.scenarios.core.results import RunResult
from rigsim.scenarios.core.rig import Rig
from rigsim.scenarios.core.run import run
from rigsim.scenarios.core.watch import SayFn
from rigsim.scenarios.studies.identify.compute import identify_rig
from rigsim.scenarios.studies.scoring import METHODS, NOISE_N, PairScore, measured_force, score_pair

__all__ = ["TARGETS", "IDENT_NPERSEG", "ComparisonRow", "IterateResult",
           "check_options", "splice_drive", "identify_frf_matrix", "iterate_scenario"]

TARGETS = ("displacement", "force")
IDENT_NPERSEG = 4096  # samples: at 1 kHz 0.24 Hz resolution, ~30 averages per 60 s
TAPER_S = 0.5  # s: the iteration's cosine taper of error and update at both ends of the record


@dataclass(frozen=True)
class ComparisonRow:
    """One row of the comparison table.

    Attributes
    ----------
    dlc : float, 1
        DLC of the wheel force, mean of the four wheels, on the compared samples.
    dlc_error : float, 1
        ``dlc / dlc of the road - 1``.
    nrmse_vs_road : float, 1
        NRMSE against the unfiltered road force, mean of the four wheels, on the compared samples.
    rig_runs : int
        Rig runs this result costs (the iteration's: original, identification and the updates).
    wall_s : float or None, s
        Wall time of those rig runs.
    nrmse_vs_road_lowpassed : float or None, 1
        Output correction only: NRMSE against the road force through the same 30 Hz low-pass
        (the scoring's ``nrmse_corrected_best``).
    """

    dlc: float
    dlc_error: float
    nrmse_vs_road: float
    rig_runs: int
    wall_s: float | None = None
    nrmse_vs_road_lowpassed: float | None = None

    def to_dict(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if v is not None}


@dataclass(frozen=True)
class IterateResult:
    """Everything ``rigsim iterate`` reports.

    Attributes
    ----------
    scenario_name : str
    target : {"displacement", "force"}
    iteration : rigsim.correction.input.iterate.IterationResult
        Error per step; ``drive`` (m, (n, 4), at the output rate, t >= 0) is the best drive.
    frf : rigsim.correction.input.frf.FRF
        Identified drive -> pan (m/m) or drive -> tire force (N/m) matrix.
    band_hz : (float, float), Hz
        Band of the drive update.
    road, rig, rig_iterated : rigsim.scenarios.core.results.RunResult
        Road run, rig run with the original drive, rig run with the best iterated drive
        (``profile_m`` of the latter is the iterated drive).
    score : PairScore or None
        Output correction of the original rig run (None if it failed, see ``output_correction_error``).
    compared : numpy.ndarray of bool, (n,)
        The samples every row of ``comparison`` is scored on.
    comparison : Mapping[str, ComparisonRow]
        ``road``, ``rig_original_drive``, ``rig_iterated_drive`` and ``output_corrected``.
    wall_s : Mapping[str, float], s
        Wall time of the road run, the original rig run, the identification run and the iteration.
    noise_N : float, N
        rms of the load-cell noise added to the rig forces.
    output_correction_error : str or None
    """

    scenario_name: str
    target: str
    iteration: IterationResult
    frf: FRF
    band_hz: tuple
    road: RunResult
    rig: RunResult
    rig_iterated: RunResult
    score: PairScore | None
    compared: np.ndarray
    comparison: Mapping
    wall_s: Mapping
    noise_N: float
    output_correction_error: str | None = None

    @property
    def t_s(self) -> np.ndarray:
        """numpy.ndarray, s: the analysed record's time (t >= 0, the output rate)."""
        return self.rig.t_s

    def to_dict(self) -> dict:
        """Everything of ``iteration.json``."""
        f = self.frf
        band = (f.f_hz >= self.band_hz[0]) & (f.f_hz <= self.band_hz[1])
        idx = np.flatnonzero(self.compared)
        t = self.t_s
        return {
            "scenario": self.scenario_name,
            "target": self.target,
            "iteration": self.iteration.summary(),
            "identification": {"nperseg": int((f.f_hz.size - 1) * 2), "averages": f.averages,
                               "skip_s": IDENT_SKIP_S,
                               "coherence_min_in_band": float(np.nanmin(f.coherence[band])),
                               "coherence_mean_in_band": float(np.nanmean(f.coherence[band]))},
            "comparison": {k: row.to_dict() for k, row in self.comparison.items()},
            "compared_samples": {"count": int(idx.size), "seconds": idx.size / self.rig.rate_hz,
                                 "first_s": float(t[idx[0]]), "last_s": float(t[idx[-1]])},
            "scoring": None if self.score is None else self.score.to_dict(),
            "events_original": dict(self.rig.events),
            "events_iterated": dict(self.rig_iterated.events),
            "output_correction_error": self.output_correction_error,
            "wall_time_s": {k: round(v, 2) for k, v in self.wall_s.items()},
            "noise_N": self.noise_N,
            "note": ("DLC and NRMSE: means of the four wheels on the compared samples (where the best output "
                     "correction's filters have settled on the original rig run); rig forces include the "
                     "load-cell noise; nrmse_vs_road: against the unfiltered road force; rig_runs of the "
                     "iteration count the original run, the identification run and the updates; 'scoring': the "
                     "output correction of the original rig run (rigsim.scenarios.studies.scoring)"),
        }


def check_options(target: str, *, gain: float = 0.8, max_iterations: int = 6, tolerance: float = 0.01,
                  band_hz=(0.3, BAND_HZ), coherence_min: float = 0.8, noise_N: float | None = None,
                  run_anyway: bool = False, duration_s: float | None = None) -> None:
    """Refuse bad options before any work (arguments as :func:`iterate_scenario`'s; ``duration_s``, s,
    the scenario's duration).

    Raises
    ------
    ScenarioError
        One sentence naming the option (and its command-line flag) and the allowed range.
    """
    if target not in TARGETS:
        raise ScenarioError(f"target must be one of {', '.join(TARGETS)}, got {target!r}")
    if not (math.isfinite(gain) and 0 < gain <= 4):
        raise ScenarioError(f"gain (--gain) must be in (0, 4], got {gain:g}")
    if gain >= 2 and not run_anyway:
        raise ScenarioError(
            f"gain (--gain) {gain:g} is not stable even with an exact rig model: the iteration's error map "
            f"I - g H H^-1 has spectral radius |1 - g| = {abs(1 - gain):g} >= 1; use 0 < g < 2 "
            "(or pass --run-anyway to watch it diverge)")
    if not (int(max_iterations) == max_iterations and 0 <= max_iterations <= 50):
        raise ScenarioError(f"max_iterations (--max-iterations) must be an integer in [0, 50], got {max_iterations}")
    if not (math.isfinite(tolerance) and 0 < tolerance < 1):
        raise ScenarioError(f"tolerance (--tolerance) must be in (0, 1), got {tolerance:g}")
    lo, hi = band_hz
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi <= 200):
        raise ScenarioError(f"band_hz (--band-hz) must be LO HI with 0 <= LO < HI <= 200 Hz, got {lo:g} {hi:g}")
    if not (math.isfinite(coherence_min) and 0 <= coherence_min < 1):
        raise ScenarioError(f"coherence_min (--coherence-min) must be in [0, 1), got {coherence_min:g}")
    if noise_N is not None and not (math.isfinite(noise_N) and noise_N >= 0):
        raise ScenarioError(f"noise_N (--noise-N) must be >= 0 N, got {noise_N:g}")
    # The comparison scores the samples outside the iteration's tapers (TAPER_S at each end) where the
    # output correction's filters have settled: the paper method's causal start-up transient alone
    # takes ~4.5 s (score_pair refuses fewer than MIN_SCORED_S settled seconds after it), so a record
    # below 10 s fails after all its runs (2 s: no sample left to compare, an empty DLC).
    if duration_s is not None and not (math.isfinite(duration_s) and 10 <= duration_s <= 3600):
        raise ScenarioError(f"duration_s (--duration-s) must be in [10, 3600] s (the output correction's filters "
                            f"take ~5 s to settle and the iteration's tapers 1 s), got {duration_s:g}")


def splice_drive(base: Drive, t_out_s, drive_out_m) -> Drive:
    """``base`` with its analysed part (t >= ``t_out_s[0]``) replaced by ``drive_out_m``.

    Parameters
    ----------
    base : Drive
        The scenario's road drive on the model's time step (lead-in at t < 0).
    t_out_s : array_like, s, (n,)
        Output-rate times of ``drive_out_m`` (from the first step at t >= 0).
    drive_out_m : array_like, m, (n, 4)
        The new drive at those times; linearly interpolated onto the steps (held after the last).

    Returns
    -------
    Drive
        The lead-in (t < ``t_out_s[0]``) unchanged, velocity by centred differences.
    """
    t = base.t_s
    t_out = np.asarray(t_out_s, dtype=float)
    d = np.asarray(drive_out_m, dtype=float)
    k0 = int(np.searchsorted(t, t_out[0] - 0.5 * base.dt_s))
    z = np.array(base.z_m)
    for i in range(z.shape[1]):
        z[k0:, i] = np.interp(t[k0:], t_out, d[:, i])
    return Drive.from_positions(t, z)


def identify_frf_matrix(rig: Rig, target: str, duration_s: float, rate_hz: float) -> FRF:
    """Identification run of ``duration_s`` (s) analysed plus :data:`~rigsim.scenarios.core.drive.IDENT_SKIP_S` and its H1 FRF
    matrix at ``rate_hz`` (Hz): drive -> pan displacement (m/m) or drive -> tire force (N/m)."""
    rec = rig.run(identification_drive(duration_s + IDENT_SKIP_S, rig.dt_s), rate_hz=rate_hz)
    y = rec.pan_m if target == "displacement" else rec.tire_force_N
    skip = int(IDENT_SKIP_S * rate_hz)
    nper = min(IDENT_NPERSEG, (y.shape[0] - skip) // 4)
    return identify_frf(rec.x_ref_m[skip:], y[skip:], rate_hz, nper)


def _row(force_N, road_N, s, road_dlc, rig_runs, wall_s=None, lowpassed=None) -> ComparisonRow:
    d = float(np.mean(dlc(force_N[s])))
    return ComparisonRow(dlc=d, dlc_error=d / road_dlc - 1.0, nrmse_vs_road=float(np.mean(nrmse(force_N[s], road_N[s]))),
                         rig_runs=rig_runs, wall_s=wall_s, nrmse_vs_road_lowpassed=lowpassed)


def iterate_scenario(scenario: Scenario, target: str, *, gain: float = 0.8, max_iterations: int = 6,
                     tolerance: float = 0.01, band_hz=(0.3, BAND_HZ), coherence_min: float = 0.8,
                     noise_N: float | None = None, run_anyway: bool = False,
                     say: SayFn | None = None) -> IterateResult:
    """Road run, rig run, identification and the iteration; the comparison with the output correction.

    Parameters
    ----------
    scenario : Scenario
    target : {"displacement", "force"}
        Pan displacement = road profile (Moran) or tire force = the road run's (RPC-style).
    gain : float, 1
        Relaxation gain g of the update (stable below ~2).
    max_iterations : int
        Most drive updates.
    tolerance : float, 1
        Stop at this mean NRMSE against the target.
    band_hz : (float, float), Hz
        Band of the update.
    coherence_min : float, 1
        No update where the identification's coherence is below this.
    noise_N : float, N, optional
        rms load-cell noise added to the rig forces (default :data:`rigsim.scenarios.studies.scoring.NOISE_N`).
    run_anyway : bool
        Run even if the identified model predicts the gain unstable (divergence still stops it).
    say : callable, optional
        ``say(line)`` for progress lines.

    Raises
    ------
    ScenarioError
        Bad options (before any run), an unstable rig, or a gain the identification says is unstable.
    SimulationError
        A MuJoCo warning during a rig run.
    """
    check_options(target, gain=gain, max_iterations=max_iterations, tolerance=tolerance, band_hz=band_hz,
                  coherence_min=coherence_min, noise_N=noise_N, run_anyway=run_anyway, duration_s=scenario.duration_s)
    say = say or (lambda s: None)
    noise = NOISE_N if noise_N is None else float(noise_N)
    fs = scenario.output_rate_hz
    rig = Rig(scenario)
    walls = {}

    w0 = time.perf_counter()
    road = run(scenario, "road")
    walls["road_s"] = time.perf_counter() - w0
    say(f"road run: {walls['road_s']:.1f} s")
    w0 = time.perf_counter()
    rig0 = run(scenario, "rig")
    walls["rig_original_s"] = time.perf_counter() - w0
    say(f"rig run with the original drive: {walls['rig_original_s']:.1f} s")

    w0 = time.perf_counter()
    frf = identify_frf_matrix(rig, target, max(IDENT_MIN_S, scenario.duration_s), fs)
    walls["identification_s"] = time.perf_counter() - w0
    say(f"identification run: {walls['identification_s']:.1f} s")

    key = "pan_m" if target == "displacement" else "tire_force_N"
    profile = np.asarray(rig0.signals["profile_m"], dtype=float)
    tgt = profile if target == "displacement" else np.asarray(road.signals["tire_force_N"], dtype=float)
    base = rig.road_drive()
    records = [rig0]

    def system(d: np.ndarray) -> np.ndarray:
        rec = rig.run(splice_drive(base, rig0.t_s, d), rate_hz=fs)
        records.append(RunResult(scenario_name=scenario.name, mode="rig", t_s=rig0.t_s,
                                 signals={"profile_m": np.array(d), "pan_m": rec.pan_m,
                                          "tire_force_N": rec.tire_force_N},
                                 vehicle_mass_kg=rig0.vehicle_mass_kg, events=rec.events, info={}))
        return rec.pan_m if target == "displacement" else rec.tire_force_N

    w0 = time.perf_counter()
    try:
        res = iterate_drive(system, tgt, frf, fs, drive0=profile, response0=np.asarray(rig0.signals[key], dtype=float),
                            gain=gain, band_hz=tuple(band_hz), coherence_min=coherence_min,
                            max_iterations=max_iterations, tolerance=tolerance, drive_limit=rig.half_stroke_m,
                            taper_s=TAPER_S, on_unstable="run" if run_anyway else "raise",
                            callback=lambda step: say(f"iteration {step.index}: mean NRMSE {step.nrmse_mean:.4f}"))
    except IterationStabilityError as exc:
        raise ScenarioError(f"{exc} (or pass --run-anyway)") from None
    walls["iteration_s"] = time.perf_counter() - w0
    rig_it = records[res.best_index]

    try:
        identified = identify_rig(scenario, rig=rig).actuators()  # T_a of the output correction
        score = score_pair(road, rig0, rig, methods=METHODS, identified=identified, noise_N=noise, seed=scenario.seed)
        error = None
    except (ValueError, IndexError, np.linalg.LinAlgError) as exc:
        # The per-wheel identification of the output correction can fail on a strongly nonlinear
        # rig; the drive iteration's result stands on its own, so report it without that row.
        score, error = None, f"output correction failed: {type(exc).__name__}: {exc}"
    road_N = np.asarray(road.signals["tire_force_N"], dtype=float)
    # Outside the iteration's tapers at both ends (where the iterated drive fades to the original)
    # and, when the output correction was made, where its filters have settled.
    s = np.zeros(road_N.shape[0], dtype=bool)
    edge = int(round(TAPER_S * fs)) if score is not None else int(round((TAPER_S + 0.5) * fs))
    s[edge:road_N.shape[0] - edge] = True
    if score is not None:
        s &= np.array(score.methods["best"].settled)
    road_dlc = float(np.mean(dlc(road_N[s])))
    rig_wall = walls["rig_original_s"]
    comparison = {
        "road": _row(road_N, road_N, s, road_dlc, 0),
        "rig_original_drive": _row(measured_force(rig0, noise, scenario.seed), road_N, s, road_dlc, 1, rig_wall),
        "rig_iterated_drive": _row(measured_force(rig_it, noise, scenario.seed), road_N, s, road_dlc, 2 + res.runs,
                                   rig_wall + walls["identification_s"] + walls["iteration_s"]),
    }
    if score is not None:
        comparison["output_corrected"] = _row(score.methods["best"].corrected_N, road_N, s, road_dlc, 1, rig_wall,
                                              lowpassed=score.mean["nrmse_corrected_best"])
    return IterateResult(scenario_name=scenario.name, target=target, iteration=res, frf=frf,
                         band_hz=tuple(float(b) for b in band_hz), road=road, rig=rig0, rig_iterated=rig_it,
                         score=score, compared=s, comparison=comparison, wall_s=walls, noise_N=noise,
                         output_correction_error=error)
