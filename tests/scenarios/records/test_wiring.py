"""Drive and LVDT wired wrongly in ``--pairs`` / ``--identify``: refused in one sentence naming the
corner and the likely cause, exit 2, nothing written, before any calibration.

Reference: the project's simulated rig (the paper's high-roughness 72 km/h case, 20 s on the
hydraulic rig, independent left and right tracks) written as a lab's CSV (drives ``Soll_XX`` and
LVDTs ``Weg_XX`` in mm, forces ``Fz_XX`` in kN): its own pairs identify T_a with held-out errors of
0.03-0.05 (docs/results/walkthrough_identify.md), the same pairs swapped give 1.35-1.39 and a phase
that leads the drive (:mod:`rigsim.correction.identification.plausibility`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rigsim.scenarios.cli.main import main

CORNERS = ("fl", "fr", "rl", "rr")


def _pairs(**override) -> str:
    pairs = {c: f"Soll_{c.upper()}:Weg_{c.upper()}" for c in CORNERS}
    pairs.update(override)
    return ",".join(f"{c}={p}" for c, p in pairs.items())


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    from test_correct_model import _write_csv

    from rigsim.scenarios.core.config import load_scenario, paper_scenarios
    from rigsim.scenarios.core.run import run

    scenario = paper_scenarios()[2]
    res = run(dataclasses.replace(load_scenario(scenario), duration_s=20.0), "rig")
    force = res.signals["tire_force_N"] + np.random.default_rng(7).normal(0.0, 100.0, res.signals["tire_force_N"].shape)
    d = tmp_path_factory.mktemp("wiring")
    _write_csv(d / "messung.csv", res.t_s, force, res.signals["profile_m"], res.signals["pan_m"])
    return {"csv": str(d / "messung.csv"), "scenario": str(scenario)}


def _identify(lab, pairs, out):
    return main(["identify", "--from-file", lab["csv"], "--pairs", pairs, "--out", str(out), "--quiet"])


def test_the_projects_own_pairs_are_identified(lab, tmp_path):
    assert _identify(lab, _pairs(), tmp_path / "ident") == 0
    assert (tmp_path / "ident" / "actuators.toml").exists()


def test_swapped_pairs_are_refused_naming_the_corner_and_nothing_is_written(lab, tmp_path, capsys, one_line):
    out = tmp_path / "ident"
    assert _identify(lab, _pairs(fl="Weg_FL:Soll_FL"), out) == 2
    line = one_line(capsys.readouterr().err)
    assert line.startswith("rigsim identify: error: --pairs fl:") or "--pairs fl:" in line, line
    assert "swapped" in line and "fl=Soll_FL:Weg_FL" in line, line
    assert not out.exists()


def _no_fit(monkeypatch):
    """Make any T_a fit or model calibration fail the test: a refusal must come before them."""
    from rigsim.scenarios.records import recorded
    from rigsim.scenarios.records.model import differential

    def never(*args, **kw):
        raise AssertionError("reached the identification or the calibration")

    monkeypatch.setattr(recorded, "fit_actuator", never)
    monkeypatch.setattr(differential, "correct_with_model", never)


@pytest.mark.parametrize("pairs", [_pairs(fl="Soll_FL:Soll_FL"), _pairs(fl="Soll_FL:soll_fl")])
def test_the_same_channel_twice_is_refused_before_any_fit(lab, tmp_path, capsys, one_line, monkeypatch, pairs):
    _no_fit(monkeypatch)
    out = tmp_path / "ident"
    assert _identify(lab, pairs, out) == 2
    line = one_line(capsys.readouterr().err)
    assert "--pairs fl: channel 'Soll_FL' is both the drive and the LVDT (the same channel twice)" in line, line
    assert not out.exists()


def test_the_same_channel_twice_is_refused_by_the_corrections_at_once(lab, tmp_path, capsys, one_line, monkeypatch):
    _no_fit(monkeypatch)
    out = tmp_path / "out.csv"
    model = ["correct", lab["csv"], "--model", lab["scenario"], "-o", str(out)]
    assert main(model + ["--pairs", _pairs(rr="Weg_RR:Weg_RR")]) == 2
    assert "--pairs rr: channel 'Weg_RR' is both the drive and the LVDT" in one_line(capsys.readouterr().err)
    assert main(["correct", lab["csv"], "--identify", "Soll_FL,Soll_FL", "--columns", "Fz_FL", "-o", str(out)]) == 2
    assert "--identify names channel 'Soll_FL' twice" in one_line(capsys.readouterr().err)
    assert not out.exists()


def test_swapped_pairs_are_refused_by_the_corrections_before_any_calibration(lab, tmp_path, capsys, one_line,
                                                                             monkeypatch):
    from rigsim.scenarios.records.model import differential

    monkeypatch.setattr(differential, "correct_with_model", lambda *a, **k: pytest.fail("calibrated"))
    out = tmp_path / "out.csv"
    assert main(["correct", lab["csv"], "--model", lab["scenario"], "--pairs", _pairs(rl="Weg_RL:Soll_RL"),
                 "-o", str(out), "--quiet"]) == 2
    line = one_line(capsys.readouterr().err)
    assert "--pairs rl:" in line and "swapped; give rl=Soll_RL:Weg_RL" in line, line
    # with its progress lines: the refusal comes before the calibration is announced
    assert main(["correct", lab["csv"], "--model", lab["scenario"], "--pairs", _pairs(rl="Weg_RL:Soll_RL"),
                 "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "swapped" in err.splitlines()[-1] and "calibrating" not in err, err
    assert main(["correct", lab["csv"], "--identify", "Weg_FL,Soll_FL", "--columns", "Fz_FL", "-o", str(out)]) == 2
    line = one_line(capsys.readouterr().err)
    assert "--identify Weg_FL,Soll_FL" in line and "swapped" in line, line
    assert not out.exists()


def test_the_wrong_corner_is_refused_naming_the_drive_its_lvdt_follows(lab, tmp_path, capsys, one_line):
    out = tmp_path / "ident"
    # the other side (independent track): this drive's LVDT in the pairs, or not
    assert _identify(lab, _pairs(fl="Soll_FL:Weg_FR"), out) == 2
    line = one_line(capsys.readouterr().err)
    assert ("--pairs fl: LVDT 'Weg_FR' follows fr's drive 'Soll_FR'" in line and "the wrong corner; give fl the LVDT "
            "of its own post, fl=Soll_FL:LVDT" in line), line
    assert _identify(lab, "fl=Soll_FL:Weg_FR", out) == 2
    line = one_line(capsys.readouterr().err)
    assert "--pairs fl:" in line and "what unrelated channels give" in line and "the wrong corner" in line, line
    # the other axle (the same track, 0.2 s later): its own drive is the one its LVDT follows best
    assert _identify(lab, _pairs(fl="Soll_FL:Weg_RL"), out) == 2
    line = one_line(capsys.readouterr().err)
    assert "--pairs fl: LVDT 'Weg_RL' follows rl's drive 'Soll_RL'" in line, line
    assert not out.exists()
