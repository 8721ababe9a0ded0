"""Outputs whole or absent: :mod:`rigsim.scenarios.core.outputs` and every command that writes
a folder.

The context manager: refusals before any work (empty path, a file in the folder's place, a previous
result without --force, a parent that cannot be written), nothing at the target and no staging
folder after an error or an interrupt, the old result kept when a --force run fails, leftovers of
killed runs removed. The commands: a second ``rigsim run`` into the same --out is refused with one
line and leaves the first result byte-identical, --force replaces it, --out "" and an --rrd that
cannot be written are refused before the run; paper, validate, identify and iterate (their
computations replaced by stand-ins) build their folders in one piece and print the final paths.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import pathlib
import types

import pytest

# Imported before any test replaces a function they import by name (identify_rig, run): a module
# imported for the first time while a stand-in is in place would keep the stand-in.
import rigsim.scenarios.studies.iterate.compute  # noqa: F401
import rigsim.scenarios.studies.paper.compute  # noqa: F401
import rigsim.scenarios.studies.validate.compute  # noqa: F401
import rigsim.scenarios.studies.validate.runs  # noqa: F401
from rigsim.correction.io.atomic import host_tag
from rigsim.scenarios.cli.main import main
from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.outputs import MARKER, check_output_file, remove_stale_staging, staged_output

SCENARIO = 'name = "o"\nspeed_kmh = 72.0\nduration_s = 1.0\nseed = 5\nlead_in_s = 0.5\n[road]\nroughness = "high"\n'


def _listing(folder: pathlib.Path) -> dict[str, str]:
    """Every file under ``folder`` (hidden ones too, rigsim's marker left out) -> sha256 of its bytes."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file() and p.name != MARKER}


def _names(folder: pathlib.Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name != MARKER)


def _previous(target: pathlib.Path, files: dict[str, str]) -> None:
    """A previous result of rigsim in ``target``: ``files`` (relative path -> text) written through
    :func:`staged_output`, so that the folder carries rigsim's marker."""
    with staged_output(target) as stage:
        for rel, text in files.items():
            (stage.path / rel).parent.mkdir(parents=True, exist_ok=True)
            (stage.path / rel).write_text(text)


def _no_staging(folder: pathlib.Path) -> bool:
    return not [p for p in folder.iterdir() if p.name.endswith((".partial", ".old", ".tmp"))]


def _read_only(folder: pathlib.Path) -> pathlib.Path:
    folder.mkdir()
    folder.chmod(0o555)
    if os.access(folder, os.W_OK):  # root: permission bits do not stop it
        folder.chmod(0o755)
        pytest.skip("running as a user whom chmod 0o555 does not stop (root)")
    return folder


@pytest.fixture()
def readonly(tmp_path):
    folder = tmp_path / "ro"
    yield _read_only(folder)
    folder.chmod(0o755)


# ------------------------------------------------------------------------------- staged_output
@pytest.mark.parametrize("bad", ["", "   ", "\t"])
def test_an_empty_path_is_refused(tmp_path, monkeypatch, bad):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScenarioError, match=r"^--out is empty"):
        with staged_output(bad):
            pytest.fail("the block ran")
    assert list(tmp_path.iterdir()) == []


def test_a_file_in_the_folders_place_is_refused_even_with_force(tmp_path):
    target = tmp_path / "out"
    target.write_text("a file")
    for force in (False, True):
        with pytest.raises(ScenarioError, match="exists and is not a folder"):
            with staged_output(target, force=force):
                pytest.fail("the block ran")
    assert target.read_text() == "a file" and _no_staging(tmp_path)


def test_a_previous_result_is_refused_without_force_and_replaced_with_it(tmp_path):
    target = tmp_path / "out"
    _previous(target, {"a.txt": "old a", "sub/b.txt": "old b"})
    with pytest.raises(ScenarioError) as err:
        with staged_output(target):
            pytest.fail("the block ran")
    assert str(err.value) == (f"--out {target} already holds a previous result (2 files); choose another folder "
                              "or give --force to replace it")
    assert _listing(target) and (target / "a.txt").read_text() == "old a"
    with staged_output(target, force=True) as stage:
        assert stage.path.parent == tmp_path and stage.path.name == f".out.{host_tag()}.{os.getpid()}.partial"
        assert (target / "a.txt").exists()  # the old result stays until the work is done
        (stage.path / "new.txt").write_text("new")
    assert _names(target) == ["new.txt"]  # no stale file of the old result beside the new one
    assert _no_staging(tmp_path)


