"""The load cells' mass as the lab's (:mod:`rigsim.scenarios.studies.model_suite.lab_mass`).

Reference: a corrected force linear in the cells' mass, ``c(m) = c0 - m b`` (what the hybrid is, W
held), scored directly at a mass between and beyond the three scanned ones with the same scoring
(:func:`rigsim.scenarios.studies.correction_score.score_correction`): the interpolation through the
three scores must give the direct score.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from rigsim.scenarios.core.files import to_json
from rigsim.scenarios.studies.correction_score import score_correction
from rigsim.scenarios.studies.model_suite import lab_mass
from rigsim.scenarios.studies.model_suite.mismatch_score import MASS_SCAN_KG, PlantScore

FS = 1000.0


def _signals(seed: int):
    rng = np.random.default_rng(seed)
    n = 20000
    t = np.arange(n) / FS
    road = 40e3 + 3e3 * np.sin(2 * np.pi * 2.1 * t)[:, None] + 800.0 * rng.standard_normal((n, 4))
    b = 60.0 * np.sin(2 * np.pi * 11.0 * t)[:, None] + 40.0 * rng.standard_normal((n, 4))  # N per kg
    c0 = road - 5.0 * b + 150.0 * rng.standard_normal((n, 4))  # right at -5 kg, up to noise
    return road, c0, b


def _score(seed: int, fitted_kg: float):
    road, c0, b = _signals(seed)
    at = {m: score_correction(c0 - m * b, road, FS) for m in fitted_kg + np.asarray(MASS_SCAN_KG)}
    own = at[fitted_kg]
    n = {"linear": np.full(4, 0.5), "hybrid": np.asarray(own["nrmse"]), "delivered": np.asarray(own["nrmse"])}
    d = {"linear": np.full(4, 0.03), "hybrid": np.asarray(own["dlc_error"]), "delivered": np.asarray(own["dlc_error"])}
    scan = {"mass_kg": np.array(list(at)), "dlc_error": np.array([v["dlc_error"] for v in at.values()]),
            "nrmse": np.array([v["nrmse"] for v in at.values()])}
    score = PlantScore(name=f"t{seed}", plant={}, method="model", reason="", nrmse=n, dlc_error=d,
                       floor=np.full(4, 0.4), wall_s=1.0, cpu_s=1.0, scored_s=20.0, cell_mass_kg=fitted_kg,
                       mass_scan=scan)
    return score, (road, c0, b)


@pytest.mark.parametrize("mass", [-7.5, -14.0, 4.0])
def test_a_score_at_another_mass_is_the_direct_score(mass):
    score, (road, c0, b) = _score(1, -9.0)
    direct = score_correction(c0 - mass * b, road, FS)
    dlc, nrmse = lab_mass.hybrid_at_mass(score, mass)
    np.testing.assert_allclose(dlc, direct["dlc_error"], atol=2e-5)
    np.testing.assert_allclose(nrmse, direct["nrmse"], rtol=1e-6)


def test_the_lab_mass_is_the_median_and_scores_survive_json():
    scores = [_score(s, m)[0] for s, m in zip(range(3), (-9.0, -2.0, -6.5))]
    assert lab_mass.lab_mass_kg(scores) == -6.5
    back = [PlantScore.from_dict(json.loads(to_json(s.to_dict()))) for s in scores]
    assert [s.cell_mass_kg for s in back] == [-9.0, -2.0, -6.5]
    np.testing.assert_array_equal(back[0].mass_scan["nrmse"], scores[0].mass_scan["nrmse"])
    # at the signals' own mass (-5 kg) every wheel is within 1 % at NRMSE far below half the linear's
    assert lab_mass.share_at_mass(back, -5.0) == 1.0
    far = lab_mass.share_at_mass(back, 40.0)  # 45 kg off: every wheel's DLC well past 1 %
    assert far == 0.0
    text = lab_mass.mass_text(back, -7.5)
    assert "median -6.5 kg" in text and "the chain's own -7.5 kg" in text and "-9.0 to -2.0 kg" in text
