"""benchmarks/model_correction.py's bookkeeping: which cases and plants it runs, and how it counts the goals.

No simulation runs here (the benchmark's numbers are its own, docs/model_correction.md); the
shares below are counted by hand from the synthetic rows.
"""

from __future__ import annotations

import importlib.util
import pathlib

import pytest

from mjcf.names import CORNERS

_PATH = pathlib.Path(__file__).resolve().parents[1] / "benchmarks" / "model_correction.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("benchmark_model_correction", _PATH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _row(mismatch, floor, linear, linear_dlc, model=None, model_dlc=None, cpu=10.0):
    wheels = {"floor": floor, "linear": linear, "linear_dlc_error": linear_dlc}
    if model is not None:
        wheels |= {"model": model, "model_dlc_error": model_dlc}
    return {"case": "c", "mismatch": mismatch, "method": "model" if model else "linear",
            "reason": "" if model else "fit.", "cpu_s": cpu, "wall_s": cpu,
            "wheels": {k: dict(zip(CORNERS, v)) for k, v in wheels.items()}}


def test_summary_counts_what_the_method_delivers(bench):
    rows = [
        # family: model / floor 0.4, 0.6, 0.2, 0.1 -> 3 of 4 at <= 0.5; |DLC| 0.5 %, 2 %, 0.1 %, 0.9 % -> 3 of 4
        _row("off", [0.1] * 4, [0.2] * 4, [0.05] * 4, [0.04, 0.06, 0.02, 0.01], [0.005, -0.02, 0.001, -0.009], 20.0),
        # cab on, model: 0.9, 1.2 x floor; the fallback row scores its linear correction (1.5 x floor)
        _row("on", [0.1] * 4, [0.2] * 4, [0.0] * 4, [0.09, 0.12, 0.09, 0.09], [0.0, 0.03, 0.0, 0.0], 30.0),
        _row("on", [0.1] * 4, [0.15] * 4, [0.008, -0.02, 0.0, 0.0], cpu=40.0),
    ]
    s = bench.summary(rows)
    assert s["off"]["floor_goal_share"] == 0.75 and s["off"]["dlc_within_1pct_share"] == 0.75
    assert s["off"]["fallbacks"] == 0 and s["off"]["worst_ratio"] == pytest.approx(0.6)
    assert s["on"]["wheels"] == 8 and s["on"]["fallbacks"] == 1
    assert s["on"]["floor_goal_share"] == 3 / 8  # 0.9 x on three wheels of the model row; 1.5 x on the fallback's
    assert s["on"]["worst_ratio"] == pytest.approx(1.5)
    assert s["on"]["dlc_within_1pct_share"] == 6 / 8 and s["on"]["worst_dlc_error"] == pytest.approx(0.03)
    assert s["cpu_s"] == {"median": 30.0, "max": 40.0}


def test_suite_cases_and_their_plants(bench):
    (empty,) = bench.pick("generalization", ["gen03"], 20.0)
    assert empty["vehicle"]["payload_kg"] == 0.0 and len(bench.pick("generalization", None, 30.0)) == 24
    with pytest.raises(SystemExit):
        bench.pick("generalization", ["gen0"], 30.0)  # gen00 ... gen09: not unique
    nominal = bench.xml_nominal()
    family = bench.plant_scenario(empty, 20.0, cab=False)
    assert family.duration_s == 20.0 and family.vehicle.payload_kg == 0.0  # -5 % of the case's own payload
    assert family.vehicle.tire_stiffness_front_N_per_m == pytest.approx(1.1 * nominal["tire_stiffness_front_N_per_m"])
    assert family.vehicle.cab_mount_hz is None
    assert bench.plant_scenario(empty, 20.0, cab=True).vehicle.cab_mount_hz == bench.CAB_HZ
    (laden,) = bench.pick("generalization", ["gen00"], 20.0)
    assert bench.plant_scenario(laden, 20.0, cab=False).vehicle.payload_kg == pytest.approx(0.95 * 4500.0)