def test_an_empty_existing_folder_is_used_without_force(tmp_path):
    target = tmp_path / "out"
    target.mkdir()
    with staged_output(target) as stage:
        (stage.path / "x").write_text("x")
    assert (target / "x").read_text() == "x" and _no_staging(tmp_path)


def test_missing_parents_are_created_and_removed_again_after_an_error(tmp_path):
    target = tmp_path / "a" / "b" / "out"
    with pytest.raises(RuntimeError):
        with staged_output(target):
            assert (tmp_path / "a" / "b").is_dir()
            raise RuntimeError("work failed")
    assert list(tmp_path.iterdir()) == []
    with staged_output(target) as stage:
        (stage.path / "x").write_text("x")
    assert (target / "x").is_file()


def test_an_unwritable_parent_is_refused_before_the_work(readonly):
    with pytest.raises(ScenarioError, match=r"cannot be written: cannot create a folder in .*ro"):
        with staged_output(readonly / "out"):
            pytest.fail("the block ran")
    assert list(readonly.iterdir()) == []


def test_a_permission_error_of_the_os_is_one_sentence_before_the_work(tmp_path, monkeypatch):
    """The same refusal where chmod cannot be used (root): the OS's refusal stood in for."""
    def mkdir(path, mode=0o777):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(os, "mkdir", mkdir)
    with pytest.raises(ScenarioError) as err:
        with staged_output(tmp_path / "out"):
            pytest.fail("the block ran")
    assert str(err.value) == (f"--out {tmp_path / 'out'} cannot be written: cannot create a folder in {tmp_path} "
                              "(Permission denied); choose a folder you can write to")
    monkeypatch.setattr(os, "access", lambda path, mode: False)
    with pytest.raises(ScenarioError, match="^--rrd x.rrd cannot be written: no permission to write in "):
        check_output_file("x.rrd", "--rrd")
    assert list(tmp_path.iterdir()) == []


def test_a_parent_that_is_a_file_is_refused(tmp_path):
    (tmp_path / "f").write_text("")
    with pytest.raises(ScenarioError, match="cannot be written"):
        with staged_output(tmp_path / "f" / "out"):
            pytest.fail("the block ran")


@pytest.mark.parametrize("exc", [RuntimeError("boom"), KeyboardInterrupt(), SystemExit(3)])
def test_an_error_or_interrupt_leaves_nothing(tmp_path, exc):
    target = tmp_path / "out"
    with pytest.raises(type(exc)):
        with staged_output(target) as stage:
            (stage.path / "half.csv").write_text("1,2\n")
            (stage.path / "sub").mkdir()
            raise exc
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("exc", [RuntimeError("boom"), KeyboardInterrupt()])
def test_force_keeps_the_old_result_when_the_work_fails(tmp_path, exc):
    target = tmp_path / "out"
    _previous(target, {"result.json": "old"})
    before = _listing(target)
    with pytest.raises(type(exc)):
        with staged_output(target, force=True) as stage:
            (stage.path / "result.json").write_text("new, half")
            raise exc
    assert _listing(target) == before and _no_staging(tmp_path)


def test_a_failed_rename_puts_the_old_result_back(tmp_path, monkeypatch):
    target = tmp_path / "out"
    _previous(target, {"r": "old"})
    real = os.rename

    def rename(src, dst):
        if str(src).endswith(".partial"):
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(os, "rename", rename)
    with pytest.raises(OSError):
        with staged_output(target, force=True) as stage:
            (stage.path / "r").write_text("new")
    assert (target / "r").read_text() == "old" and _no_staging(tmp_path)


