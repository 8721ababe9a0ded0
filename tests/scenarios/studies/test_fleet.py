"""The fleet suite's trucks (scenarios/studies/model_suite/fleet.py, scenarios/data/suites/fleet.toml).

References: the data file's own ranges (every drawn value inside them), the spec sheet's fields
(:data:`rigsim.mjcf.description.DESCRIPTION_FIELDS`, nothing else a lab would not know), the plant's
structure (every plant carries what the model family lacks), the determinism of a seed.
"""

from __future__ import annotations

import dataclasses

import pytest

from rigsim.mjcf.description import DESCRIPTION_FIELDS
from rigsim.mjcf.standing import check_stands
from rigsim.mjcf.variant import TruckVariant
from rigsim.scenarios.core.lab import TYPICAL_LAB
from rigsim.scenarios.records.model.first_guess import description
from rigsim.scenarios.studies.model_suite.fleet import fleet_ranges, fleet_trucks, lacks

N = 8


@pytest.fixture(scope="module")
def fleet():
    return fleet_trucks(N, 0)


def test_a_seed_gives_one_fleet_and_another_seed_another(fleet):
    assert fleet_trucks(3, 0) == fleet[:3]
    assert [t.plant for t in fleet_trucks(3, 1)] != [t.plant for t in fleet[:3]]


def test_the_spec_sheet_is_the_description_only_and_the_model_reads_it(fleet):
    for truck in fleet:
        assert set(truck.spec) <= set(DESCRIPTION_FIELDS)
        assert {"wheelbase_m", "rear_tires", "suspension_front", "suspension_rear"} <= set(truck.spec)
        spec_sc = truck.scenario(20.0, truck="spec")
        assert description(spec_sc) == TruckVariant(**truck.spec)
        assert all(truck.plant[k] == v for k, v in truck.spec.items())  # the plant is that truck


def test_every_value_lies_in_the_files_ranges(fleet):
    spec = fleet_ranges()["spec"]
    for truck in fleet:
        lo, hi = spec["values"]["wheelbase_m"]
        assert lo <= truck.spec["wheelbase_m"] <= hi
        by = spec["by_word"]["rear_tires"][truck.spec["rear_tires"]]
        assert by["track_rear_m"][0] <= truck.spec["track_rear_m"] <= by["track_rear_m"][1]
        for axle in ("front", "rear"):
            kind = truck.spec[f"suspension_{axle}"]
            lo, hi = spec["by_word"][f"suspension_{axle}"][kind][f"spring_rate_{axle}_N_per_m"]
            assert lo <= truck.spec[f"spring_rate_{axle}_N_per_m"] <= hi


def test_every_plant_stands_and_carries_what_its_model_lacks(fleet):
    structure = fleet_ranges()["structure"]["values"]
    for truck in fleet:
        plant = TruckVariant(**truck.plant)
        check_stands(plant)
        for field, (lo, hi) in structure.items():
            assert lo <= getattr(plant, field) <= hi
        # the frame unlike the model's (cut at mid-wheelbase, damped 0.04): its cut and damping drawn, and said
        for field, (lo, hi) in fleet_ranges()["structure"]["frame"].items():
            assert lo <= getattr(plant, field) <= hi
        assert f"cut at {plant.frame_hinge_share:.2f} of the wheelbase" in lacks(truck)
        assert f"rebound x{plant.damper_rebound_ratio:.2f}" in lacks(truck)  # the model's dampers start at x2
        digressive = plant.damper_digressive_ratio is not None
        worn = all(getattr(plant, f"spring_damping_factor_{c}") <= 0.5 for c in ("fl", "fr", "rl", "rr"))
        assert digressive or worn
        for axle in ("front", "rear"):  # an air axle's bushings rub; the model's air spring has no friction
            if truck.spec[f"suspension_{axle}"] == "air":
                assert 50.0 <= getattr(plant, f"spring_friction_{axle}_N") <= 300.0


def test_the_lab_chain_is_off_its_nominal_settings_within_tolerance(fleet):
    tol = fleet_ranges()["lab"]
    for truck in fleet:
        for field, limit in (("force_filter_hz", tol["corner_tolerance"]), ("lvdt_filter_hz", tol["corner_tolerance"]),
                             ("force_delay_s", tol["delay_tolerance"])):
            nominal = getattr(TYPICAL_LAB, field)
            assert abs(getattr(truck.lab, field) / nominal - 1) <= limit
        assert dataclasses.replace(truck.lab, force_filter_hz=TYPICAL_LAB.force_filter_hz,
                                   lvdt_filter_hz=TYPICAL_LAB.lvdt_filter_hz,
                                   force_delay_s=TYPICAL_LAB.force_delay_s) == TYPICAL_LAB
    assert len({t.lab.force_filter_hz for t in fleet}) == N  # each truck's chain its own


def test_a_sweep_runs_over_the_spec_sheets_words_and_refuses_a_wrong_one():
    """Sweep axes over the description's word fields: each case's truck has its word; a word the field
    does not take is refused naming the case and the field, before anything runs."""
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.studies.sweep.grid import parse_grid

    doc = {"sweep": {"name": "kinds"},
           "base": {"name": "kinds", "speed_kmh": 60.0, "duration_s": 10.0, "road": {"roughness": "C"},
                    "vehicle": {"payload_kg": 5000.0, "wheelbase_m": 4.2}},
           "axes": {"vehicle": {"suspension_rear": ["leaf", "air"], "rear_tires": ["dual", "single"]}}}
    grid = parse_grid(doc)
    kinds = {(c.scenario.vehicle.suspension_rear, c.scenario.vehicle.rear_tires) for c in grid.cases}
    assert kinds == {("leaf", "dual"), ("leaf", "single"), ("air", "dual"), ("air", "single")}
    assert all(c.scenario.vehicle.wheelbase_m == 4.2 for c in grid.cases)
    doc["axes"]["vehicle"]["suspension_rear"] = ["leaf", "coil"]
    with pytest.raises(ScenarioError, match=r"vehicle.suspension_rear must be \"leaf\" or \"air\", got 'coil'"):
        parse_grid(doc)
