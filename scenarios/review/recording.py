"""Rerun recordings (.rrd) of scenario runs, for review in the Rerun viewer.

One file holds one recording per scenario (its road-mode and/or rig-mode runs, the corrected
forces, the body poses), all under the application id :data:`APPLICATION_ID`, so the one
blueprint of :mod:`rigsim.scenarios.review.blueprint` lays out every case; the viewer lists the recordings
by scenario name. Each recording holds, on the time line ``time`` (s, 0 at the end of the
lead-in, as ``RunResult.t_s``):

- ``/rig/<corner>/<plot>`` (corners ``fl fr rl rr``), one row per analysis sample (1 kHz) with
  one value per series, named in the entity's static ``SeriesLines``:
  ``displacement`` (m): drive, pan rig (and pan road when it is not the drive itself);
  ``tire_force`` (N): road, rig, corrected; ``pressure`` (Pa): p1, p2; ``spool`` (1, +-1);
- ``/scene/<body>``: the world pose of each MuJoCo body at video rate (``Transform3D``), with
  its visual geoms logged once, static, under ``/scene/<body>/<box|cylinder|capsule>`` in the
  body's frame; ``/scene/world/plane`` the lab floor; ``/scene/road/left|right`` the road
  profile under each track, moving under the truck;
- ``/info/dlc``, ``/info/parameters`` (and ``/info/dlc_table`` when given): static text.

Pose sampling (:class:`PoseRecorder`) is numpy on MuJoCo's arrays and imports no rerun: rerun
is imported inside :func:`write_recording` and :func:`warm_up` only (and by
:mod:`rigsim.scenarios.review.blueprint`, which only they import), so a run without a recording never
loads rerun, and ``rigsim run --rrd`` loads it in its recording process only
(:mod:`rigsim.scenarios.review.recording_process`). Each recording is logged through its own
``rerun.RecordingStream`` (never the global one) with ``send_columns`` of the finished arrays.
"""

from __future__ import annotations

import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import uuid
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rigsim.mjcf.names import CORNERS, pan_body
from rigsim.correction.io.atomic import atomic_path
from rigsim.scenarios.core.poses import DEFAULT_POSE_RATE_HZ, Geoms, PoseTrack, drawn_bodies, model_geoms
from rigsim.scenarios.core.results import RunResult

__all__ = ["APPLICATION_ID", "rest_track", "write_recording", "open_viewer", "warm_up"]

#: Application id of every recording; the viewer keys its blueprint on it.
APPLICATION_ID = "rigsim"


def rest_track(result: RunResult, rate_hz: float = DEFAULT_POSE_RATE_HZ) -> PoseTrack:
    """A stand-in :class:`PoseTrack` when a run recorded no poses.

    The nominal truck (:class:`rigsim.mjcf.variant.TruckVariant` defaults) stands still at its static
    equilibrium; the pans move with the result's ``pan_m``, decimated to ``rate_hz``. The
    chassis and axles do not move: only a :class:`PoseRecorder` in the run can show that.
    """
    import mujoco

    from rigsim.mjcf.build import build_model
    from rigsim.mjcf.variant import TruckVariant
    from rigsim.mjcf.physics import static_equilibrium

    model = build_model(TruckVariant())
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    geoms = model_geoms(model)
    ids, names = drawn_bodies(model, geoms)
    step = max(1, int(round(result.rate_hz / rate_hz)))
    t = np.asarray(result.t_s)[::step]
    pos = np.repeat(data.xpos[ids][None], t.size, axis=0)
    quat = np.repeat(data.xquat[ids][None], t.size, axis=0)
    pan = np.asarray(result.signals["pan_m"])[::step]
    for i, c in enumerate(result.corners):
        if pan_body(c) in names:
            pos[:, names.index(pan_body(c)), 2] += pan[:, i]
    return PoseTrack(t, names, pos, quat, geoms)


@dataclass(frozen=True)
class _Case:
    name: str
    runs: dict  # mode -> RunResult, in the order given
    corrected: np.ndarray | None
    poses: PoseTrack | None
    dlc_table: str | None