def test_leftovers_of_killed_runs_are_removed(tmp_path, capsys):
    host = host_tag()
    dead = tmp_path / f".out.{host}.99999999.partial"  # pid above the kernel's pid_max: not running
    (dead / "sub").mkdir(parents=True)
    (dead / "sub" / "half.csv").write_text("x")
    keep = [tmp_path / f".out.{host}.1.partial", tmp_path / ".out.elsewhere.99999999.partial",
            tmp_path / f".other.{host}.99999999.partial"]
    for p in keep:  # pid 1 runs; another host's; another target's
        p.mkdir()
    with staged_output(tmp_path / "out") as stage:
        (stage.path / "x").write_text("x")
    assert not dead.exists() and all(p.exists() for p in keep)
    assert (tmp_path / "out" / "x").is_file()
    assert capsys.readouterr().err == ""


def test_a_previous_result_moved_aside_by_a_killed_force_run_is_put_back(tmp_path, capsys):
    aside = tmp_path / f".out.{host_tag()}.99999999.old"
    aside.mkdir()
    (aside / "result.json").write_text("old")
    remove_stale_staging(tmp_path / "out")
    assert (tmp_path / "out" / "result.json").read_text() == "old" and not aside.exists()
    assert "put back" in capsys.readouterr().err


def test_a_leftover_that_cannot_be_removed_is_named_in_a_warning(tmp_path, capsys):
    dead = tmp_path / f".out.{host_tag()}.99999999.partial"
    (dead / "sub").mkdir(parents=True)
    (dead / "sub" / "f").write_text("x")
    (dead / "sub").chmod(0o555)
    try:
        if os.access(dead / "sub", os.W_OK):
            pytest.skip("running as a user whom chmod 0o555 does not stop (root)")
        remove_stale_staging(tmp_path / "out")
        err = capsys.readouterr().err.strip()
        assert err.startswith("rigsim: warning: cannot remove") and str(dead) in err and len(err.splitlines()) == 1
    finally:
        (dead / "sub").chmod(0o755)


def test_staging_maps_paths_to_their_final_place(tmp_path):
    target = tmp_path / "out"
    with staged_output(target) as stage:
        assert stage.final(stage.path / "a" / "b.json") == target / "a" / "b.json"
        assert stage.place(target / "rec.rrd") == stage.path / "rec.rrd"
        assert stage.place(tmp_path / "rec.rrd") == tmp_path / "rec.rrd"


# ---------------------------------------------------------------------------- check_output_file
def test_check_output_file(tmp_path):
    (tmp_path / "exists.rrd").write_text("x")
    (tmp_path / "folder").mkdir()
    (tmp_path / "file").write_text("")
    cases = {"": "is empty", " ": "is empty", str(tmp_path / "folder"): "is a folder",
             str(tmp_path / "exists.rrd"): "already exists; choose another file or give --force",
             str(tmp_path / "file" / "x.rrd"): "is not a folder"}
    for path, what in cases.items():
        with pytest.raises(ScenarioError, match=what):
            check_output_file(path, "--rrd")
    check_output_file(tmp_path / "exists.rrd", "--rrd", force=True)
    check_output_file(tmp_path / "new" / "deeper" / "x.rrd", "--rrd")  # parents made when written
    with pytest.raises(ScenarioError, match="is the --out folder"):
        check_output_file(tmp_path / "out", "--rrd", folder=tmp_path / "out")
    check_output_file(tmp_path / "out" / "x.rrd", "--rrd", folder=tmp_path / "out")
    assert not (tmp_path / "new").exists()


def test_check_output_file_refuses_an_unwritable_folder(readonly):
    with pytest.raises(ScenarioError, match="no permission to write in"):
        check_output_file(readonly / "x.rrd", "--rrd")


# ------------------------------------------------------------------------------- rigsim run

@pytest.fixture()
def scenario(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SCENARIO)
    return path


