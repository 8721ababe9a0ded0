"""Rerun recordings: written, read back with rerun's chunk reader, and checked against the runs."""

from __future__ import annotations

import dataclasses
import os
import pathlib
import subprocess
import sys

import mujoco
import numpy as np
import pytest

from rigsim.mjcf.build import build_model
from rigsim.mjcf.names import CORNERS
from rigsim.mjcf.physics import RigIndex, static_equilibrium
from rigsim.scenarios.core.config import parse_scenario
from rigsim.scenarios.core.poses import PoseRecorder
from rigsim.scenarios.review.recording import warm_up, write_recording
from rigsim.scenarios.core.run import run

rr = pytest.importorskip("rerun")
pa = pytest.importorskip("pyarrow")

ROOT = pathlib.Path(__file__).resolve().parents[3]
SCENARIO = {"name": "t", "speed_kmh": 72.0, "duration_s": 2.0, "lead_in_s": 1.0, "seed": 1,
            "road": {"roughness": "C"}}
TRUCK = ("chassis", "payload", "front_axle", "rear_axle")
PANS = tuple(f"pan_{c}" for c in CORNERS)


def read_rrd(path) -> dict[str, dict[str, dict]]:
    """{recording name: {entity path: {"static": {component: batch}, component: rows, "time": ns}}}:
    a static component is its one batch (a list of instances), a time-varying one a list of
    batches per row, sorted by time."""
    reader = rr.chunk.RrdReader(path)
    out = {}
    for entry in reader.recordings():
        ents: dict[str, dict] = {}
        for chunk in reader.stream(store=entry):
            rb = chunk.to_record_batch()
            e = ents.setdefault(chunk.entity_path, {"static": {}})
            for field, col in zip(rb.schema, rb.columns):
                meta = field.metadata or {}
                if meta.get(b"rerun:kind") == b"data":
                    comp = meta[b"rerun:component"].decode()
                    if chunk.is_static:  # one row: keep its batch
                        e["static"][comp] = col.to_pylist()[-1]
                    else:
                        e.setdefault(comp, []).extend(col.to_pylist())
                elif meta.get(b"rerun:kind") == b"index":
                    e.setdefault(field.name, []).extend(col.cast(pa.int64()).to_pylist())
        for e in ents.values():
            if "time" in e:
                order = np.argsort(e["time"], kind="stable")
                for k in [k for k in e if k != "static"]:
                    e[k] = [e[k][i] for i in order]
        name = ents["/__properties"]["static"]["RecordingInfo:name"][0]
        out[name] = ents
    return out


def sine_poses(duration_s: float = 1.0, every: int = 1) -> tuple:
    """Step the truck with its pans moved along sines (as a road run does) and record poses."""
    model = build_model()
    data = mujoco.MjData(model)
    idx = RigIndex.of(model)
    static_equilibrium(model, data)
    dt = model.opt.timestep
    t = np.arange(-100, int(round(duration_s / dt)) + 1) * dt
    phase = np.array([0.0, 0.5, 1.0, 1.5])
    z = 0.02 * np.sin(2 * np.pi * 2.0 * t[:, None] + phase)
    recorder = PoseRecorder(model, t, rate_hz=50.0, every=every)
    truth = {}
    for k in range(t.size):
        data.qpos[idx.pan_qpos] = z[k]
        mujoco.mj_step(model, data)
        if k % every == 0:
            recorder(data, k)
        truth[k] = (data.xpos.copy(), data.xquat.copy())
    return recorder, model, t, truth


@pytest.fixture(scope="module")
def runs():
    s = parse_scenario(SCENARIO)
    return run(s, "road"), run(s, "rig")


@pytest.fixture(scope="module")
def written(runs, tmp_path_factory):
    road, rig = runs
    recorder, _, _, _ = sine_poses(2.0)
    corrected = rig.signals["tire_force_N"] * 0.97 + 100.0
    path = tmp_path_factory.mktemp("rrd") / "case.rrd"
    write_recording(path, [road, rig], poses={"t": recorder.track()}, corrected={"t": corrected},
                    dlc_table=rig.table())
    return path, read_rrd(path), recorder.track(), corrected


