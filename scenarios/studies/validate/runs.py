"""The runs of ``rigsim validate``: one worker job each, every one through the one Rig.

Each function is a picklable job for :func:`rigsim.scenarios.core.pool.run_jobs` (one run per
process: MuJoCo's actuator callbacks are process-global). None steps MuJoCo itself:

* :func:`identification_run`: the nonlinear rig under four independent random drives
  (:func:`rigsim.scenarios.core.drive.identification_drive`) for route 3, through :meth:`Rig.run`;
* :func:`step_run`: all four pans stepped together (:func:`rigsim.scenarios.core.drive.step_drive`),
  the Figure 7 analogue, through :meth:`Rig.run`;
* :func:`scenario_run`: the Table 1 scenario in road or rig mode (:func:`rigsim.scenarios.core.run.run`);
* :func:`linear_model_run`: a road run whose pans follow the profile through a linear actuator
  model (route 2 by modes, :func:`rigsim.scenarios.core.plant.simulate`, or eq. 4).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy import signal

from rigsim.scenarios.core.drive import IDENT_SKIP_S, Drive, identification_drive, step_drive
from rigsim.scenarios.core.plant import fine_factor
from rigsim.scenarios.core.rig import Rig, RigRecord
from rigsim.scenarios.core.run import run
from rigsim.scenarios.studies.validate.settings import IDENT_RATE_HZ, STEP_AT_S, STEP_RUN_S, validation_scenario

__all__ = ["IdentificationRun", "ScenarioRun", "LINEAR_KINDS", "identification_run", "step_run", "scenario_run",
           "linear_model_run"]

#: Linear actuator models a :func:`linear_model_run` can drive the pans with.
LINEAR_KINDS = ("route2_per_wheel", "route2_mimo", "eq4")


@dataclass(frozen=True)
class IdentificationRun:
    """The nonlinear rig under four independent road-like random drives (route 3's record).

    Attributes
    ----------
    record : rigsim.scenarios.core.rig.RigRecord
        Drive x_ref (m) and pan displacement x_a (m) at :data:`IDENT_RATE_HZ` from t = 0,
        hydraulic states and events.
    drive_rms_m : float, m
        RMS displacement of the drives after :data:`~rigsim.scenarios.core.drive.IDENT_SKIP_S`, mean over the wheels.
    drive_velocity_rms_m_s : float, m/s
        RMS velocity (differences per time step) of the drives, mean over the wheels.
    """

    record: RigRecord
    drive_rms_m: float
    drive_velocity_rms_m_s: float


@dataclass(frozen=True)
class ScenarioRun:
    """What Table 1 needs of one run of the Table 1 scenario.

    Attributes
    ----------
    dlc_mean : float, 1
        DLC (std / mean of the tire force) averaged over the four wheels.
    dlc : Mapping[str, float], 1
        DLC per wheel.
    mean_force_N : Mapping[str, float], N
        Mean tire force per wheel.
    events : Mapping
        Hydraulic events ``{event: {corner: {"samples": int, "first_time_s": float (s)}}}``.
    wall_time_s : float, s
        Wall time of the run.
    result : rigsim.scenarios.core.results.RunResult or None
        The whole run, kept when body poses were recorded (for a rerun recording).
    """

    dlc_mean: float
    dlc: Mapping
    mean_force_N: Mapping
    events: Mapping
    wall_time_s: float
    result: object = None


def _scenario_run(result, keep: bool) -> ScenarioRun:
    s = result.summary()
    return ScenarioRun(dlc_mean=s["dlc_mean"], dlc={c: w["dlc"] for c, w in s["wheels"].items()},
                       mean_force_N={c: w["mean_force_N"] for c, w in s["wheels"].items()},
                       events=s["events"], wall_time_s=s["info"]["wall_time_s"], result=result if keep else None)


def identification_run(path: str, duration_s: float, friction: bool = True) -> IdentificationRun:
    """Route 3's record: the rig under :func:`identification_drive` for ``duration_s`` (s)
    after :data:`~rigsim.scenarios.core.drive.IDENT_SKIP_S`, kept at :data:`IDENT_RATE_HZ`; ``friction``
    False: without the leaf springs' dry friction (a diagnostic)."""
    rig = Rig(validation_scenario(path, friction=friction))
    dt = rig.dt_s
    drive = identification_drive(duration_s + IDENT_SKIP_S, dt)
    record = rig.run(drive, rate_hz=IDENT_RATE_HZ)
    z = drive.z_m
    return IdentificationRun(record=record,
                             drive_rms_m=float(np.mean(z[int(IDENT_SKIP_S / dt):].std(axis=0))),
                             drive_velocity_rms_m_s=float(np.mean((np.diff(z, axis=0) / dt).std(axis=0))))


def step_run(path: str, size_m: float, friction: bool = True) -> RigRecord:
    """All four pans stepped by ``size_m`` (m) at :data:`STEP_AT_S` from static rest, recorded
    at every time step over :data:`STEP_RUN_S`."""
    rig = Rig(validation_scenario(path, friction=friction))
    return rig.run(step_drive(STEP_RUN_S, rig.dt_s, size_m, STEP_AT_S), rate_hz=1.0 / rig.dt_s)


def scenario_run(path: str, duration_s: float | None, mode: str, pose_rate_hz: float | None = None) -> ScenarioRun:
    """The Table 1 scenario (``duration_s``, s) in ``mode`` ("road" or "rig"); the whole
    result is kept when poses are asked for (``pose_rate_hz``, Hz: a recording is wanted)."""
    result = run(validation_scenario(path, duration_s), mode, pose_rate_hz=pose_rate_hz)
    return _scenario_run(result, keep=pose_rate_hz is not None)


def linear_model_run(path: str, duration_s: float | None, kind: str, model) -> ScenarioRun:
    """Road run of the Table 1 scenario with the pans following a linear actuator model of the profile.

    Parameters
    ----------
    path : str
        Scenario file.
    duration_s : float, s, optional
    kind : str
        "route2_per_wheel": each pan through its own path of the linearized plant;
        "route2_mimo": the whole linear plant with all four profiles (cross-coupling included);
        "eq4": eq. 4 per wheel.
    model : PlantLinearization or tuple
        Route 2: the :class:`rigsim.scenarios.core.plant.PlantLinearization`; eq. 4: ``(tfs, dt_s)``,
        per corner ``(num, den)`` in s (rad/s) and the step (s) to discretize them at (the
        plant's; the run's drive is refined onto it and taken back, as route 2's is).
    """
    if kind not in LINEAR_KINDS:
        raise ValueError(f"kind must be one of {', '.join(LINEAR_KINDS)}, got {kind!r}")

    def pan_drive(drive: Drive) -> Drive:
        if kind.startswith("route2"):
            return model.pan_drive(drive, diagonal=(kind == "route2_per_wheel"))
        tfs, dt = model
        r = fine_factor(drive.dt_s, dt)
        fine = drive.refined(r)
        # First-order hold (exact for a piecewise-linear drive; a zero-order hold adds half a
        # step of delay), and the profile's velocity through the same T_a (d/dt commutes).
        z = np.empty_like(fine.z_m)
        v = np.empty_like(fine.z_m)
        for i, (num, den) in enumerate(tfs):
            bd, ad, _ = signal.cont2discrete((num, den), dt, method="foh")
            z[:, i] = signal.lfilter(np.ravel(bd), ad, fine.z_m[:, i])
            v[:, i] = signal.lfilter(np.ravel(bd), ad, fine.v_mps[:, i])
        return Drive(fine.t_s, z, v, fine.corners).every(r)

    return _scenario_run(run(validation_scenario(path, duration_s), "road", pan_drive=pan_drive), keep=False)