def test_a_second_run_into_the_same_folder_is_refused_and_force_replaces(one_line, tmp_path, scenario, capsys, monkeypatch):
    out = tmp_path / "out"
    assert main(["run", str(scenario), "--out", str(out), "--quiet"]) == 0
    assert f"wrote {out / 'result.json'} and {out / 'timeseries.csv'}" in capsys.readouterr().out
    first = _listing(out)
    assert set(first) == {"result.json", "timeseries.csv", "timings.json"}

    from rigsim.scenarios.core import run as run_module

    monkeypatch.setattr(run_module, "run", lambda *a, **k: pytest.fail("the run started"))
    assert main(["run", str(scenario), "--out", str(out), "--quiet"]) == 2
    line = one_line(capsys.readouterr().err)
    assert line == (f"rigsim: error: --out {out} already holds a previous result (3 files); choose another folder "
                    "or give --force to replace it")
    assert _listing(out) == first
    monkeypatch.undo()

    (out / "notes.txt").write_text("the user's, added after the run")  # --force never deletes it
    other = tmp_path / "other.toml"
    other.write_text(SCENARIO.replace("seed = 5", "seed = 6"))
    assert main(["run", str(other), "--out", str(out), "--quiet", "--force"]) == 2
    assert one_line(capsys.readouterr().err) == (f"rigsim: error: --out {out} holds notes.txt that rigsim did not "
                                                  "write there; move it out of the folder or name another folder")
    assert _listing(out) == {**first, "notes.txt": _listing(out)["notes.txt"]}
    (out / "notes.txt").unlink()
    assert main(["run", str(other), "--out", str(out), "--quiet", "--force"]) == 0
    assert f"wrote {out / 'result.json'}" in capsys.readouterr().out
    now = _listing(out)
    assert set(now) == {"result.json", "timeseries.csv", "timings.json"}
    assert now["timeseries.csv"] != first["timeseries.csv"]  # replaced by the new run's
    assert _no_staging(tmp_path)


