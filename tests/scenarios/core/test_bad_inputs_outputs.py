"""Output folders and files against careless paths: ``--force`` never deletes what rigsim did not write.

The cases of a careless user: the output folder given as the folder that holds the input
(``identify --from-file d/rec.rsp --out d --force``, ``run d/scen.toml --out d --force``), as the
working folder (``--out .``), a parent of it (``--out ..``), the home folder, through a symbolic
link; a folder of the user's own that rigsim never wrote; a rigsim result with a file of the user's
added; a sweep folder under another command's ``--force``. Each is refused with one line on stderr
and exit code 2, before any work, and every file stays byte for byte. Also: a dangling symbolic
link as ``--out`` and ``-o p/x.csv/`` are refused before the run; a speed that aliases the road's
band is refused naming the scenario's keys; a long run states its time and disk first, and one
whose files would not fit on the disk is refused.
"""

from __future__ import annotations

import hashlib
import pathlib

import pytest

from rigsim.scenarios.cli.main import main
from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.outputs import MARKER, claim_output_folder, staged_output

SCENARIO = 'name = "o"\nspeed_kmh = 72.0\nduration_s = 1.0\nseed = 5\nlead_in_s = 0.5\n[road]\nroughness = "high"\n'
CSV = "time_s,drive_fl,lvdt_fl\n" + "".join(f"{i / 1000},{i % 7},{i % 5}\n" for i in range(20))


def _tree(folder: pathlib.Path) -> dict[str, str]:
    """Every file under ``folder`` -> sha256 of its bytes."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}



@pytest.fixture()
def no_work(monkeypatch):
    """The simulation and the recorded identification fail the test if they start."""
    from rigsim.scenarios.core import run as run_module
    from rigsim.scenarios.records import recorded

    monkeypatch.setattr(run_module, "run", lambda *a, **k: pytest.fail("the run started"))
    monkeypatch.setattr(recorded, "identify_recorded", lambda *a, **k: pytest.fail("the identification started"))


def _refused(one_line, argv, folder, capsys, *expected):
    before = _tree(folder)
    assert main(argv) == 2
    line = one_line(capsys.readouterr().err)
    for text in expected:
        assert text in line, line
    assert _tree(folder) == before
    return line


@pytest.mark.parametrize("force", [False, True])
def test_the_folder_of_the_input_is_refused_as_out(one_line, tmp_path, capsys, no_work, force):
    d = tmp_path / "d"
    d.mkdir()
    (d / "rec.csv").write_text(CSV)
    (d / "notes.txt").write_text("mine")
    (d / "scen.toml").write_text(SCENARIO)
    extra = ["--force"] if force else []
    line = _refused(one_line, ["identify", "--from-file", str(d / "rec.csv"), "--pairs", "fl=drive_fl:lvdt_fl",
                     "--out", str(d), "--quiet", *extra], tmp_path, capsys, f"--out {d} contains the input {d / 'rec.csv'}")
    assert "previous result" not in line
    _refused(one_line, ["run", str(d / "scen.toml"), "--out", str(d), "--quiet", *extra], tmp_path, capsys,
             f"--out {d} contains the input {d / 'scen.toml'}")


def test_the_working_folder_its_parents_and_home_are_refused(one_line, tmp_path, capsys, no_work, monkeypatch):
    work = tmp_path / "home" / "work"
    (work / "src").mkdir(parents=True)
    (work / "src" / "a.py").write_text("x = 1\n")
    (work / "scen.toml").write_text(SCENARIO)
    monkeypatch.chdir(work)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    for out, what in ((".", "is the working folder"), ("..", "contains the working folder"),
                      (str(tmp_path / "home"), "contains the working folder"), (str(tmp_path), "contains")):
        _refused(one_line, ["run", "scen.toml", "--out", out, "--quiet", "--force"], tmp_path, capsys, what)
    monkeypatch.chdir(tmp_path)  # the home folder, as such, from elsewhere
    (tmp_path / "s.toml").write_text(SCENARIO)
    _refused(one_line, ["run", "s.toml", "--out", str(tmp_path / "home"), "--quiet", "--force"], tmp_path, capsys,
             "the home folder")


def test_a_symbolic_link_to_the_folder_of_the_input_is_refused(one_line, tmp_path, capsys, no_work):
    d = tmp_path / "d"
    d.mkdir()
    (d / "scen.toml").write_text(SCENARIO)
    (tmp_path / "link").symlink_to(d)
    _refused(one_line, ["run", str(d / "scen.toml"), "--out", str(tmp_path / "link"), "--quiet", "--force"], tmp_path,
             capsys, "contains the input")


@pytest.mark.parametrize("force", [False, True])
def test_a_folder_rigsim_did_not_write_is_refused_force_or_not(one_line, tmp_path, capsys, no_work, force):
    (tmp_path / "s.toml").write_text(SCENARIO)
    mine = tmp_path / "mine"
    (mine / "data").mkdir(parents=True)
    (mine / "data" / "x.bin").write_bytes(b"\x00\x01")
    (mine / "readme.txt").write_text("mine")
    line = _refused(one_line, ["run", str(tmp_path / "s.toml"), "--out", str(mine), "--quiet", *(["--force"] * force)],
                    tmp_path, capsys)
    assert line == (f"rigsim: error: --out {mine} holds 2 files that rigsim did not write; name a new or empty "
                    "folder (--force replaces only a folder rigsim wrote)")


def test_a_marker_that_is_not_rigsims_does_not_make_a_folder_rigsims(tmp_path):
    """A marker that is a folder, not JSON, or lists entries of the wrong type: not rigsim's."""
    for i, make in enumerate((lambda p: p.mkdir(), lambda p: p.write_text("not json"),
                              lambda p: p.write_text('{"entries": [1, 2]}'))):
        target = tmp_path / f"t{i}"
        target.mkdir()
        (target / "keep.txt").write_text("keep")
        make(target / MARKER)
        with pytest.raises(ScenarioError, match="that rigsim did not write"):
            with staged_output(target, force=True):
                pytest.fail("the block ran")
        assert (target / "keep.txt").read_text() == "keep"