def test_entity_tree_and_blueprint(written):
    path, recs, track, _ = written
    assert list(recs) == ["t"]
    ents = recs["t"]
    for c in CORNERS:
        for plot in ("displacement", "tire_force", "pressure", "spool"):
            assert f"/rig/{c}/{plot}" in ents, f"/rig/{c}/{plot}"
    for body in TRUCK + PANS:
        assert "Transform3D:translation" in ents[f"/scene/{body}"], body
    for doc in ("/info/dlc", "/info/parameters", "/info/dlc_table"):
        assert len(ents[doc]["static"]["TextDocument:text"][0]) > 20
    assert "Boxes3D:half_sizes" in ents["/scene/chassis/box"]["static"]
    assert "Cylinders3D:radii" in ents["/scene/rear_axle/cylinder"]["static"]
    assert "LineStrips3D:strips" in ents["/scene/road/left"]["static"]
    reader = rr.chunk.RrdReader(path)
    assert [b.application_id for b in reader.blueprints()] == ["rigsim"]


def test_series_match_the_runs(written, runs):
    road, rig = runs
    _, recs, _, corrected = written
    ents = recs["t"]
    n = road.t_s.size
    for i, c in enumerate(CORNERS):
        force = ents[f"/rig/{c}/tire_force"]
        assert len(force["time"]) == n
        np.testing.assert_array_equal(force["time"], np.round(road.t_s * 1e9).astype(np.int64))
        values = np.array(force["Scalars:scalars"])
        assert values.shape == (n, 3)
        np.testing.assert_array_equal(values[:, 0], road.signals["tire_force_N"][:, i])
        np.testing.assert_array_equal(values[:, 1], rig.signals["tire_force_N"][:, i])
        np.testing.assert_array_equal(values[:, 2], corrected[:, i])
        assert force["static"]["SeriesLines:names"] == ["road (N)", "rig (N)", "corrected (N)"]
        disp = np.array(ents[f"/rig/{c}/displacement"]["Scalars:scalars"])
        # the road run's pan equals its drive and is left out: drive, then the rig's pan
        np.testing.assert_array_equal(disp[:, 0], road.signals["profile_m"][:, i])
        np.testing.assert_array_equal(disp[:, 1], rig.signals["pan_m"][:, i])
        pressure = np.array(ents[f"/rig/{c}/pressure"]["Scalars:scalars"])
        np.testing.assert_array_equal(pressure, np.column_stack([rig.signals["p1_Pa"][:, i], rig.signals["p2_Pa"][:, i]]))
        spool = np.array(ents[f"/rig/{c}/spool"]["Scalars:scalars"])[:, 0]
        np.testing.assert_array_equal(spool, rig.signals["spool"][:, i])


def test_poses_at_video_rate_in_xyzw(written):
    _, recs, track, _ = written
    ents = recs["t"]
    assert track.t_s.size == 101  # 2 s at 50 Hz, both ends included
    for b, body in enumerate(track.bodies):
        e = ents[f"/scene/{body}"]
        assert len(e["time"]) == track.t_s.size
        np.testing.assert_allclose(np.array(e["Transform3D:translation"]).reshape(-1, 3),
                                   track.position_m[:, b], atol=1e-6)
        q = np.array(e["Transform3D:quaternion"]).reshape(-1, 4)
        np.testing.assert_allclose(q, track.quat_wxyz[:, b][:, [1, 2, 3, 0]], atol=1e-6)
    # the truck does pitch and roll under the sine drive: a wxyz/xyzw swap could not pass
    chassis = track.quat_wxyz[:, track.bodies.index("chassis")]
    assert np.ptp(chassis[:, 1]) > 1e-5 and np.ptp(chassis[:, 2]) > 1e-5