def _cases(results, poses, corrected, dlc_table) -> list[_Case]:
    runs: dict[str, dict[str, RunResult]] = {}
    for r in results:
        per = runs.setdefault(r.scenario_name, {})
        if r.mode in per:
            raise ValueError(f"two {r.mode}-mode results of scenario {r.scenario_name!r}")
        per[r.mode] = r
    if not runs:
        raise ValueError("write_recording needs at least one RunResult")
    for label, given in (("poses", poses), ("corrected", corrected)):
        unknown = set(given or {}) - set(runs)
        if unknown:
            raise ValueError(f"{label} names unknown scenarios: {', '.join(sorted(unknown))}")
    cases = []
    for name, per in runs.items():
        t0 = next(iter(per.values())).t_s
        if any(not np.array_equal(r.t_s, t0) for r in per.values()):
            raise ValueError(f"the runs of scenario {name!r} have different time axes")
        n = {t0.size}
        cor = None if corrected is None or name not in corrected else np.asarray(corrected[name], dtype=float)
        if cor is not None and cor.shape != (n.pop(), len(CORNERS)):
            raise ValueError(f"corrected[{name!r}] has shape {cor.shape}; expected the runs' (N, 4)")
        track = (poses or {}).get(name)
        if track is None:  # a runner that records poses may attach them to its results
            track = next((getattr(r, "poses", None) for r in (per.get("rig"), per.get("road"))
                          if r is not None and getattr(r, "poses", None) is not None), None)
        table = dlc_table.get(name) if isinstance(dlc_table, Mapping) else dlc_table
        cases.append(_Case(name, per, cor, track, table))
    return cases


def write_recording(
    path,
    results: Sequence[RunResult],
    *,
    poses: Mapping[str, PoseTrack] | None = None,
    corrected: Mapping[str, np.ndarray] | None = None,
    dlc_table: str | Mapping[str, str] | None = None,
    spawn: bool = False,
    pose_rate_hz: float = DEFAULT_POSE_RATE_HZ,
) -> pathlib.Path:
    """Write the runs as one .rrd file, one recording per scenario, atomically.

    Parameters
    ----------
    path : str or path-like
        The .rrd file. It is written to a temporary file in the same folder and renamed, so an
        error leaves neither a partial file nor a temporary one.
    results : sequence of RunResult
        Grouped by ``scenario_name`` (one road-mode and/or one rig-mode run per scenario).
    poses : mapping of str to PoseTrack, optional
        Per scenario, the body poses (from a :class:`PoseRecorder` in the rig run, preferably).
        Falls back to a ``poses`` attribute of the rig or road result, then to
        :func:`rest_track` (truck at rest, pans moving).
    corrected : mapping of str to numpy.ndarray, N, optional
        Per scenario, the corrected tire forces, (N, 4) on the scenario's time axis.
    dlc_table : str or mapping of str to str, optional
        A DLC table as text (the terminal's), for every recording or per scenario.
    spawn : bool
        Open the written file in the Rerun viewer (a detached process). Otherwise no window
        is ever opened.
    pose_rate_hz : float, Hz
        Frame rate of the stand-in poses of :func:`rest_track`.

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    ValueError
        Results that do not fit together (two runs of one mode and scenario, different time
        axes, ``poses``/``corrected`` for unknown scenarios, a wrong shape), before anything
        is written.
    RuntimeError
        ``rerun rrd merge`` failed (several scenarios only).
    OSError
        The file cannot be written.

    Notes
    -----
    Each scenario is logged through rerun's file sink into a temporary file beside ``path``
    (:func:`rigsim.correction.io.atomic.atomic_path`). One scenario's file is the recording; several are
    merged by the ``rerun rrd merge`` of the pinned wheel's CLI, because an RRD stream ends with
    a footer that indexes its own chunks and streams cannot be concatenated byte-wise.
    """
    path = pathlib.Path(path)
    cases = _cases(results, poses, corrected, dlc_table)
    with atomic_path(path) as tmp:
        if len(cases) == 1:
            _save(cases, pose_rate_hz, [tmp])
        else:
            _merge(cases, pose_rate_hz, tmp)
    if spawn:
        open_viewer(path)
    return path


#: How every complete RRD stream of the pinned rerun ends (its footer's magic, then its version).
RRD_END = b"RRF2FOOT"


def _save(cases: list[_Case], pose_rate_hz: float, files: Sequence[pathlib.Path]) -> None:
    """Each case logged to its own RRD file (rerun's file sink, which encodes on its own thread
    while the arrays are sent: a 120 s rig run's 53 MB take 0.29 s of CPU against 0.42-0.52 s
    through a memory sink whose bytes Python then wrote, measured ad hoc on a shared machine;
    ``benchmarks/recording_e2e.py`` measures the end-to-end cost); the blueprint goes with the
    first. A file that does not end with rerun's footer (:data:`RRD_END`: the sink failed, a full
    disk) raises ``OSError``."""
    import rerun as rr

    from rigsim.scenarios.review import blueprint as bp

    plots = dict.fromkeys(["tire_force", "displacement"])
    for case in cases:
        plots.update(dict.fromkeys(bp.case_series(case.runs, case.corrected)))
    layout = bp.review_blueprint(next(iter(cases[0].runs.values())).corners, tuple(plots))
    for i, (case, file) in enumerate(zip(cases, files, strict=True)):
        rec = rr.RecordingStream(APPLICATION_ID, recording_id=uuid.uuid4())
        rec.save(file)
        if i == 0:  # the blueprint belongs to the application: one for every case
            rec.send_blueprint(layout)
        first = next(iter(case.runs.values()))
        track = case.poses if case.poses is not None else rest_track(case.runs.get("rig", first), pose_rate_hz)
        bp.log_case(rec, case.name, case.runs, track=track, corrected=case.corrected, dlc_table=case.dlc_table)
        rec.flush()
        rec.disconnect()  # writes the footer and closes the file
        del rec
        with open(file, "rb") as fh:
            fh.seek(0, os.SEEK_END)
            fh.seek(max(0, fh.tell() - 4 * len(RRD_END)))
            if RRD_END not in fh.read():
                raise OSError(f"rerun left the recording of {case.name!r} incomplete (no footer); is the disk full?")


