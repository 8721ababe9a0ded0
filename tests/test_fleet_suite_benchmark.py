"""``benchmarks/fleet_suite.py --page``: the parts of one draw (``--part K/N``) joined into that draw,
from hand-made plant scores. Reference: the joined draw holds each truck once, in the draw's order,
and its confidence interval is the one computed over all of its trucks at once
(:func:`rigsim.scenarios.studies.model_suite.goals.share_interval`), not either part's."""

from __future__ import annotations

import argparse
import json

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
