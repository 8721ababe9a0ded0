"""The mismatch suite's plant trucks: seeded, inside their data file's ranges, always valid trucks.

Reference: the data file itself, read here with tomllib (not through the module), and the bounds
rigsim.mjcf.variant.TruckVariant and rigsim.mjcf.stations accept.
"""

from __future__ import annotations

import importlib.resources
import tomllib

import numpy as np
import pytest

from rigsim.mjcf.build import nominal_values
from rigsim.mjcf.names import CORNERS
from rigsim.mjcf.stations import STATION_FACTORS, station_factor_field
from rigsim.mjcf.variant import BOUNDS, TruckVariant
from rigsim.scenarios.studies.model_suite.mismatch import _range, draw_plant, mismatch_plants
from rigsim.scenarios.studies.suites import pick_cases


@pytest.fixture(scope="module")
def doc():
    path = importlib.resources.files("rigsim.scenarios").joinpath("data", "suites", "mismatch_plants.toml")
    return tomllib.loads(path.read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def cases():
    return pick_cases("generalization", None, 30.0)


def test_the_same_seed_gives_the_same_plants_and_another_seed_others(cases):
    a, b, c = mismatch_plants(cases[:4], 0), mismatch_plants(cases[:4], 0), mismatch_plants(cases[:4], 1)
    assert a == b
    assert a != c
    assert a[0] != a[1]


def test_every_drawn_value_lies_in_its_range_and_every_plant_is_a_valid_truck(doc, cases):
    nominal = nominal_values()
    plants = mismatch_plants(cases, 0)
    assert len(plants) == 24
    for case, plant in zip(cases, plants):
        payload = case.get("vehicle", {}).get("payload_kg", nominal["payload_kg"])
        for field, (lo, hi) in doc["factors"].items():
            base = payload if field == "payload_kg" else nominal[field]
            assert base * lo - 1e-9 <= plant[field] <= base * hi + 1e-9, field
        for field, (lo, hi) in doc["offsets"].items():
            assert nominal[field] + lo - 1e-12 <= plant[field] <= nominal[field] + hi + 1e-12, field
        for quantity, (lo, hi) in doc["stations"].items():
            for c in CORNERS:
                assert lo <= plant[station_factor_field(quantity, c)] <= hi
        for field, (lo, hi) in doc["values"].items():
            assert lo <= plant[field] <= hi
        TruckVariant(**plant)


def test_the_occasional_features_appear_in_some_plants_not_all(doc, cases):
    plants = mismatch_plants(cases, 0)
    for key, table in doc["sometimes"].items():
        field = next(k for k in table if k != "probability")
        n = sum(field in p for p in plants)
        assert 0 < n < len(plants), key  # p = 1/2 over 24 plants: 0 or 24 has probability 1e-7


def test_the_files_ranges_lie_inside_what_a_truck_may_be(doc):
    """A draw can never be refused: each range inside TruckVariant's bounds (on the XML's values)."""
    nominal = nominal_values()
    for field, (lo, hi) in doc["factors"].items():
        if field in BOUNDS and field != "payload_kg":
            b_lo, b_hi = BOUNDS[field][:2]
            assert b_lo <= nominal[field] * lo and nominal[field] * hi <= b_hi, field
    for quantity, (lo, hi) in doc["stations"].items():
        b_lo, b_hi = STATION_FACTORS[quantity][:2]
        assert b_lo <= lo and hi <= b_hi, quantity


def test_a_draw_is_one_per_generator_state():
    rng1, rng2 = np.random.default_rng(5), np.random.default_rng(5)
    assert draw_plant(3000.0, rng1) == draw_plant(3000.0, rng2)


@pytest.mark.parametrize("bad", [[1.0], [2.0, 1.0], ["a", 1.0], 3.0, [True, 1.0]])
def test_a_malformed_range_is_refused_with_its_place(bad):
    with pytest.raises(ValueError, match=r"mismatch_plants.toml: stations.spring_rate must be \[low, high\]"):
        _range("stations.spring_rate", bad)
