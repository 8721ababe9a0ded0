"""``benchmarks/fleet_suite.py --page``: the parts of one draw (``--part K/N``) joined into that draw,
from hand-made plant scores. Reference: the joined draw holds each truck once, in the draw's order,
and its confidence interval is the one computed over all of its trucks at once
(:func:`rigsim.scenarios.studies.model_suite.goals.share_interval`), not either part's."""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess

import numpy as np
import pytest

from rigsim.scenarios.core.files import to_json
from rigsim.scenarios.studies.model_suite.goals import share_interval
from rigsim.scenarios.studies.model_suite.mismatch_score import PlantScore


@pytest.fixture(scope="module")
def suite(load_benchmark):
    return load_benchmark("fleet_suite")


def _score(i: int, dlc: float) -> PlantScore:
    n = {k: np.full(4, 0.05) for k in ("linear", "hybrid", "forced", "delivered")}
    n["linear"] = np.full(4, 0.2)
    return PlantScore(name=f"fleet{i:02d}-B-50kmh-0kg", plant={"_spec": "s", "_lacks": "l"}, method="model", reason="",
                      nrmse=n, dlc_error={k: np.full(4, dlc) for k in n}, floor=np.full(4, 0.2), wall_s=10.0 + i,
                      cpu_s=20.0, scored_s=20.0, fit_nrmse=np.full(4, 0.05), model_error=np.full(4, 0.1))


def _run(part: str, scores, seed: int = 7) -> dict:
    return json.loads(to_json({"draw": "fresh", "seed": seed, "trucks": 4, "part": part, "duration_s": 30.0,
                               "at_retry_rate": [], "noise_N": 100.0, "cab": "auto", "command": f"run --part {part}",
                               "summary": {}, "interval": [0.0, 0.0], "wall_time_s": 5.0,
                               "plants": [s.to_dict() for s in scores]}))


def test_the_parts_of_a_draw_are_joined_into_it(suite):
    scores = [_score(0, 0.001), _score(1, 0.02), _score(2, 0.003), _score(3, 0.004)]  # truck 1 misses the 1 %
    one, two = _run("1/2", scores[0::2]), _run("2/2", scores[1::2])
    (run,) = suite.joined([two, one])
    assert [p["name"][:7] for p in run["plants"]] == ["fleet00", "fleet01", "fleet02", "fleet03"]
    assert run["part"] == "1/1" and run["command"] == "run --part 2/2 & run --part 1/2"
    assert tuple(run["interval"]) == share_interval(scores) != (0.0, 0.0)
    assert suite.joined([_run("1/1", scores)])[0]["interval"] == [0.0, 0.0]  # a whole draw as it was printed


def test_parts_that_do_not_make_one_draw_are_refused(suite):
    scores = [_score(i, 0.001) for i in range(4)]
    with pytest.raises(SystemExit, match="do not make one draw"):
        suite.joined([_run("1/2", scores[0::2]), _run("2/2", scores[0::2])])  # a truck twice, two missing
    with pytest.raises(SystemExit, match="do not make one draw"):
        suite.joined([_run("1/2", scores[0::2])])  # half a draw
    with pytest.raises(SystemExit, match="do not make one draw"):  # parts of two draws are two half draws
        suite.joined([_run("1/2", scores[0::2]), _run("2/2", scores[1::2], seed=8)])


def test_a_part_is_k_of_n(suite):
    assert suite._part("2/3") == (2, 3)
    for bad in ("3/2", "0/2", "a/b", "2"):
        with pytest.raises(argparse.ArgumentTypeError):
            suite._part(bad)


def _args(tmp_path, **kw) -> argparse.Namespace:
    return argparse.Namespace(**{"draw": "fresh", "seed": 7, "trucks": 4, "duration_s": 30.0, "noise_N": 100.0,
                                 "cab": "auto", "part": (1, 1), "workers": 1, "keep": tmp_path / "kept.jsonl"} | kw)


def _settings(suite, args) -> dict:
    return {"draw": args.draw, "seed": args.seed, "trucks": args.trucks, "duration_s": args.duration_s,
            "noise_N": args.noise_N, "cab": args.cab, "code": suite.code_version()}


def test_a_kept_score_is_read_back_as_it_was_and_a_cut_line_is_run_again(suite, tmp_path):
    args = _args(tmp_path)
    settings = _settings(suite, args)
    suite.keep(args.keep, settings, _score(0, 0.001), False)
    suite.keep(args.keep, settings, _score(1, 0.02), True)
    with args.keep.open("a", encoding="utf-8") as f:
        f.write('{"draw": "fresh", "plant": {"na')  # a run cut while writing truck 2
    kept = suite.kept_scores(suite.read_kept(args.keep), settings, args.keep)
    assert sorted(kept) == ["fleet00-B-50kmh-0kg", "fleet01-B-50kmh-0kg"]
    score, retried = kept["fleet01-B-50kmh-0kg"]
    assert retried and not kept["fleet00-B-50kmh-0kg"][1]
    assert score.to_dict() == _score(1, 0.02).to_dict()