def test_run_refuses_an_empty_out(one_line, tmp_path, scenario, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    before = sorted(os.listdir(tmp_path))
    assert main(["run", str(scenario), "--out", "", "--quiet"]) == 2
    assert one_line(capsys.readouterr().err) == "rigsim: error: --out is empty; name the output folder"
    assert sorted(os.listdir(tmp_path)) == before


def test_run_refuses_an_rrd_it_cannot_write_before_the_run(one_line, tmp_path, scenario, capsys, monkeypatch):
    from rigsim.scenarios.core import run as run_module

    monkeypatch.setattr(run_module, "run", lambda *a, **k: pytest.fail("the run started"))
    (tmp_path / "file").write_text("")
    (tmp_path / "exists.rrd").write_text("old")
    for rrd, what in ((tmp_path / "file" / "x.rrd", "is not a folder"), (tmp_path / "exists.rrd", "already exists"),
                      (tmp_path / "out", "is the --out folder")):
        assert main(["run", str(scenario), "--out", str(tmp_path / "out"), "--rrd", str(rrd), "--quiet"]) == 2
        assert what in one_line(capsys.readouterr().err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["exists.rrd", "file", "s.toml"]


def test_run_refuses_an_rrd_into_a_read_only_folder(one_line, tmp_path, scenario, capsys, readonly):
    out = tmp_path / "out"
    assert main(["run", str(scenario), "--out", str(out), "--rrd", str(readonly / "x.rrd"), "--quiet"]) == 2
    assert "no permission to write in" in one_line(capsys.readouterr().err)
    assert not out.exists() and list(readonly.iterdir()) == [] and _no_staging(tmp_path)


class _RecordingStandIn:
    """Stands in for :class:`rigsim.scenarios.review.recording_process.RecordingProcess` (the real child
    process is tested in test_recording_process.py): writes b"rrd" where it is told, or fails."""

    seen: list = []
    failure: BaseException | None = None

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        return None

    def submit(self, path, results, *, dlc_table=None):
        self.path = pathlib.Path(path)

    def commit(self):
        if self.failure is not None:
            raise self.failure
        type(self).seen.append(self.path)
        self.path.write_bytes(b"rrd")
        return self.path


def _stand_in_recording(monkeypatch, failure=None):
    from rigsim.scenarios.review import recording_process

    stand_in = type("StandIn", (_RecordingStandIn,), {"seen": [], "failure": failure})
    monkeypatch.setattr(recording_process, "RecordingProcess", stand_in)
    return stand_in


def test_run_writes_an_rrd_inside_its_folder_with_the_rest(tmp_path, scenario, capsys, monkeypatch):
    """--rrd inside --out lands there with the other files (one rename); the recording process is
    replaced by a stand-in (the real one is tested in test_recording_process.py)."""
    stand_in = _stand_in_recording(monkeypatch)
    out = tmp_path / "out"
    assert main(["run", str(scenario), "--out", str(out), "--rrd", str(out / "run.rrd"), "--quiet"]) == 0
    assert stand_in.seen and stand_in.seen[0].parent.name.endswith(".partial")  # written into the staging folder
    assert (out / "run.rrd").read_bytes() == b"rrd" and (out / "result.json").is_file()
    assert f"wrote recording {out / 'run.rrd'}" in capsys.readouterr().out


def test_run_failing_after_the_simulation_leaves_nothing(one_line, tmp_path, scenario, capsys, monkeypatch):
    _stand_in_recording(monkeypatch, failure=OSError(28, "No space left on device"))
    out = tmp_path / "out"
    assert main(["run", str(scenario), "--out", str(out), "--rrd", str(tmp_path / "x.rrd"), "--quiet"]) == 2
    assert "No space left" in one_line(capsys.readouterr().err)
    assert not out.exists() and _no_staging(tmp_path)


# ------------------------------------------------------------- the studies (computations stood in)
@dataclasses.dataclass(frozen=True)
class _FakePaper:
    cases: tuple = ()

    def table(self) -> str:
        return "table"

    def damage_table(self) -> str:
        return "damage"

    def model_table(self) -> None:  # no --model
        return None


def _fake_paper(monkeypatch, fail):
    from rigsim.scenarios.studies.paper import compute, report

    def run_paper(paths, **kwargs):
        if fail:
            raise RuntimeError("the study failed")
        return _FakePaper()

    monkeypatch.setattr(compute, "run_paper", run_paper)
    monkeypatch.setattr(report, "render_report", lambda r, **kw: {"report.md": b"# report", "fig.png": b"png"})
    return [], ["paper.json", "report.md", "fig.png"]


def _fake_validate(monkeypatch, fail):
    from rigsim.scenarios.studies.validate import command, report

    def validate(**kwargs):
        if fail:
            raise RuntimeError("the study failed")
        return types.SimpleNamespace(runs={})

    def write_report(result, out_dir):
        paths = {}
        for name in ("a.png", "report.md", "validate.json"):
            (pathlib.Path(out_dir) / name).write_text(name)
            paths[name] = pathlib.Path(out_dir) / name
        return paths

    monkeypatch.setattr(command, "validate", validate, raising=False)
    monkeypatch.setattr(report, "write_report", write_report)
    monkeypatch.setattr(report, "summary_lines", lambda r: ["summary"])
    return [], ["a.png", "report.md", "validate.json"]


def _fake_iterate(monkeypatch, fail, scenario):
    from rigsim.scenarios.studies.iterate import compute, report

    def iterate_scenario(*a, **k):
        if fail:
            raise RuntimeError("the study failed")
        return object()

    def write_files(result, out_dir):
        d = pathlib.Path(out_dir)
        for name in report.FILES:
            (d / name).write_text(name)
        return {name: d / name for name in report.FILES}

    monkeypatch.setattr(compute, "iterate_scenario", iterate_scenario)
    monkeypatch.setattr(report, "write_files", write_files)
    monkeypatch.setattr(report, "comparison_table", lambda r: "comparison")
    scenario.write_text(SCENARIO.replace("duration_s = 1.0", "duration_s = 12.0"))
    return [str(scenario), "--target", "displacement"], list(report.FILES)


@dataclasses.dataclass(frozen=True)
class _FakeIdent:
    fits: dict = dataclasses.field(default_factory=dict)

    def meta(self) -> dict:
        return {}


def _fake_identify(monkeypatch, fail, scenario):
    from rigsim.correction.io import actuator_file
    from rigsim.scenarios.studies.identify import compute, report

    def identify_rig(*a, **k):
        if fail:
            raise RuntimeError("the study failed")
        return _FakeIdent()

    monkeypatch.setattr(compute, "identify_rig", identify_rig)
    monkeypatch.setattr(report, "bode_png", lambda fits, title: b"png")
    monkeypatch.setattr(actuator_file, "write_actuators_file", lambda p, fits, meta: pathlib.Path(p).write_text("t"))
    return [str(scenario)], ["actuators.toml", "identification.json", "bode.png"]


def _study(name, monkeypatch, fail, scenario):
    if name == "paper":
        return _fake_paper(monkeypatch, fail)
    if name == "validate":
        return _fake_validate(monkeypatch, fail)
    if name == "iterate":
        return _fake_iterate(monkeypatch, fail, scenario)
    return _fake_identify(monkeypatch, fail, scenario)


STUDIES = ["paper", "validate", "identify", "iterate"]


@pytest.mark.parametrize("name", STUDIES)
def test_a_study_writes_its_folder_in_one_piece_and_names_the_final_paths(one_line, name, tmp_path, scenario, capsys,
                                                                          monkeypatch):
    argv, files = _study(name, monkeypatch, False, scenario)
    out = tmp_path / "out"
    assert main([name, *argv, "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert _names(out) == sorted(files)
    shown = {"paper": "report.md", "validate": "report.md", "identify": "actuators.toml", "iterate": "drive.csv"}
    assert str(out / shown[name]) in printed and ".partial" not in printed
    assert _no_staging(tmp_path)
    # a second time: refused before the computation, the first result unchanged
    first = _listing(out)
    assert main([name, *argv, "--out", str(out), "--quiet"]) == 2
    assert "already holds a previous result" in one_line(capsys.readouterr().err)
    assert _listing(out) == first
    # --force replaces it, but never a file rigsim did not write there
    (out / "notes.txt").write_text("x")
    assert main([name, *argv, "--out", str(out), "--quiet", "--force"]) == 2
    assert "holds notes.txt that rigsim did not write there" in one_line(capsys.readouterr().err)
    (out / "notes.txt").unlink()
    assert main([name, *argv, "--out", str(out), "--quiet", "--force"]) == 0
    assert _names(out) == sorted(files) and _no_staging(tmp_path)


@pytest.mark.parametrize("name", STUDIES)
def test_a_failing_study_leaves_nothing_and_force_keeps_the_old_result(name, tmp_path, scenario, capsys,
                                                                      monkeypatch):
    argv, _ = _study(name, monkeypatch, True, scenario)
    out = tmp_path / "deeper" / "out"
    with pytest.raises(RuntimeError):
        main([name, *argv, "--out", str(out), "--quiet"])
    assert not (tmp_path / "deeper").exists()
    _previous(out, {"old.json": "old"})
    with pytest.raises(RuntimeError):
        main([name, *argv, "--out", str(out), "--quiet", "--force"])
    assert _listing(out) == {"old.json": hashlib.sha256(b"old").hexdigest()} and _no_staging(out.parent)


@pytest.mark.parametrize("name", ["paper", "validate"])
def test_a_study_refuses_an_rrd_it_cannot_write_before_any_work(one_line, name, tmp_path, scenario, capsys, monkeypatch):
    argv, _ = _study(name, monkeypatch, True, scenario)  # the computation would fail: it must not start
    (tmp_path / "file").write_text("")
    out = tmp_path / "out"
    assert main([name, *argv, "--out", str(out), "--rrd", str(tmp_path / "file" / "x.rrd"), "--quiet"]) == 2
    assert "--rrd" in one_line(capsys.readouterr().err)
    assert not out.exists() and _no_staging(tmp_path)


def test_paper_rrd_into_a_read_only_folder_is_refused_before_any_work(one_line, tmp_path, capsys, monkeypatch, readonly):
    _fake_paper(monkeypatch, True)
    out = tmp_path / "out"
    assert main(["paper", "--out", str(out), "--rrd", str(readonly / "p.rrd"), "--quiet"]) == 2
    assert "no permission" in one_line(capsys.readouterr().err)
    assert not out.exists() and list(readonly.iterdir()) == []


def test_every_command_that_writes_a_folder_has_force():
    import argparse

    from rigsim.scenarios.cli.main import build_parser

    subs = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    for name in ("run", "paper", "validate", "identify", "iterate"):
        force = [a for a in subs[name]._actions if "--force" in a.option_strings]
        assert force and force[0].help.startswith("replace a previous result in --out"), name
    assert "--force" not in {o for a in subs["sweep"]._actions for o in a.option_strings}  # sweeps resume
