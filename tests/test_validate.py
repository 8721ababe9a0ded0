"""scenarios.validate: route 2's linearization, the rig with an arbitrary drive, and the
``rigsim validate`` command on a short run.

Expected values come from the controller's structure (integral action: static gain 1), from
the paper's Table 1 ordering (a rig follows the road only partly, so its DLC is lower), from
the static rest state, or from the command's own output files (the JSON must say what it
prints) -- never from a previous run.
"""

import argparse
import contextlib
import io
import json
import math
import re

import numpy as np
import pytest

from scenarios import validate as v
from scenarios.config import ScenarioError, load_scenario


@pytest.fixture(scope="module")
def plant():
    return v.linearize_plant(load_scenario(v.table1_scenario_path()))


def test_route2_static_gain_is_one_and_the_plant_is_stable(plant):
    # PI position loop (Ti = 1 s): zero steady-state error on every wheel whatever its load, so
    # x_a / x_ref -> 1 on the diagonal and -> 0 across wheels as f -> 0.
    h = plant.frequency_response([1e-4])[0]
    assert np.allclose(np.diag(h), 1.0, atol=1e-3)
    assert np.max(np.abs(h - np.diag(np.diag(h)))) < 1e-3
    assert np.max(np.abs(np.linalg.eigvals(plant.a))) < 1.0
    # 1 % above 0.1 Hz already (integrator pole at ~-1 rad/s cancelled by the PI zero)
    h01 = plant.frequency_response([0.1])[0]
    assert np.allclose(np.abs(np.diag(h01)), 1.0, atol=0.02)


def test_route2_sees_each_station_load_and_tire(plant):
    # Front stations carry one 0.9 MN/m tire, rear ones a 1.8 MN/m dual pair (mjcf/README.md);
    # the static actuator loads add up to the truck's weight plus four pans' weight.
    assert np.allclose(plant.kt_N_per_m, [0.9e6, 0.9e6, 1.8e6, 1.8e6])
    truck_kg = 5200 + 3640 + 700 + 1200
    assert plant.load_N.sum() == pytest.approx((truck_kg + 4 * 500) * 9.81, rel=1e-3)


def test_run_rig_drive_holds_rest_and_checks_its_drive():
    sc = load_scenario(v.table1_scenario_path())
    rec = v.run_rig_drive(sc, np.zeros((1001, 4)), record_every=10)
    assert rec["x_a_m"].shape == (101, 4) and rec["t_s"][-1] == pytest.approx(0.1)
    assert np.max(np.abs(rec["x_a_m"])) < 1e-5  # static rest: the pans stay at mid-stroke
    with pytest.raises(ValueError, match="shape"):
        v.run_rig_drive(sc, np.zeros((10, 3)))


def test_identification_drive_is_road_like_and_independent():
    z = v.identification_drive(60.0, 1e-3, seed=1)
    assert z.shape == (60001, 4)
    assert np.allclose(z[2000:].std(axis=0), v.IDENT_RMS_M, rtol=0.1)
    assert np.max(np.abs(z)) < 0.076  # inside the 15.2 cm stroke
    c = np.corrcoef(z.T)
    assert np.max(np.abs(c - np.eye(4))) < 0.1


def _parse(argv):
    p = argparse.ArgumentParser()
    v.add_parser(p.add_subparsers())
    return p.parse_args(["validate"] + argv)


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("validate")
    args = _parse(["--out", str(out), "--duration-s", "3", "--ident-duration-s", "8", "--quiet",
                   "--rrd", str(out / "validate.rrd")])
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = args.func(args)
    assert rc == 0
    return out, buf.getvalue(), json.loads((out / "validate.json").read_text())


def _lookup(js, dotted):
    node = js
    for part in dotted.split("."):
        node = node[part]
    return node


def test_validate_json_holds_every_required_number(short_run):
    _, _, js = short_run
    for key in ("step_max_error_small_pct", "step_max_error_large_pct", "step_max_error_small_mm",
                "step_max_error_large_mm"):
        assert math.isfinite(js[key]) and js[key] >= 0
    for route in ("route1", "route2", "route3"):
        assert set(js["bandwidth_hz"][route]) == {"fl", "fr", "rl", "rr"}
        assert all(1.0 < x < 50.0 for x in js["bandwidth_hz"][route].values())
    for route in ("route1", "route3"):
        assert math.isfinite(js["frf_max_error_db"][route]) and math.isfinite(js["frf_max_error_deg"][route])
    for key in ("road_test", "rig_test", "linearized_model", "linearized_model_eq4"):
        assert 0.0 < js["table1"][key] < 1.0
    # The paper's Table 1, typed in from the paper.
    assert js["table1"]["paper"] == {"road_test": 0.2105, "rig_test": 0.1754, "nonlinear_model": 0.1748,
                                     "linearized_model": 0.1724}


def test_validate_json_matches_the_numbers_printed(short_run):
    _, printed, js = short_run
    lines = [ln for ln in printed.splitlines() if " = " in ln]
    assert len(lines) >= 20
    for line in lines:
        key, value = line.split(" = ")
        expected = _lookup(js, key)
        if isinstance(expected, bool):
            assert value == str(expected), key
        else:
            assert float(value) == pytest.approx(expected, rel=1e-5), key


def test_recording_of_the_table1_runs_is_written(short_run):
    """--rrd writes one recording of the Table 1 road and rig runs (read back: entity paths)."""
    out, printed, _ = short_run
    path = out / "validate.rrd"
    assert path.stat().st_size > 100_000
    assert "wrote recording" in printed
    from tests.test_recording import read_rrd

    recordings = read_rrd(path)
    assert len(recordings) == 1
    (entities,) = recordings.values()
    assert any(p.startswith("/rig/fl") for p in entities)
    assert any(p.startswith("/scene/chassis") for p in entities)


def test_table1_ordering_road_above_rig(short_run):
    # Paper, Table 1: the rig test's DLC is below the road test's (the actuators cannot follow
    # the profile's high frequencies), and the linearized model lands near the rig, not the road.
    _, _, js = short_run
    t1 = js["table1"]
    assert t1["road_test"] > t1["rig_test"]
    assert abs(t1["linearized_model"] - t1["rig_test"]) < abs(t1["road_test"] - t1["rig_test"])
    assert js["goals"]["table1_road_above_rig"] is True


def test_report_links_only_files_that_exist(short_run):
    out, _, _ = short_run
    report = (out / "report.md").read_text()
    links = re.findall(r"\]\(([^)]+)\)", report)
    assert "validate.json" in links and any(link.endswith(".png") for link in links)
    for link in links:
        assert (out / link).is_file(), link
    assert not list(out.glob("*.tmp")) and not list(out.glob(".*.tmp"))


@pytest.mark.parametrize("bad", ["0", "-5", "nan", "4000"])
def test_bad_durations_are_refused_before_anything_runs(tmp_path, bad):
    args = _parse(["--out", str(tmp_path / "x"), "--duration-s", bad, "--quiet"])
    with pytest.raises(ScenarioError, match="duration"):
        args.func(args)
    assert not (tmp_path / "x").exists()