def test_a_keep_file_of_another_draw_is_refused_naming_what_differs(suite, tmp_path, capsys):
    args = _args(tmp_path)
    suite.keep(args.keep, _settings(suite, args), _score(0, 0.001), False)
    with pytest.raises(SystemExit) as exc:
        suite.kept_scores(suite.read_kept(args.keep), _settings(suite, _args(tmp_path, seed=8)), args.keep)
    assert exc.value.code == 2 and "seed 7, not 8" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # scored by other code: not one draw either
        suite.kept_scores(suite.read_kept(args.keep), _settings(suite, args) | {"code": "0" * 40}, args.keep)


def test_a_fresh_draw_with_a_keep_file_goes_on_with_its_seed(suite, tmp_path):
    args = _args(tmp_path, seed=None)
    suite.keep(args.keep, _settings(suite, _args(tmp_path, seed=123)), _score(0, 0.001), False)
    lines = suite.read_kept(args.keep)
    assert suite._seed(args, lines) == 123
    assert suite._seed(_args(tmp_path, seed=5), lines) == 5
    assert suite._seed(_args(tmp_path, seed=None, draw="development"), lines) == suite.DEVELOPMENT_SEED


def test_a_draw_cut_short_runs_only_the_trucks_its_keep_file_lacks(suite, tmp_path, monkeypatch):
    """Three of four trucks kept: only the fourth's road, rig and identification run and it is scored and
    kept; the draw's table holds all four (truck 1's miss counted)."""
    args = _args(tmp_path)
    for i in range(3):
        suite.keep(args.keep, _settings(suite, args), _score(i, 0.02 if i == 1 else 0.001), False)
    trucks = [argparse.Namespace(name=f"fleet{i:02d}-B-50kmh-0kg") for i in range(4)]
    ran = []
    monkeypatch.setattr(suite, "fleet_trucks", lambda n, seed: trucks)
    monkeypatch.setattr(suite, "run_jobs", lambda jobs, workers, on_done=None: ran.extend(jobs) or [None] * len(jobs))
    monkeypatch.setattr(suite, "_score", lambda truck, runs, a, rate: _score(3, 0.002))
    monkeypatch.setattr(suite, "spec_text", lambda truck: "s")
    monkeypatch.setattr(suite, "lacks", lambda truck: "l")
    out = suite.run_draw(args)
    assert [job[1][0].name for job in ran] == ["fleet03-B-50kmh-0kg"] * 3
    assert [p["name"][:7] for p in out["plants"]] == ["fleet00", "fleet01", "fleet02", "fleet03"]
    assert out["summary"]["share_good"] == pytest.approx(0.75)
    assert len(suite.read_kept(args.keep)) == 4


def test_bad_input_is_refused_with_exit_2_before_any_run(suite, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        suite.main(["--page", str(tmp_path / "missing.txt"), "--results", str(tmp_path)])
    assert exc.value.code == 2 and "no such file" in capsys.readouterr().err
    (tmp_path / "empty.txt").write_text("not a run\n", encoding="utf-8")
    with pytest.raises(SystemExit) as exc:
        suite.main(["--page", str(tmp_path / "empty.txt"), "--results", str(tmp_path)])
    assert exc.value.code == 2 and "no JSON line" in capsys.readouterr().err
    for argv in (["--draw", "fresh", "--trucks", "0"], []):
        with pytest.raises(SystemExit) as exc:
            suite.main(argv)
        assert exc.value.code == 2
    assert not list(tmp_path.glob("*.md"))


@pytest.mark.skipif(shutil.which("git") is None, reason="needs git")
def test_the_code_version_follows_the_code_not_the_docs(suite, tmp_path):
    """A --keep file is tied to the code that scored it: a commit of docs leaves the version as it is, an
    uncommitted change to the package says ``+changes-`` with its own digest, and its commit gives another
    version."""
    def git(*args):
        subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *args], cwd=tmp_path, check=True,
                       capture_output=True)

    for path in suite.CODE_PATHS + ("docs/index.md",):  # a folder (no suffix) gets one file
        f = tmp_path / path if "." in path else tmp_path / path / "a.py"
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text("1\n", encoding="utf-8")
    git("init", "-q")
    git("add", "-A")
    git("commit", "-qm", "a")
    first = suite.code_version(tmp_path)
    assert first is not None and "+" not in first
    (tmp_path / "docs/index.md").write_text("2\n", encoding="utf-8")
    git("commit", "-qam", "docs")
    assert suite.code_version(tmp_path) == first
    (tmp_path / "scenarios/a.py").write_text("2\n", encoding="utf-8")
    changed = suite.code_version(tmp_path)
    assert changed.startswith(first + "+changes-")
    (tmp_path / "scenarios/a.py").write_text("3\n", encoding="utf-8")  # other uncommitted code: another version
    assert suite.code_version(tmp_path).startswith(first + "+changes-") and suite.code_version(tmp_path) != changed
    git("commit", "-qam", "code")
    assert suite.code_version(tmp_path) not in (first, changed, None) and "+" not in suite.code_version(tmp_path)
    assert suite.code_version(tmp_path.parent / "nowhere") is None
