"""Cost of a rerun recording relative to the run it records, and the size of the file.

A 60 s case of the paper (high roughness, 72 km/h, 3640 kg) is run in road mode and in rig
mode with :func:`rigsim.scenarios.core.run.run`; their wall times are the reference. The recording
of the case (both runs, the causally corrected rig forces, the body poses at video rate) is
then written with :func:`rigsim.scenarios.review.recording.write_recording`, repeated, and the fastest
write is kept. The poses come from a road-mode loop that mirrors the runner's with a
:class:`rigsim.scenarios.core.poses.PoseRecorder` hooked in after every ``mj_step``; what the hook
adds to a run is measured separately, as the cost of calling the recorder once per output
sample (inside the runner's existing ``if record:`` block; the runner does nothing else for it).

Printed as one JSON line::

    {"duration_s", "road_wall_s", "rig_wall_s", "write_s", "pose_hook_s", "ratio_case",
     "ratio_road_only", "size_mb", "size_road_only_mb", "target_ratio": 0.05, ...}

``ratio_case`` = (write + pose hook) / (road + rig wall time): ``rigsim paper --rrd``.
``ratio_road_only`` = the same for a road-only recording over the road run alone:
``rigsim run --mode road --rrd``, the least favourable case since a road run is the cheapest.

Usage::

    python benchmarks/recording_cost.py [--duration 60] [--repeats 3] [--keep PATH.rrd]
"""

from __future__ import annotations

import argparse
import json
import pathlib
import tempfile
import time

import mujoco
import numpy as np

from rigsim.correction.output.apply import correct
from rigsim.correction.output.filters import reference_filter
from rigsim.scenarios.core.config import parse_scenario
from rigsim.scenarios.core.poses import DEFAULT_POSE_RATE_HZ, PoseRecorder
from rigsim.scenarios.core.rig import Rig
from rigsim.scenarios.core.run import run
from rigsim.scenarios.core.watch import output_schedule
from rigsim.scenarios.review.recording import write_recording

TARGET_RATIO = 0.05


def road_poses(scenario, rate_hz: float = DEFAULT_POSE_RATE_HZ):
    """Body poses of a road-mode run (the one Rig's road loop with its pose hook)."""
    rig = Rig(scenario, hydraulic=False)
    drive = rig.road_drive()
    rec = rig.run(drive, rate_hz=scenario.output_rate_hz, pose_rate_hz=rate_hz)
    k0, decim, _ = output_schedule(drive, rig.dt_s, scenario.output_rate_hz)
    return rec.poses, rig.model, drive, (k0, decim)


def hook_cost_s(model, drive, data, schedule, rate_hz: float = DEFAULT_POSE_RATE_HZ) -> float:
    """Wall time of the pose hook in one run: one recorder call per output sample, as in
    :func:`road_poses` (the ``record`` flag exists in the runner already); min of 3."""
    k0, decim = schedule
    best = np.inf
    for _ in range(3):
        recorder = PoseRecorder(model, drive.t_s, rate_hz, every=decim)
        t0 = time.perf_counter()
        for k in range(k0, drive.t_s.size, decim):
            recorder(data, k)
        best = min(best, time.perf_counter() - t0)
    return float(best)


def timed_write(path, results, repeats: int, **kw) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        write_recording(path, results, **kw)
        best = min(best, time.perf_counter() - t0)
    return float(best)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=60.0, help="analysed record, s")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--keep", type=pathlib.Path, help="also keep the case's recording here")
    args = ap.parse_args(argv)

    scenario = parse_scenario({
        "name": f"high-72kmh-3640kg-{args.duration:g}s", "speed_kmh": 72.0, "duration_s": args.duration,
        "seed": 1995, "road": {"roughness": "high"}, "vehicle": {"payload_kg": 3640.0},
    })
    road = run(scenario, "road")
    rig = run(scenario, "rig")
    # Wall time of the runs as the runner measures it (model build, drive, simulation).
    road_wall, rig_wall = road.info["wall_time_s"], rig.info["wall_time_s"]
    filt = reference_filter(rig.rate_hz)
    corrected = {scenario.name: correct(rig.signals["tire_force_N"], filt, "causal")}
    track, model, drive, schedule = road_poses(scenario)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    hook_s = hook_cost_s(model, drive, data, schedule)

    with tempfile.TemporaryDirectory() as tmp:
        case_path = pathlib.Path(tmp) / "case.rrd"
        road_path = pathlib.Path(tmp) / "road.rrd"
        write_recording(case_path, [road], poses={scenario.name: track})  # warm-up: imports rerun
        write_s = timed_write(case_path, [road, rig], args.repeats, poses={scenario.name: track},
                              corrected=corrected, dlc_table=rig.table())
        write_road_s = timed_write(road_path, [road], args.repeats, poses={scenario.name: track})
        size_mb = case_path.stat().st_size / 1e6
        size_road_mb = road_path.stat().st_size / 1e6
        if args.keep is not None:
            args.keep.parent.mkdir(parents=True, exist_ok=True)
            case_path.replace(args.keep)

    ratio_case = (write_s + hook_s) / (road_wall + rig_wall)
    ratio_road = (write_road_s + hook_s) / road_wall
    print(json.dumps({
        "duration_s": args.duration,
        "samples": int(road.t_s.size),
        "pose_frames": int(track.t_s.size),
        "road_wall_s": round(road_wall, 3),
        "rig_wall_s": round(rig_wall, 3),
        "write_s": round(write_s, 3),
        "write_road_only_s": round(write_road_s, 3),
        "pose_hook_s": round(hook_s, 4),
        "ratio_case": round(ratio_case, 4),
        "ratio_road_only": round(ratio_road, 4),
        "size_mb": round(size_mb, 2),
        "size_road_only_mb": round(size_road_mb, 2),
        "target_ratio": TARGET_RATIO,
        "meets_target": bool(max(ratio_case, ratio_road) <= TARGET_RATIO),
    }))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
