"""``benchmarks/mismatch_suite.py``'s table and goals from hand-made plant scores: the model error
column, and a fallback counted wrong where the model correction it refused (the hybrid, forced)
beats the linear correction on every wheel, whatever the differential form did."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rigsim.scenarios.studies.model_suite.goals import limit_evidence, rows_and_goals, share_interval
from rigsim.scenarios.studies.model_suite.mismatch_score import PlantScore


@pytest.fixture(scope="module")
def suite(load_benchmark):
    return load_benchmark("mismatch_suite")


def _score(name, method, linear, hybrid, forced, error):
    n = {"linear": np.full(4, linear), "hybrid": np.full(4, hybrid), "forced": np.full(4, forced)}
    n["delivered"] = n["hybrid"] if method == "model" else n["linear"]
    return PlantScore(name=name, plant={"payload_y_m": 0.1}, method=method, reason="" if method == "model" else "why",
                      nrmse=n, dlc_error={k: np.full(4, 0.005) for k in n}, floor=np.full(4, 0.1), wall_s=10.0,
                      cpu_s=20.0, scored_s=20.0, fit_nrmse=np.full(4, error), model_error=np.array([0.1, error, 0.1, 0.1]))


def test_a_fallback_is_wrong_where_the_refused_hybrid_was_better():
    scores = [_score("kept", "model", 0.2, 0.05, 0.3, 0.05),
              _score("right", "linear", 0.2, 0.25, 0.1, 0.3),  # the differential better, the hybrid not: right
              _score("wrong", "linear", 0.2, 0.1, 0.3, 0.18)]  # the hybrid better: wrong
    head, rows, text, numbers = rows_and_goals(scores, lambda s: s.name)
    assert numbers["wrong_fallbacks"] == ["wrong"] and numbers["fallbacks"] == 2
    col = head.index("model error (worst): windows / record")
    assert [r[col] for r in rows] == ["0.100", "0.300", "0.180"]
    # where the model ran on the whole record, its error there beside the windows'
    rows = rows_and_goals([dataclasses.replace(scores[0], record_error=np.array([0.1, 0.54, 0.1, 0.1]))],
                          lambda s: s.name)[1]
    assert rows[0][col] == "0.100 / 0.540"
    assert "where the forced model correction (hybrid) was better on every wheel: 1 (wrong)" in text


def test_the_limit_is_read_where_the_hybrid_stops_beating_the_linear_correction():
    """Wheel by wheel (each plant's wheels at model error 0.1 but one): the hybrid better at 0.05 and
    0.18, worse at 0.3 and on the 0.1 wheels of that plant: the ten wheels from 0.1 to 0.18 overlap;
    with that plant's wheels all at 0.3, a limit in [0.18, 0.3) separates them."""
    scores = [_score("kept", "model", 0.2, 0.05, 0.3, 0.05),
              _score("right", "linear", 0.2, 0.25, 0.1, 0.3),
              _score("wrong", "linear", 0.2, 0.1, 0.3, 0.18)]
    ev = limit_evidence(scores)
    assert ev == {"wheels": 12, "beats_up_to": 0.18, "loses_from": 0.1, "overlap": 10, "beats": 8}
    # "right"'s hybrid is worse on every wheel, three of them at model error 0.1: with all four at 0.3
    scores[1] = dataclasses.replace(scores[1], model_error=np.full(4, 0.3))
    ev = limit_evidence(scores)
    assert ev["beats_up_to"] == 0.18 and ev["loses_from"] == 0.3 and ev["overlap"] == 0
    text = rows_and_goals(scores, lambda s: s.name)[2]
    assert "the largest model error where it beat: 0.180, the smallest where it did not: 0.300: a limit between" in text


def test_the_page_is_written_again_from_a_runs_printed_json(suite, tmp_path):
    """``--from-json``: the scores a run printed (PlantScore.to_dict) come back as they were
    (from_dict), and the page written from them carries the run's command; an output without
    its JSON line is refused in one sentence."""
    import json

    scores = [_score("kept", "model", 0.2, 0.05, 0.3, 0.05), _score("wrong", "linear", 0.2, 0.1, 0.3, 0.18)]
    back = PlantScore.from_dict(json.loads(json.dumps(scores[1].to_dict())))
    assert back.to_dict() == scores[1].to_dict()
    framed = dataclasses.replace(scores[0], frame_hz=(6.1, 8.0))  # a calibration that fitted the frame
    assert PlantScore.from_dict(json.loads(json.dumps(framed.to_dict()))).frame_hz == (6.1, 8.0)
    out = tmp_path / "run.txt"
    run = {"lab": "ideal", "cab": "auto", "seed": 0, "duration_s": 30.0, "plants": [s.to_dict() for s in scores]}
    out.write_text("[ 1 s] progress\n" + json.dumps(run) + "\n", encoding="utf-8")
    assert suite.main(["--from-json", str(out), "--results", str(tmp_path)]) == 0
    # a run without channels: raw; another lab than the typical one: a page of its own
    page = (tmp_path / "mismatch_suite_raw_ideal.md").read_text(encoding="utf-8")
    assert "`python benchmarks/mismatch_suite.py --plants 2 --workers 2 --lab ideal --channels raw`" in page
    assert "| wrong |" in page and "lab measurement: ideal, channels raw" in page and "drift cut 0.7 Hz" in page
    run |= {"lab": "typical-no-drift", "channels": "aligned", "drift_cut_hz": 0.0, "command": "python x"}
    out.write_text(json.dumps(run) + "\n", encoding="utf-8")
    assert suite.main(["--from-json", str(out), "--results", str(tmp_path)]) == 0
    page = (tmp_path / "mismatch_suite_typical_no_drift_cut0.md").read_text(encoding="utf-8")
    assert "lab measurement: typical-no-drift, channels aligned" in page and "no drift cut" in page
    assert not (tmp_path / "mismatch_suite.md").exists()
    (tmp_path / "empty.txt").write_text("no json\n", encoding="utf-8")
    with pytest.raises(SystemExit, match="no JSON line"):
        suite.main(["--from-json", str(tmp_path / "empty.txt")])


def test_the_share_interval_resamples_whole_trucks():
    """All trucks good: the interval is [1, 1]; one truck of four bad on every wheel: the share is 0.75
    and the bootstrap over trucks spans it (a truck's wheels move together: with four trucks the
    share takes the values k / 4 only)."""
    good = _score("good", "model", 0.2, 0.02, 0.3, 0.05)  # NRMSE 0.02 over a floor of 0.1: good
    bad = dataclasses.replace(good, name="bad", dlc_error={k: np.full(4, 0.02) for k in good.dlc_error})
    assert share_interval([good] * 4) == (1.0, 1.0)
    lo, hi = share_interval([good, good, good, bad])
    assert lo < 0.75 < hi and {lo * 4, hi * 4} <= set(range(5))
