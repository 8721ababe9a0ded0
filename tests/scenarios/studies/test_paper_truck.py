"""``rigsim paper --truck TRUCK.toml``: the paper's cases on a lab's own truck.

References: the truck file's [vehicle] (every field but its payload reaches each case), each case's
own payload and road (kept), and the compiled wheelbase the road's rear delay follows."""

from __future__ import annotations

import pathlib

from rigsim.scenarios.core.config import load_scenario, paper_scenarios
from rigsim.scenarios.core.rig import Rig
from rigsim.scenarios.studies.paper.command import _truck
from rigsim.scenarios.studies.paper.compute import case_scenario

TRACTOR = pathlib.Path(__file__).resolve().parents[3] / "scenarios" / "data" / "trucks" / "tractor_air.toml"


def test_the_truck_file_replaces_the_cases_truck_but_not_their_payload_or_road():
    truck = _truck(str(TRACTOR))
    assert "payload_kg" not in truck and truck["wheelbase_m"] == 3.7 and truck["suspension_rear"] == "air"
    for path in paper_scenarios("design"):
        case, on_truck = load_scenario(path), case_scenario(path, 12.0, truck)
        assert on_truck.vehicle.payload_kg == case.vehicle.payload_kg
        assert on_truck.road == case.road and on_truck.speed_kmh == case.speed_kmh and on_truck.duration_s == 12.0
        assert on_truck.vehicle.rear_tires == "single"
        assert Rig(on_truck, hydraulic=False).wheelbase_m == 3.7  # the rear pans' delay follows it
    assert _truck(None) is None and case_scenario(paper_scenarios("design")[0], None, None) == \
        load_scenario(paper_scenarios("design")[0])