def warm_up() -> None:
    """Import rerun and do its first-use work once, on a two-sample recording in a temporary file.

    The first recording a process writes costs about 0.25 s more than the next ones (measured on
    a 30 s rig run: 0.42 s against 0.18 s): on first use rerun's converters have pyarrow import
    pandas (which the recording process refuses) and rerun starts its logging machinery. A process
    that will write a recording later (:mod:`rigsim.scenarios.review.recording_process`) calls this while
    it waits, so that the write itself costs only its data (0.20 s against 0.18 s). Writes a
    temporary file only.
    """
    t = np.array([0.0, 1e-3])
    zero = np.zeros((t.size, len(CORNERS)))
    signals = {k: zero for k in ("profile_m", "pan_m", "p1_Pa", "p2_Pa", "spool")}
    signals["tire_force_N"] = np.full_like(zero, 1.0e4)  # N; a DLC needs a wheel in compression
    result = RunResult(scenario_name="warm-up", mode="rig", t_s=t, signals=signals, vehicle_mass_kg=1.0,
                       info={"speed_kmh": 72.0})
    kinds = ("box", "cylinder", "capsule", "sphere", "plane")
    bodies = tuple(pan_body(c) for c in CORNERS)
    n = len(kinds)
    geoms = Geoms(body=(bodies[0],) * (n - 1) + ("world",), kind=kinds, size_m=np.full((n, 3), 0.1),
                  pos_m=np.zeros((n, 3)), quat_wxyz=np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)), rgba=np.ones((n, 4)))
    pos = np.zeros((t.size, len(bodies), 3))
    pos[:, :, 0] = [1.0, 1.0, -1.0, -1.0]  # front pans ahead of the rear ones (the road's wheelbase)
    quat = np.tile([1.0, 0.0, 0.0, 0.0], (t.size, len(bodies), 1))
    cases = _cases([result], {result.scenario_name: PoseTrack(t, bodies, pos, quat, geoms)}, None, "warm-up")
    with tempfile.TemporaryDirectory(prefix="rigsim-warm-up.") as tmp:
        _save(cases, 50.0, [pathlib.Path(tmp) / "warm-up.rrd"])


def _rerun_cli() -> list[str]:
    return [sys.executable, "-m", "rerun_cli"]


def _merge(cases: list[_Case], pose_rate_hz: float, out: pathlib.Path) -> None:
    """Several cases as one file ``out``: each saved on its own (:func:`_save`), then merged by
    ``rerun rrd merge`` (the CLI of the pinned rerun-sdk wheel): RRD streams cannot be concatenated
    byte-wise, since each ends with a footer indexing its own chunks. The parts live in a
    temporary folder beside ``out``, removed in any case."""
    tmp_dir = pathlib.Path(tempfile.mkdtemp(dir=out.parent, prefix=f"{out.name}.", suffix=".parts"))
    try:
        parts = [tmp_dir / f"case{i}.rrd" for i in range(len(cases))]
        _save(cases, pose_rate_hz, parts)
        merged = tmp_dir / "merged.rrd"
        proc = subprocess.run([*_rerun_cli(), "rrd", "merge", *map(str, parts), "-o", str(merged)],
                              stdin=subprocess.DEVNULL, capture_output=True, text=True)
        if proc.returncode != 0 or not merged.is_file():
            tail = proc.stderr.strip().splitlines()[-1:] or ["no output"]
            raise RuntimeError(f"rerun rrd merge failed (exit {proc.returncode}): {tail[0]}")
        os.replace(merged, out)
    finally:
        shutil.rmtree(tmp_dir, ignore_errors=True)


def open_viewer(path) -> subprocess.Popen:
    """Open ``path`` in the Rerun viewer shipped with rerun-sdk, as a detached process."""
    return subprocess.Popen(
        [*_rerun_cli(), str(path)],
        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
