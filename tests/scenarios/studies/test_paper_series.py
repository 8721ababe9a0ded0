"""``rigsim paper`` writes the runs' time series only on request: a default run writes paper.json,
report.md, the figures and each run's result.json and timings.json; ``--series FORMAT`` adds each
run's ``timeseries.<ext>`` in that format (the writers of :func:`rigsim.scenarios.core.results.write_run`).
The physics is stood in by synthetic runs (tests/scenarios/studies/test_work_once.py's), so the
whole command runs in seconds."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import pytest

from rigsim.scenarios.cli.main import main
from rigsim.scenarios.core.config import load_scenario, paper_scenarios
from rigsim.scenarios.core.results import TIMESERIES_FORMATS
from rigsim.scenarios.studies.paper import command, compute
from tests.scenarios.studies.test_work_once import _actuators, _runs


@dataclasses.dataclass(frozen=True)
class _Identified:
    """The rig's identification as the scoring and paper.json read it: T_a per corner and its fit."""

    fits = {c: SimpleNamespace(orders=(0, 2), bandwidth_hz=15.0, held_out_error=0.01) for c in ("fl", "fr", "rl", "rr")}

    def actuators(self):
        return _actuators()


def _fake_identify_job(path, duration_s=None, truck=None):
    return _Identified()


def _fake_run_job(path, mode, duration_s=None, pose_rate_hz=None, finish_run=None, truck=None):
    """A road or rig run of the case at ``path`` (synthetic forces, 12 s at 1 kHz), finished as
    ``rigsim paper`` finishes its runs (module level: the pool's workers are forked from here)."""
    road, rig = _runs(extra_signals=True)
    result = dataclasses.replace(road if mode == "road" else rig, scenario_name=load_scenario(path).name)
    if finish_run is not None:
        finish_run(result)
    return result


@pytest.fixture()
def stand_ins(monkeypatch):
    monkeypatch.setattr(compute, "identify_job", _fake_identify_job)
    monkeypatch.setattr(compute, "run_job", _fake_run_job)


def _run_files(out):
    return sorted(p.relative_to(out).as_posix() for p in out.glob("*/*/*"))


def test_the_series_formats_are_the_writers():
    assert set(command.SERIES_FORMATS) == set(TIMESERIES_FORMATS)


def test_a_default_run_writes_tables_figures_report_and_json_only(stand_ins, tmp_path, capsys):
    out = tmp_path / "paper"
    assert main(["paper", "--out", str(out), "--jobs", "2", "--quiet"]) == 0
    names = [load_scenario(p).name for p in paper_scenarios(command.RIG)]
    assert _run_files(out) == sorted(f"{n}/{m}/{f}" for n in names for m in ("road", "rig")
                                     for f in ("result.json", "timings.json"))
    top = {p.name for p in out.iterdir() if p.is_file()}
    assert {"paper.json", "report.md", "table2.png"} <= top
    assert {p.suffix for p in out.rglob("*") if p.is_file()} <= {".json", ".md", ".png", ""}  # "": .rigsim-output
    assert not list(out.rglob("timeseries*"))
    assert "timeseries" not in (out / names[0] / "rig" / "result.json").read_text()
    assert "timeseries" not in capsys.readouterr().out


@pytest.mark.parametrize("fmt", ["csv", "rsp"])
def test_series_writes_every_run_in_the_asked_format(stand_ins, tmp_path, fmt):
    out = tmp_path / "paper"
    assert main(["paper", "--out", str(out), "--jobs", "2", "--quiet", "--series", fmt]) == 0
    series = sorted(p.relative_to(out).as_posix() for p in out.rglob("timeseries*"))
    names = [load_scenario(p).name for p in paper_scenarios(command.RIG)]
    assert series == sorted(f"{n}/{m}/timeseries{TIMESERIES_FORMATS[fmt]}" for n in names for m in ("road", "rig"))
    assert all((out / s).stat().st_size > 10_000 for s in series)
    assert f'"format": "{fmt}"' in (out / names[0] / "road" / "result.json").read_text()


def test_an_unknown_series_format_is_refused_before_any_work(stand_ins, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:  # argparse's refusal: the usage, then one error line
        main(["paper", "--out", str(tmp_path / "p"), "--series", "xlsx"])
    assert exc.value.code == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].startswith("rigsim: error: argument --series: invalid choice")
    assert not (tmp_path / "p").exists()


def test_a_series_format_without_its_library_is_refused_in_one_sentence(stand_ins, monkeypatch, tmp_path, capsys,
                                                                         one_line):
    from rigsim.correction.io import measured_lab

    def missing(*args, **kwargs):
        raise ValueError("writing .mf4 needs asammdf: pip install -e \".[lab]\"")

    monkeypatch.setattr(measured_lab, "need", missing)
    assert main(["paper", "--out", str(tmp_path / "p"), "--series", "mf4", "--quiet"]) == 2
    assert one_line(capsys.readouterr().err).startswith("rigsim: error: --series mf4: writing .mf4 needs asammdf")
    assert not (tmp_path / "p").exists()
