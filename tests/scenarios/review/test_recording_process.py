"""The recording process of ``rigsim run --rrd`` (:mod:`rigsim.scenarios.review.recording_process`): it
writes what one process writes, reports its errors as one sentence, leaves nothing when it fails,
keeps rerun out of the command's own process, and does not outlive the command."""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

import numpy as np
import shutil

import pytest

from rigsim.scenarios.core.config import parse_scenario
from rigsim.scenarios.core.run import run
from rigsim.scenarios.review.recording import write_recording
from rigsim.scenarios.review.recording_process import RecordingError, RecordingProcess
from tests.scenarios.review.test_recording import ROOT, SCENARIO, read_rrd, sine_poses

rr = pytest.importorskip("rerun")

TOML = 'name = "t"\nspeed_kmh = 72.0\nduration_s = 2.0\nlead_in_s = 1.0\nseed = 1\n[road]\nroughness = "C"\n'
ENV = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
_UUID = re.compile(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")


def _blueprint(path) -> list:
    """The blueprint's chunks with rerun's row ids and log times left out and the random ids of
    its views and containers replaced by one placeholder: what two writes of one layout share."""
    reader = rr.chunk.RrdReader(path)
    out = []
    for entry in reader.blueprints():
        for chunk in reader.stream(store=entry):
            rb = chunk.to_record_batch()
            cols = {f.name: c.to_pylist() for f, c in zip(rb.schema, rb.columns)
                    if f.name not in ("rerun.controls.RowId", "log_time", "log_tick")}
            if "ViewportBlueprint:root_container" in cols:  # the root container's id, as 16 bytes
                cols["ViewportBlueprint:root_container"] = "<id>"
            out.append(_UUID.sub("<id>", repr((entry.application_id, chunk.entity_path, chunk.is_static, cols))))
    return sorted(out)


def _without_start_time(recs: dict) -> dict:
    for ents in recs.values():
        ents["/__properties"]["static"].pop("RecordingInfo:start_time")
    return recs


def _leftovers(folder: pathlib.Path) -> list[str]:
    return sorted(p.name for p in folder.rglob("*") if p.name.endswith((".partial", ".old", ".tmp")))


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie, ended but not yet reaped by its new parent, does not)."""
    try:
        stat = pathlib.Path(f"/proc/{pid}/stat").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return False
    return stat.rpartition(")")[2].split()[0] not in ("Z", "X")


def _recording_child(parent: subprocess.Popen, timeout_s: float = 120.0) -> int:
    """The pid of ``parent``'s recording process, once it has started."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        assert parent.poll() is None, parent.communicate()
        for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
            try:
                fields = stat.read_text().rpartition(")")[2].split()
                cmd = (stat.parent / "cmdline").read_bytes()
            except OSError:
                continue
            if int(fields[1]) == parent.pid and b"recording_process" in cmd:
                return int(stat.parent.name)
        time.sleep(0.02)
    raise AssertionError("no recording process started")


