"""``rigsim paper --model``: the third method's table and paper.json entry (the correction itself
is tested in tests/scenarios/records/test_model_correction.py; a whole paper run with --model takes minutes)."""

from __future__ import annotations

import json

import numpy as np

from rigsim.scenarios.core.files import to_json
from rigsim.scenarios.records.model.result import LINEAR, MODEL, Calibration, ModelCorrection
from rigsim.scenarios.studies.paper.model import ModelScore, model_table


def _calibration(fit):
    return Calibration(names=("payload_kg",), units=("kg",), initial=(3000.0,), fitted=(3600.0,), sigma=(5.0,),
                       sigma_robust=(9.0,), fixed={}, fit_nrmse=tuple(fit), initial_nrmse=(0.5,) * 4,
                       windows_s=((2.0, 6.0),), weighted=True, evaluations=30, converged=True, message="ok",
                       wall_time_s=60.0)


def _scores():
    used = ModelScore(
        case="paper-medium-72kmh-6360kg",
        correction=ModelCorrection(method=MODEL, reason="", calibration=_calibration([0.04, 0.05, 0.03, 0.03]),
                                   corrected_N=np.zeros((10, 4)), settled=np.ones(10, bool), wall_time_s=75.0),
        figures={"nrmse": np.array([0.01, 0.012, 0.008, 0.01]), "dlc": np.array([0.09, 0.09, 0.11, 0.11]),
                 "dlc_road": np.array([0.0898, 0.0902, 0.11, 0.1099]), "dlc_error": np.array([0.002, -0.002, 0.0, 0.001]),
                 "scored_s": np.asarray(50.0)},
        linear_nrmse=np.array([0.14, 0.14, 0.18, 0.19]))
    kept = ModelScore(case="paper-high-48kmh-3640kg",
                      correction=ModelCorrection(method=LINEAR, reason="the calibrated model misses the force.",
                                                 calibration=_calibration([0.9] * 4), wall_time_s=40.0),
                      figures=None, linear_nrmse=np.array([0.12] * 4))
    return used, kept


def test_the_third_methods_table_shows_the_model_or_why_not():
    used, kept = _scores()
    text = model_table([used, kept])
    row = next(line for line in text.splitlines() if line.startswith(used.case))
    # means over the wheels: NRMSE 0.010, linear 0.1625 -> "0.163", fit 0.0375 -> "0.037" or "0.038"
    assert "0.010" in row and "0.163" in row and "+0.0%" in row
    # no noise estimate in this calibration: the model error is the worst fit NRMSE itself, 0.050; the cab held
    assert row.split()[-3:] == ["0.050", "held", "75"], row
    assert f"{kept.case:28s} linear correction kept: the calibrated model misses the force." in text
    assert used.used and not kept.used


def test_paper_json_entry_holds_means_wheels_and_the_calibration():
    used, kept = _scores()
    js = json.loads(to_json(used))
    assert js["method"] == "model" and abs(js["mean"]["nrmse"] - 0.0100) < 1e-9
    assert js["wheels"]["dlc_error"] == [0.002, -0.002, 0.0, 0.001]
    assert js["correction"]["calibration"]["fitted"] == [3600.0]
    js2 = json.loads(to_json(kept))
    assert js2["method"] == "linear" and "mean" not in js2 and js2["reason"].endswith("force.")


def test_paper_offers_the_model_flag():
    import argparse

    from rigsim.scenarios.studies.paper import command

    p = argparse.ArgumentParser()
    command.add_parser(p.add_subparsers())
    args = p.parse_args(["paper", "--out", "x", "--model"])
    assert args.model is True
    assert p.parse_args(["paper", "--out", "x"]).model is False


def test_the_drift_cut_follows_the_cases_lab():
    """A case whose lab chain has no load-cell drift (the paper's scenarios: white noise only) is
    corrected without the drift cut, as a lab that knows its cells passes --drift-cut-hz 0; a lab
    whose cells drift (TYPICAL_LAB: 50 N below 1 Hz) gets the default corner."""
    import dataclasses

    from rigsim.correction.output.denoise import DRIFT_HZ
    from rigsim.scenarios.core.config import load_scenario, paper_scenarios
    from rigsim.scenarios.core.lab import TYPICAL_LAB, LabChain
    from rigsim.scenarios.studies.paper.model import drift_corner

    assert drift_corner(load_scenario(paper_scenarios()[0]).lab) is None
    assert drift_corner(LabChain()) is None
    assert drift_corner(TYPICAL_LAB) == DRIFT_HZ
    assert drift_corner(dataclasses.replace(LabChain(), drift_noise_N=5.0)) == DRIFT_HZ