def _rotate_xyzw(q, v):
    x, y, z, w = q
    u = np.array([x, y, z])
    t = 2 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def test_geoms_in_body_frames(written):
    ents = written[1]["t"]
    # wheels: MuJoCo cylinders turned onto the y axis (axle direction)
    wheels = ents["/scene/front_axle/cylinder"]["static"]
    for q, centre in zip(wheels["Cylinders3D:quaternions"], wheels["Cylinders3D:centers"]):
        axis = _rotate_xyzw(np.array(q), np.array([0.0, 0.0, 1.0]))
        np.testing.assert_allclose(np.abs(axis), [0, 1, 0], atol=1e-6)
        assert abs(abs(centre[1]) - 1.025) < 1e-6
    np.testing.assert_allclose(wheels["Cylinders3D:radii"], 0.527, rtol=1e-6)
    # the front beam (fromto 0 -0.9 0 -> 0 0.9 0): rerun's capsule starts at one end
    cap = ents["/scene/front_axle/capsule"]["static"]
    start = np.array(cap["Capsules3D:translations"][0])
    end = start + _rotate_xyzw(np.array(cap["Capsules3D:quaternions"][0]),
                               np.array([0.0, 0.0, cap["Capsules3D:lengths"][0]]))
    np.testing.assert_allclose(sorted([start[1], end[1]]), [-0.9, 0.9], atol=1e-6)
    np.testing.assert_allclose(start[[0, 2]], 0, atol=1e-6)


def test_pose_recorder_called_at_the_output_rate_matches_every_step():
    every_step, model, t, truth = sine_poses(0.5, every=1)
    at_output, _, _, _ = sine_poses(0.5, every=10)
    a, b = every_step.track(), at_output.track()
    np.testing.assert_array_equal(a.t_s, b.t_s)
    np.testing.assert_array_equal(a.position_m, b.position_m)
    np.testing.assert_allclose(np.diff(a.t_s), 0.02, atol=1e-12)
    assert a.t_s[0] == pytest.approx(0.0, abs=1e-12)
    k = int(np.argmin(np.abs(t - 0.3)))
    j = int(np.argmin(np.abs(a.t_s - 0.3)))
    xpos, xquat = truth[k]
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in a.bodies]
    np.testing.assert_array_equal(a.position_m[j], xpos[ids])
    np.testing.assert_array_equal(a.quat_wxyz[j], xquat[ids])


def test_is_frame_picks_exactly_the_frame_steps():
    """is_frame, arithmetic on the schedule, against the recorder's own list of frame steps."""
    rec, _, t, _ = sine_poses(0.5, every=10)
    every = np.arange(-5, t.size + 5)
    np.testing.assert_array_equal(every[rec.is_frame(every)], rec.steps)


def test_without_poses_the_pans_still_move(runs, tmp_path):
    road, _ = runs
    path = tmp_path / "road.rrd"
    write_recording(path, [road])
    ents = read_rrd(path)["t"]
    pan = np.array(ents["/scene/pan_fl"]["Transform3D:translation"]).reshape(-1, 3)
    step = 20  # 1 kHz -> 50 Hz
    np.testing.assert_allclose(pan[:, 2] - pan[0, 2], road.signals["pan_m"][::step, 0] - road.signals["pan_m"][0, 0],
                               atol=1e-6)
    chassis = np.array(ents["/scene/chassis"]["Transform3D:translation"]).reshape(-1, 3)
    assert np.ptp(chassis[:, 2]) == 0.0  # a stand-in at rest
    assert np.array(ents["/rig/fl/tire_force"]["Scalars:scalars"]).shape == (road.t_s.size, 1)


def test_one_file_one_recording_per_case(runs, tmp_path):
    road, rig = runs
    other = dataclasses.replace(road, scenario_name="u")
    path = tmp_path / "paper.rrd"
    write_recording(path, [road, rig, other])
    recs = read_rrd(path)
    assert sorted(recs) == ["t", "u"]
    assert np.array(recs["u"]["/rig/rr/tire_force"]["Scalars:scalars"]).shape == (road.t_s.size, 1)
    assert np.array(recs["t"]["/rig/rr/tire_force"]["Scalars:scalars"]).shape == (road.t_s.size, 2)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["paper.rrd"]