def _wait_gone(pid: int, timeout_s: float = 60.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    return not _alive(pid)


@pytest.fixture(scope="module")
def runs():
    s = parse_scenario(SCENARIO)
    return run(s, "road"), run(s, "rig")


@pytest.fixture(scope="module")
def rig_with_poses(runs):
    recorder, _, _, _ = sine_poses(2.0)
    return dataclasses.replace(runs[1], poses=recorder.track())


def test_the_recording_process_writes_what_one_process_writes(rig_with_poses, tmp_path):
    """The child (its own interpreter, pandas refused) and write_recording in this process give
    the same recording: every entity's series, scene and text, and the same blueprint; only the
    recording's start time and rerun's random ids differ."""
    rig = rig_with_poses
    with RecordingProcess() as rec:
        assert rec.pid is not None and _alive(rec.pid)
        rec.submit(tmp_path / "child.rrd", [rig], dlc_table=rig.table())
        assert rec.commit() == tmp_path / "child.rrd"
    write_recording(tmp_path / "one.rrd", [rig], dlc_table=rig.table())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["child.rrd", "one.rrd"]  # no temporary left
    child, one = read_rrd(tmp_path / "child.rrd"), read_rrd(tmp_path / "one.rrd")
    assert "/scene/chassis" in child["t"] and "/rig/fl/pressure" in child["t"]
    assert _without_start_time(child) == _without_start_time(one)
    assert _blueprint(tmp_path / "child.rrd") == _blueprint(tmp_path / "one.rrd")
    np.testing.assert_array_equal(np.array(child["t"]["/rig/rl/tire_force"]["Scalars:scalars"])[:, 0],
                                  rig.signals["tire_force_N"][:, 2])


def test_the_recording_process_reports_bad_input_as_write_recording_does(runs, tmp_path):
    road, rig = runs
    late = dataclasses.replace(rig, t_s=rig.t_s + 1e-3)
    with pytest.raises(ValueError) as one:
        write_recording(tmp_path / "one.rrd", [road, late])
    with RecordingProcess() as rec:
        rec.submit(tmp_path / "child.rrd", [road, late])
        with pytest.raises(ValueError) as child:
            rec.commit()
    assert str(child.value) == str(one.value) and "different time axes" in str(child.value)
    assert list(tmp_path.iterdir()) == []


def test_a_recording_process_that_died_is_reported(runs, tmp_path):
    with RecordingProcess() as rec:
        os.kill(rec.pid, signal.SIGKILL)
        rec.submit(tmp_path / "x.rrd", [runs[0]])
        with pytest.raises(RecordingError, match=f"was killed by signal {int(signal.SIGKILL)} without writing"):
            rec.commit()
    assert list(tmp_path.iterdir()) == []


def test_a_recording_run_imports_no_rerun_in_its_own_process(tmp_path):
    """``rigsim run --rrd``: rerun is loaded by the recording process only; the .rrd lands in
    --out with the rest and holds the run's samples and the table the command printed."""
    (tmp_path / "s.toml").write_text(TOML)
    out = tmp_path / "out"
    code = (
        "import sys\n"
        "from rigsim.scenarios.cli.main import main\n"
        "rc = main(['run', 's.toml', '--mode', 'rig', '--out', 'out', '--rrd', 'out/run.rrd', '--quiet'])\n"
        "assert rc == 0, rc\n"
        "loaded = sorted(m for m in sys.modules if m.split('.')[0] in ('rerun', 'rerun_bindings', 'pandas'))\n"
        "assert not loaded, loaded\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=ENV, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert {"result.json", "run.rrd", "timeseries.csv"} <= {p.name for p in out.iterdir()}
    assert _leftovers(tmp_path) == []
    ents = read_rrd(out / "run.rrd")["t"]
    samples = json.loads((out / "result.json").read_text())["samples"]
    assert len(ents["/rig/fr/pressure"]["time"]) == samples == 2001  # 2 s at 1 kHz, both ends
    table = ents["/info/dlc_table"]["static"]["TextDocument:text"][0]
    assert table.splitlines()[0] in proc.stdout and table.splitlines()[-1] in proc.stdout


def _fake_run(result, before=lambda: None):
    def run(*args, **kwargs):
        before()
        return result

    return run


def test_a_failing_recording_process_leaves_nothing(runs, tmp_path, monkeypatch, capsys):
    """An error in the child: one sentence, exit 1, neither --out nor --rrd nor a temporary file."""
    from rigsim.scenarios.cli.main import main
    from rigsim.scenarios.core import run as run_module

    (tmp_path / "s.toml").write_text(TOML)
    broken = dataclasses.replace(runs[1], poses="not a pose track")  # the child's log_case fails on it
    monkeypatch.setattr(run_module, "run", _fake_run(broken))
    out, rrd = tmp_path / "out", tmp_path / "x.rrd"
    assert main(["run", str(tmp_path / "s.toml"), "--out", str(out), "--rrd", str(rrd), "--quiet"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert err.startswith("rigsim: error: writing the recording") and "AttributeError" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_a_recording_that_cannot_be_written_is_exit_2_and_leaves_nothing(runs, tmp_path, monkeypatch, capsys):
    """The child's OSError (its folder became a file during the run) reaches the command as the
    parent's own would: exit 2, one sentence, nothing written."""
    from rigsim.scenarios.cli.main import main
    from rigsim.scenarios.core import run as run_module

    (tmp_path / "s.toml").write_text(TOML)
    sub = tmp_path / "sub"
    sub.mkdir()

    def folder_becomes_file():  # the folder, with the run's claim on x.rrd in it, removed and a file put there
        shutil.rmtree(sub)
        sub.write_text("")

    monkeypatch.setattr(run_module, "run", _fake_run(runs[1], folder_becomes_file))
    out = tmp_path / "out"
    assert main(["run", str(tmp_path / "s.toml"), "--out", str(out), "--rrd", str(sub / "x.rrd"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("rigsim: error: cannot write output:"), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml", "sub"] and sub.read_text() == ""


def test_an_rrd_naming_the_scenario_is_refused_even_with_force(tmp_path, monkeypatch, capsys):
    from rigsim.scenarios.cli.main import main
    from rigsim.scenarios.core import run as run_module

    monkeypatch.setattr(run_module, "run", lambda *a, **k: pytest.fail("the run started"))
    toml = tmp_path / "s.toml"
    toml.write_text(TOML)
    assert main(["run", str(toml), "--out", str(tmp_path / "out"), "--rrd", str(toml), "--force", "--quiet"]) == 2
    assert "is the scenario file" in capsys.readouterr().err
    assert toml.read_text() == TOML and sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


@pytest.mark.skipif(not pathlib.Path("/proc/self/stat").is_file(), reason="reads /proc (Linux)")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL])
def test_no_recording_process_outlives_its_command(tmp_path, sig):
    """SIGTERM: the command stops its recording process, exits 143 and leaves nothing. SIGKILL
    (no cleanup possible): the recording process still ends by itself (its pipe to the parent
    closes)."""
    (tmp_path / "s.toml").write_text(TOML)
    argv = [sys.executable, "-m", "rigsim.scenarios.cli.main", "run", "s.toml", "--mode", "rig", "--duration-s", "600",
            "--out", "out", "--rrd", "out/run.rrd", "--quiet"]
    parent = subprocess.Popen(argv, cwd=tmp_path, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        child = _recording_child(parent)
        parent.send_signal(sig)
        parent.wait(timeout=120)
        child_alive = _alive(child)  # at once: reading stderr would wait for the child too (it shares it)
        err = parent.stderr.read()
    finally:
        if parent.poll() is None:
            parent.kill()
    if sig == signal.SIGTERM:
        assert parent.returncode == 143 and err.strip() == "rigsim: terminated", err
        assert not child_alive  # stopped and reaped before the command ended
        assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]
    else:
        assert parent.returncode == -signal.SIGKILL
        assert _wait_gone(child), f"recording process {child} outlived its killed parent"


def test_the_recording_process_loads_no_simulator():
    """What the child imports to write a recording (``rigsim.scenarios.review.recording`` and rerun's
    warm-up) loads neither MuJoCo nor numba nor scipy: it unpickles poses the run took and steps
    nothing, and what it imports runs on the core beside the run (mujoco's import alone is ~0.2 s of CPU)."""
    code = ("import sys\n"
            "from rigsim.scenarios.review.recording_process import _NoPandas\n"
            "sys.meta_path.insert(0, _NoPandas)\n"
            "from rigsim.scenarios.review import recording\n"
            "recording.warm_up()\n"
            "print(sorted(m for m in ('mujoco', 'numba', 'scipy', 'pandas') if m in sys.modules))\n")
    proc = subprocess.run([sys.executable, "-c", code], env=ENV, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip() == "[]"
