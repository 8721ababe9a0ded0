"""Run a scenario in road mode (pans follow the profile) or rig mode (hydraulic actuators).

Layers: the road and drive come from :mod:`scenarios.roads`, the model from :mod:`mjcf`,
the actuators from :mod:`hydraulics`, the statistics from :mod:`correction`. This module
only sequences them and records; it never prints (progress goes through a callback).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np

from mjcf.build import CORNERS, build_model
from mjcf.physics import RigIndex, static_equilibrium
from scenarios import roads
from scenarios.config import Scenario, ScenarioError
from scenarios.results import RunResult

__all__ = ["SimulationError", "Drive", "Watch", "output_schedule", "prepare_drive", "run", "HALF_STROKE_M", "MODES"]

#: DYNTRAC actuator stroke 15.2 cm total (paper): +-76 mm about mid-stroke.
HALF_STROKE_M = 0.076
MODES = ("road", "rig")
_PROFILE_DX_M = 0.02  # m; resolves the ISO band up to 10 cycle/m with 2.5 points per shortest wave
_CHECK_EVERY_S = 0.01  # s; MuJoCo warnings are checked this often and reported with this resolution

ProgressFn = Callable[[float, float], None]
"""progress(simulated_s, total_s), called a few hundred times per run."""


class SimulationError(RuntimeError):
    """A run that went wrong while simulating (MuJoCo warning, divergence); names the time."""


@dataclass(frozen=True)
class Drive:
    """The four pan drive signals at the simulation rate, with the lead-in.

    Attributes
    ----------
    t_s : numpy.ndarray, s
        Times of the steps, from -lead_in to duration (t = 0 starts the analysed record).
    z_m, v_mps : numpy.ndarray, m and m/s
        Elevation and vertical velocity per corner, shape (N, 4), faded in over the first
        half of the lead-in by a cosine taper.
    """

    t_s: np.ndarray
    z_m: np.ndarray
    v_mps: np.ndarray


def _road_profile(scenario: Scenario, length_m: float) -> roads.Profile:
    rc = scenario.road
    if rc.profile_csv is not None:
        base = scenario.source.parent if scenario.source is not None else None
        path = rc.profile_csv if base is None else base / rc.profile_csv
        try:
            return roads.read_profile_csv(path)
        except roads.ProfileError as exc:
            raise ScenarioError(f"road.profile_csv: {exc}") from None
    band = {"waviness": rc.waviness, "tracks": rc.tracks, "n_min_cyc_per_m": rc.n_min_cyc_per_m,
            "n_max_cyc_per_m": rc.n_max_cyc_per_m}
    if rc.roughness is not None:
        spec = roads.RoadSpec.from_class(rc.roughness, **band)
    else:
        spec = roads.RoadSpec(gd_n0_m3=rc.gd_n0_m3, **band)
    rng = np.random.default_rng(scenario.seed)
    return roads.generate_profile(spec, length_m, _PROFILE_DX_M, rng)


def _wheelbase_m(model: mujoco.MjModel) -> float:
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    sid = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"wheel_{c}") for c in ("fl", "rl")]
    return float(data.site_xpos[sid[0], 0] - data.site_xpos[sid[1], 0])


def prepare_drive(scenario: Scenario, model: mujoco.MjModel) -> Drive:
    """Road profile -> high-pass -> four pan drives at the simulation rate, stroke-checked.

    Raises
    ------
    ScenarioError
        If the profile cannot be made or read, or the drive leaves the stroke (naming the
        corner, the time and the margin).
    """
    dt = model.opt.timestep
    fs = 1.0 / dt
    v = scenario.speed_mps
    wheelbase = _wheelbase_m(model)
    total_s = scenario.lead_in_s + scenario.duration_s
    # Extra length: the rear axle starts a wheelbase behind, plus margins for the
    # high-pass's edge effects at both ends.
    margin = max(2.0 * scenario.road.cuton_wavelength_m, 20.0)
    length = wheelbase + roads.START_MARGIN_M + v * total_s + 2 * margin
    try:
        profile = _road_profile(scenario, length)
        profile = roads.envelope(profile, scenario.road.envelope_length_m)
        profile = roads.highpass(profile, scenario.road.cuton_wavelength_m)
        start = float(profile.x_m[0]) + margin + wheelbase + roads.START_MARGIN_M
        wd = roads.sample_wheels(profile, v, wheelbase, fs, total_s, start_m=start)
    except ScenarioError:
        raise
    except roads.ProfileError as exc:
        raise ScenarioError(f"road: {exc}") from None
    except ValueError as exc:
        raise ScenarioError(f"road: {exc}") from None

    t = wd.t_s - scenario.lead_in_s
    # Cosine fade-in over the first half of the lead-in: w(t) rises from 0 to 1.
    t_fade = 0.5 * scenario.lead_in_s
    tau = np.clip((t + scenario.lead_in_s) / t_fade, 0.0, 1.0)
    w = 0.5 - 0.5 * np.cos(np.pi * tau)
    dw = np.where((tau > 0) & (tau < 1), 0.5 * np.pi / t_fade * np.sin(np.pi * tau), 0.0)
    z = wd.z_m * w[:, None]
    vz = wd.v_mps * w[:, None] + wd.z_m * dw[:, None]
    try:
        roads.WheelDrive(t, z, vz).check_stroke(HALF_STROKE_M)
    except ValueError as exc:
        raise ScenarioError(str(exc)) from None
    return Drive(t_s=t, z_m=z, v_mps=vz)


def _check_warnings(data: mujoco.MjData, t0: float, t1: float) -> None:
    for kind, stat in enumerate(data.warning):
        if stat.number:
            text = mujoco.mju_warningText(kind, stat.lastinfo)
            raise SimulationError(
                f"MuJoCo warning between t = {t0:.4f} s and t = {t1:.4f} s of simulated time: {text}"
            )


@contextlib.contextmanager
def mujoco_warnings_captured():
    """Route MuJoCo's warning messages into a list for the duration of a run.

    By default MuJoCo prints each warning and appends it to ``MUJOCO_LOG.TXT`` in the current
    folder; a run must leave no such file behind. The warnings still stop the run: the
    :class:`Watch` reads MuJoCo's warning counters. The previous handler is restored on exit.
    """
    previous = mujoco.get_mju_user_warning()
    messages: list[str] = []
    mujoco.set_mju_user_warning(messages.append)
    try:
        yield messages
    finally:
        mujoco.set_mju_user_warning(previous)


def output_schedule(drive: Drive, dt: float, rate_hz: float) -> tuple[int, int, int]:
    """(k0, decim, n_out): the first step at t >= 0, the steps per output sample, the samples."""
    decim = int(round(1.0 / (rate_hz * dt)))
    k0 = int(np.searchsorted(drive.t_s, -0.5 * dt))
    return k0, decim, (drive.t_s.size - 1 - k0) // decim + 1


class Watch:
    """Checks MuJoCo's warnings every 10 ms of simulated time and reports progress.

    Call :meth:`tick` after every step ``k``; it raises :class:`SimulationError` naming the
    simulated-time window of the first warning, and :meth:`finish` after the last step.
    """

    def __init__(self, drive: Drive, dt: float, progress: ProgressFn | None, extra=None):
        self.t = drive.t_s
        self.dt = dt
        self.progress = progress
        self.extra = extra  # extra(data, t) -> None, raises on a bad state
        self.check = max(1, int(round(_CHECK_EVERY_S / dt)))
        self.report = max(self.check, self.t.size // 200)
        self.total = float(self.t[-1] - self.t[0])

    def tick(self, data: mujoco.MjData, k: int) -> None:
        if k % self.check == self.check - 1:
            t = float(self.t[k])
            _check_warnings(data, t - (self.check - 1) * self.dt, t + self.dt)
            if self.extra is not None:
                self.extra(data, t)
            if self.progress is not None and k % self.report == self.report - 1:
                self.progress(t - float(self.t[0]), self.total)

    def finish(self, data: mujoco.MjData) -> None:
        t = float(self.t[-1])
        _check_warnings(data, t - self.check * self.dt, t + self.dt)


def _truck_mass(model: mujoco.MjModel) -> float:
    names = ("chassis", "payload", "front_axle", "rear_axle")
    return float(sum(model.body_mass[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n)] for n in names))


def _run_road(scenario: Scenario, model, drive: Drive, progress: ProgressFn | None,
              pose_rate_hz: float | None = None) -> dict[str, np.ndarray]:
    """Road test: the pans are moved kinematically, exactly along the profile."""
    data = mujoco.MjData(model)
    idx = RigIndex.of(model)
    static_equilibrium(model, data, pan_z_m=drive.z_m[0])
    qa = idx.pan_qpos
    da = idx.pan_dof
    tires = idx.tire_actuator
    k0, decim, n_out = output_schedule(drive, model.opt.timestep, scenario.output_rate_hz)
    pan = np.empty((n_out, 4))
    force = np.empty((n_out, 4))
    watch = Watch(drive, model.opt.timestep, progress)
    poses = None
    if pose_rate_hz is not None:
        from scenarios.recording import PoseRecorder  # no rerun import: PoseRecorder is numpy only

        poses = PoseRecorder(model, drive.t_s, pose_rate_hz, every=decim)
    z, vz = drive.z_m, drive.v_mps
    j = 0
    for k in range(drive.t_s.size):
        data.qpos[qa] = z[k]
        data.qvel[da] = vz[k]
        record = k >= k0 and (k - k0) % decim == 0
        if record:
            pan[j] = data.qpos[qa]
        mujoco.mj_step(model, data)
        if record:
            force[j] = data.actuator_force[tires]
            j += 1
            if poses is not None:
                poses(data, k)
        watch.tick(data, k)
    watch.finish(data)
    if not np.all(np.isfinite(force)):
        raise SimulationError("the simulation produced non-finite tire forces")
    out = {"pan_m": pan, "tire_force_N": force}
    if poses is not None:
        out["poses"] = poses.track()
    return out


def _run_mode(scenario, mode, model, drive, progress, pan_drive, pose_rate_hz) -> dict:
    """Dispatch to the road or rig loop; returns the recorded signals (and events)."""
    if mode == "road":
        follow = drive
        if pan_drive is not None:
            follow = pan_drive(drive)
            if follow.t_s.shape != drive.t_s.shape or not np.array_equal(follow.t_s, drive.t_s):
                raise ValueError("pan_drive must return a Drive on the same time axis as its input")
            try:
                roads.WheelDrive(follow.t_s, follow.z_m, follow.v_mps).check_stroke(HALF_STROKE_M)
            except ValueError as exc:
                raise ScenarioError(f"pan_drive: {exc}") from None
        return _run_road(scenario, model, follow, progress, pose_rate_hz)
    from scenarios.rig import run_rig  # hydraulics in the loop

    return run_rig(scenario, drive, progress, pose_rate_hz=pose_rate_hz)


def run(
    scenario: Scenario,
    mode: str = "road",
    *,
    progress: ProgressFn | None = None,
    pan_drive: Callable[[Drive], Drive] | None = None,
    pose_rate_hz: float | None = None,
) -> RunResult:
    """Run ``scenario`` in ``mode`` and return its result.

    Parameters
    ----------
    scenario : Scenario
    mode : {"road", "rig"}
        "road": the wheelpans follow the profile exactly (a road test). "rig": the pans are
        driven by the hydraulic actuators with the profile as their drive signal.
    progress : callable, optional
        ``progress(simulated_s, total_s)``.
    pan_drive : callable, optional
        Road mode only: ``pan_drive(drive) -> Drive`` maps the scenario's drive (the road
        profile) to the motion the pans follow instead, on the same time axis (for example
        the profile passed through a linear actuator model T_a). ``profile_m`` still records
        the road profile. The returned drive is stroke-checked like the profile.
    pose_rate_hz : float, Hz, optional
        Also record the bodies' poses at this (video) rate for a rerun recording.

    Raises
    ------
    ScenarioError
        Bad input detected before the run starts.
    SimulationError
        A MuJoCo warning or divergence during the run, with its simulated time.
    """
    if mode not in MODES:
        raise ScenarioError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    wall0 = time.perf_counter()
    model = build_model(scenario.vehicle)
    fs = 1.0 / model.opt.timestep
    decim = fs / scenario.output_rate_hz
    if abs(decim - round(decim)) > 1e-9:
        raise ScenarioError(
            f"output_rate_hz = {scenario.output_rate_hz:g} Hz must divide the simulation rate {fs:g} Hz"
        )
    drive = prepare_drive(scenario, model)
    if pan_drive is not None and mode != "road":
        raise ScenarioError("pan_drive replaces the pan motion of a road-mode run only")
    with mujoco_warnings_captured():
        recorded = _run_mode(scenario, mode, model, drive, progress, pan_drive, pose_rate_hz)
    k0, decim, _ = output_schedule(drive, model.opt.timestep, scenario.output_rate_hz)
    t_out = drive.t_s[k0::decim]
    signals = {"profile_m": drive.z_m[k0::decim].copy()}
    events = recorded.pop("events", {})
    poses = recorded.pop("poses", None)
    signals.update(recorded)
    info = {
        "timestep_s": model.opt.timestep,
        "speed_kmh": scenario.speed_kmh,
        "duration_s": scenario.duration_s,
        "lead_in_s": scenario.lead_in_s,
        "seed": scenario.seed,
        "wall_time_s": round(time.perf_counter() - wall0, 3),
        "simulated_steps": int(drive.t_s.size),
    }
    for key in signals:
        signals[key].setflags(write=False)
    t_out = t_out.copy()
    t_out.setflags(write=False)
    return RunResult(
        scenario_name=scenario.name,
        mode=mode,
        t_s=t_out,
        signals=signals,
        vehicle_mass_kg=_truck_mass(model),
        events=events,
        info=info,
        corners=CORNERS,
        poses=poses,
    )