@pytest.mark.parametrize("n_cases", [1, 2])
def test_errors_leave_the_old_file_and_nothing_else(runs, tmp_path, n_cases):
    road, rig = runs
    path = tmp_path / "out.rrd"
    path.write_bytes(b"old")
    results = [road, rig] if n_cases == 1 else [road, rig, dataclasses.replace(road, scenario_name="u")]
    with pytest.raises(ValueError, match="corrected"):
        write_recording(path, results, corrected={"t": np.zeros((5, 4))})
    with pytest.raises(ValueError, match="unknown scenarios"):
        write_recording(path, results, corrected={"nope": np.zeros((5, 4))})
    bad = dataclasses.replace(rig, signals={**rig.signals, "tire_force_N": rig.signals["tire_force_N"][:, :2]})
    with pytest.raises(Exception):
        write_recording(path, [road, bad] + results[2:])
    assert path.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.rrd"]


@pytest.mark.parametrize("n_cases", [1, 2])
def test_an_incomplete_recording_is_an_error_that_leaves_the_old_file(runs, tmp_path, monkeypatch, n_cases):
    """rerun's file sink writes on its own thread and reports a failed write (a full disk) nowhere we
    can catch: a file cut after the sink closed it, as a full disk would leave it, lacks the footer,
    and write_recording refuses to put it in place."""
    import rerun as rr

    saved, save, disconnect = [], rr.RecordingStream.save, rr.RecordingStream.disconnect

    def remember(self, file, *args, **kwargs):
        saved.append(file)
        return save(self, file, *args, **kwargs)

    def cut(self):
        disconnect(self)
        os.truncate(saved[-1], os.path.getsize(saved[-1]) // 2)

    monkeypatch.setattr(rr.RecordingStream, "save", remember)
    monkeypatch.setattr(rr.RecordingStream, "disconnect", cut)
    road, rig = runs
    path = tmp_path / "out.rrd"
    path.write_bytes(b"old")
    results = [road, rig] if n_cases == 1 else [road, rig, dataclasses.replace(road, scenario_name="u")]
    with pytest.raises(OSError, match="incomplete"):
        write_recording(path, results)
    assert path.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.rrd"]


def test_a_run_without_recording_imports_no_rerun(tmp_path):
    toml = tmp_path / "s.toml"
    toml.write_text('name = "t"\nspeed_kmh = 72.0\nduration_s = 0.5\nlead_in_s = 0.5\nseed = 1\n'
                    '[road]\nroughness = "C"\n')
    code = (
        "import sys\n"
        "from rigsim.scenarios.cli.main import main\n"
        "import rigsim.scenarios.review.recording\n"
        f"rc = main(['run', {str(toml)!r}, '--mode', 'road', '--out', {str(tmp_path / 'out')!r}, '--quiet'])\n"
        "assert rc == 0, rc\n"
        "loaded = sorted(m for m in sys.modules if m.split('.')[0] in ('rerun', 'rerun_bindings'))\n"
        "assert not loaded, loaded\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (tmp_path / "out" / "result.json").is_file()


def test_viewer_opened_only_when_asked(runs, tmp_path, monkeypatch):
    import rigsim.scenarios.review.recording as recording

    opened = []
    monkeypatch.setattr(recording, "open_viewer", lambda path: opened.append(pathlib.Path(path)))
    road, _ = runs
    write_recording(tmp_path / "a.rrd", [road])
    assert opened == []
    write_recording(tmp_path / "b.rrd", [road], spawn=True)
    assert opened == [tmp_path / "b.rrd"]


def test_warm_up_writes_nothing(tmp_path, monkeypatch):
    """Nothing in the working folder, nothing left in the temporary one (where its file goes)."""
    import tempfile

    monkeypatch.chdir(tmp_path)
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    warm_up()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tmp"] and list((tmp_path / "tmp").iterdir()) == []