def test_force_refuses_a_file_added_between_the_check_and_the_replacement(tmp_path):
    target = tmp_path / "out"
    with staged_output(target) as stage:
        (stage.path / "r.json").write_text("old")
    with pytest.raises(ScenarioError, match="holds late.txt that rigsim did not write there"):
        with staged_output(target, force=True) as stage:
            (stage.path / "r.json").write_text("new")
            (target / "late.txt").write_text("another program's")
    assert (target / "r.json").read_text() == "old" and (target / "late.txt").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no staging folder left


def test_a_sweep_folder_is_resumed_by_sweep_and_refused_by_force(one_line, tmp_path, capsys, no_work):
    out = tmp_path / "sweep"
    claim_output_folder(out, written_by="rigsim sweep", create=True)
    (out / "results.csv").write_text("case\n")
    assert claim_output_folder(out, written_by="rigsim sweep") == out  # resumed into
    (tmp_path / "s.toml").write_text(SCENARIO)
    _refused(one_line, ["run", str(tmp_path / "s.toml"), "--out", str(out), "--quiet", "--force"], tmp_path, capsys,
             "holds the results of rigsim sweep, which resumes into it")
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "results.csv").write_text("my own table\n")
    with pytest.raises(ScenarioError, match="holds 1 file that rigsim sweep did not write"):
        claim_output_folder(mine, written_by="rigsim sweep")
    with staged_output(tmp_path / "run") as stage:  # another command's result
        (stage.path / "result.json").write_text("{}")
    with pytest.raises(ScenarioError, match="already holds a previous result"):
        claim_output_folder(tmp_path / "run", written_by="rigsim sweep")


def test_a_dangling_symbolic_link_as_out_is_refused_before_the_run(one_line, tmp_path, capsys, no_work):
    (tmp_path / "s.toml").write_text(SCENARIO)
    (tmp_path / "out").symlink_to(tmp_path / "nowhere")
    _refused(one_line, ["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "out"), "--quiet"], tmp_path, capsys,
             "is a symbolic link to", "which does not exist")


def test_an_output_file_ending_in_a_slash_is_refused(one_line, tmp_path, capsys):
    (tmp_path / "in.csv").write_text("time_s,Fz_fl_N\n" + "".join(f"{i / 1000},{20000 + i}\n" for i in range(50)))
    (tmp_path / "p").mkdir()
    _refused(one_line, ["correct", str(tmp_path / "in.csv"), "--actuator", str(tmp_path / "none.toml"), "-o",
              str(tmp_path / "p" / "x.csv") + "/"], tmp_path, capsys, "ends in '/'")


def test_a_speed_that_aliases_the_road_band_names_the_scenario_keys(one_line, tmp_path, capsys):
    """200 km/h = 55.6 m/s carries the synthesized road's 10 cycle/m to 556 Hz, above the 500 Hz
    Nyquist rate of the 1 kHz drive: the limits follow from v n_max <= fs / 2."""
    (tmp_path / "s.toml").write_text(SCENARIO.replace("speed_kmh = 72.0", "speed_kmh = 200.0"))
    line = _refused(one_line, ["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o"), "--quiet"], tmp_path, capsys,
                    "speed_kmh = 200 km/h", "road.n_max_cyc_per_m = 10 cycle/m")
    assert "at most 180 km/h" in line and "at most 9 cycle/m" in line and "fs_hz" not in line


def test_a_long_run_states_its_cost_and_one_too_large_for_the_disk_is_refused(one_line, tmp_path, capsys, no_work,
                                                                              monkeypatch):
    import shutil

    from rigsim.scenarios.core.cost import run_cost

    long = SCENARIO.replace("duration_s = 1.0", "duration_s = 3600.0")
    (tmp_path / "s.toml").write_text(long)
    cost = run_cost("rig", 3600.5, 3_600_001)
    assert cost.columns == 25 and cost.long  # time, then 6 signals x 4 wheels
    with pytest.raises(pytest.fail.Exception, match="the run started"):
        main(["run", str(tmp_path / "s.toml"), "--mode", "rig", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert "a 3600 s rig run: about" in err and "3,600,001 rows x 25 columns" in err
    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage._replace(free=100 * 2**20))
    _refused(one_line, ["run", str(tmp_path / "s.toml"), "--mode", "rig", "--out", str(tmp_path / "o")], tmp_path, capsys,
             "would write about 1.", "100 MiB free")


def test_the_cost_estimate_counts_the_columns_a_run_writes(tmp_path):
    """The estimate's column count against the header a real (short) run writes, in both modes."""
    from rigsim.scenarios.core.config import load_scenario
    from rigsim.scenarios.core.cost import run_cost
    from rigsim.scenarios.core.run import run

    (tmp_path / "s.toml").write_text(SCENARIO.replace("duration_s = 1.0", "duration_s = 0.05"))
    scenario = load_scenario(tmp_path / "s.toml")
    for mode in ("road", "rig"):
        result = run(scenario, mode)
        assert run_cost(mode, 0.55, result.t_s.shape[0]).columns == len(result.column_names())
