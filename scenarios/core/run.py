"""Run a scenario in road mode (pans follow the profile) or rig mode (hydraulic actuators).

Builds the :class:`rigsim.scenarios.core.rig.Rig`, makes the road's drive, runs it and returns a
:class:`rigsim.scenarios.core.results.RunResult`. It never prints (progress goes through a callback).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.config import Scenario, ScenarioError
from rigsim.scenarios.core.drive import Drive
from rigsim.scenarios.core.memory import check_memory
from rigsim.scenarios.core.results import RunResult
from rigsim.scenarios.core.rig import Rig
from rigsim.scenarios.core.watch import ProgressFn, output_schedule

__all__ = ["MODES", "run"]

MODES = ("road", "rig")


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
    if pan_drive is not None and mode != "road":
        raise ScenarioError("pan_drive replaces the pan motion of a road-mode run only")
    wall0 = time.perf_counter()
    rig = Rig(scenario, hydraulic=(mode == "rig"))
    steps = (scenario.lead_in_s + scenario.duration_s) / rig.dt_s
    check_memory(steps, scenario.duration_s * scenario.output_rate_hz,
                 f"duration_s = {scenario.duration_s:g} s plus the {scenario.lead_in_s:g} s lead-in at "
                 f"vehicle.timestep_s = {rig.dt_s:g} s is {steps:.3g} steps",
                 "shorten duration_s or raise vehicle.timestep_s")
    if mode == "road":  # a truck with no rest on its tires is refused before the drive is made
        rig.rest_state()  # (the rig mode's Rig does so in its stability check)
    fs = 1.0 / rig.dt_s
    decim = fs / scenario.output_rate_hz
    if abs(decim - round(decim)) > 1e-9:
        raise ScenarioError(
            f"output_rate_hz = {scenario.output_rate_hz:g} Hz must divide the simulation rate {fs:g} Hz"
        )
    source = rig.road_source()  # made chunk by chunk as the run reads it: never held at the step rate
    follow = source
    if pan_drive is not None:
        drive = source.drive()
        follow = pan_drive(drive)
        if follow.t_s.shape != drive.t_s.shape or not np.array_equal(follow.t_s, drive.t_s):
            raise ValueError("pan_drive must return a Drive on the same time axis as its input")
        try:
            follow.check_stroke(rig.half_stroke_m)
        except ValueError as exc:
            raise ScenarioError(f"pan_drive: {exc}") from None
    rec = rig.run(follow, rate_hz=scenario.output_rate_hz, progress=progress, pose_rate_hz=pose_rate_hz)
    if follow is source:
        profile = rec.x_ref_m  # the drive at the output samples is the profile
    else:
        k0, step, _ = output_schedule(drive, rig.dt_s, scenario.output_rate_hz)
        profile = drive.z_m[k0::step].copy()
    signals = {"profile_m": profile, "pan_m": rec.pan_m, "tire_force_N": rec.tire_force_N}
    if rec.hydraulic is not None:
        signals.update(rec.hydraulic)
    info = {
        "timestep_s": rig.dt_s,
        "speed_kmh": scenario.speed_kmh,
        "duration_s": scenario.duration_s,
        "lead_in_s": scenario.lead_in_s,
        "seed": scenario.seed,
        "wall_time_s": round(time.perf_counter() - wall0, 3),
        "simulated_steps": int(source.n_steps),
    }
    for arr in signals.values():
        arr.setflags(write=False)
    t_out = rec.t_s
    t_out.setflags(write=False)
    return RunResult(
        scenario_name=scenario.name,
        mode=mode,
        t_s=t_out,
        signals=signals,
        vehicle_mass_kg=rig.truck_mass_kg,
        events=rec.events,
        info=info,
        corners=CORNERS,
        poses=rec.poses,
    )
