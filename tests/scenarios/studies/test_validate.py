"""rigsim.scenarios.studies.validate: route 2 (the Rig's linearization), route 3's H1 estimate, the
package's structure, and the ``rigsim validate`` command on a short run.

Expected values come from the controller's structure (integral action: static gain 1), from
a known linear system (the H1 estimate of a filtered random signal), from the paper's Table 1
ordering (a rig follows the road only partly, so its DLC is lower), from the static rest
state, from the goals the code states (``settings.GOAL_FRF_DB``, ``GOAL_FRF_DEG``), or from the
command's own output files (the JSON must say what it prints).
"""

import argparse
import ast
import contextlib
import io
import json
import math
import pathlib
import re

import numpy as np
import pytest
from scipy import signal

from rigsim.scenarios.cli.main import main
from rigsim.scenarios.core.config import ScenarioError, load_scenario
from rigsim.scenarios.core.drive import IDENT_RMS_M, identification_drive
from rigsim.scenarios.core.files import to_json
from rigsim.scenarios.core.rig import Rig, RigRecord
from rigsim.scenarios.studies.validate import command, report, routes, settings

PACKAGE = pathlib.Path(settings.__file__).parent


@pytest.fixture(scope="module")
def plant():
    return Rig(load_scenario(settings.table1_scenario_path())).linearize()


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


def test_identification_drive_is_road_like_and_independent():
    z = identification_drive(60.0, 1e-3, seed=1).z_m
    assert z.shape == (60001, 4)
    assert np.allclose(z[2000:].std(axis=0), IDENT_RMS_M, rtol=0.1)
    assert np.max(np.abs(z)) < 0.076  # inside the 15.2 cm stroke
    c = np.corrcoef(z.T)
    assert np.max(np.abs(c - np.eye(4))) < 0.1


def test_identify_recovers_a_known_linear_system():
    # Each "pan" is its own drive through a known first-order low-pass (10 Hz, at 1 kHz), and
    # pan fl also sees 0.3 x drive fr through a 5 Hz second-order low-pass: the H1 estimate
    # (both Welch resolutions spliced: 67 s after the 3 s skip) must be that 4 x 4 response
    # (scipy.signal.freqz) [output, input], with coherence ~1.
    fs, n = 1000.0, 70001
    rng = np.random.default_rng(3)
    u = rng.standard_normal((n, 4))
    b, a = signal.butter(1, 10.0, fs=fs)
    b2, a2 = signal.butter(2, 5.0, fs=fs)
    y = signal.lfilter(b, a, u, axis=0)
    y[:, 0] += 0.3 * signal.lfilter(b2, a2, u[:, 1])
    rec = RigRecord(t_s=np.arange(n) / fs, x_ref_m=u, pan_m=y, tire_force_N=np.zeros((n, 4)))
    est = routes.identify(rec)
    assert est.nperseg == {"high": 4000, "low": 16000} and est.fs_hz == pytest.approx(fs)
    band = (est.f_hz >= 0.1) & (est.f_hz <= 30.0)
    f = est.f_hz[band]
    ref = np.zeros((f.size, 4, 4), complex)
    ref[:, np.arange(4), np.arange(4)] = signal.freqz(b, a, worN=f, fs=fs)[1][:, None]
    ref[:, 0, 1] = 0.3 * signal.freqz(b2, a2, worN=f, fs=fs)[1]
    assert np.max(np.abs(est.h[band] - ref)) < 0.02  # (|H| <= 1) measured 0.009
    assert np.min(est.coherence[band]) > 0.99


def test_no_module_imports_a_private_name_of_another():
    for path in sorted(PACKAGE.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom):
                private = [a.name for a in node.names if a.name.startswith("_")]
                assert not private, f"{path.name} imports {private} from {node.module}"


def _parse(argv):
    p = argparse.ArgumentParser()
    command.add_parser(p.add_subparsers())
    return p.parse_args(["validate"] + argv)


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    """The command on a 3 s Table 1 / 8 s identification run, with the result object it wrote."""
    out = tmp_path_factory.mktemp("validate")
    args = _parse(["--out", str(out), "--duration-s", "3", "--ident-duration-s", "8", "--quiet",
                   "--rrd", str(out / "validate.rrd")])
    kept = []

    def keep(**kwargs):
        kept.append(command_validate(**kwargs))
        return kept[-1]

    command_validate = command.validate
    buf = io.StringIO()
    with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(buf):
        mp.setattr(command, "validate", keep)
        rc = args.func(args)
    assert rc == 0 and len(kept) == 1
    return out, buf.getvalue(), json.loads((out / "validate.json").read_text()), kept[0]


def _lookup(js, dotted):
    node = js
    for part in dotted.split("."):
        node = node[part]
    return node


def test_validate_json_holds_every_required_number(short_run):
    _, _, js, _ = short_run
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


def test_validate_json_is_the_result_through_to_json(short_run):
    out, _, _, result = short_run
    text = (out / "validate.json").read_text()
    assert text == to_json(result)

    def refuse(token):
        raise AssertionError(f"{token} in validate.json")

    json.loads(text, parse_constant=refuse)  # valid JSON without NaN / Infinity tokens


def test_route3_is_within_loose_multiples_of_the_goal(short_run):
    # settings.GOAL_FRF_DB = 0.5 dB, GOAL_FRF_DEG = 5 deg (route 3 against route 2 up to 30 Hz,
    # coherence > 0.95) are narrowly missed by a 60 s run (measured: 0.54 dB, 5.6 deg); this 8 s
    # record measures ~1.2 dB / 6.1 deg (more estimation variance). Bounds: 3x the dB goal and 2x
    # the deg goal. A 1 ms (one sample) misalignment of x_a gives 11-16 deg, a +10 % gain error
    # 2.0 dB, swapped wheels 47 dB: each fails here.
    _, _, js, _ = short_run
    assert js["frf_max_error_db"]["route3"] <= 3 * settings.GOAL_FRF_DB
    assert js["frf_max_error_deg"]["route3"] <= 2 * settings.GOAL_FRF_DEG
    # eq. 4 (route 1) is the model under test: it departs further than the identified route.
    assert js["frf_max_error_deg"]["route1"] > js["frf_max_error_deg"]["route3"]


def test_step_errors_are_bounded_and_route2_beats_eq4(short_run):
    # The validation's goals set no number for the steps. The 2 s step runs do not depend on --duration-s, so
    # the 60 s run measures the same: 7.1 % (1 mm) and 9.8 % (1 cm) for route 2, 16.0 % and
    # 13.4 % for eq. 4. Bounds: 10 % and 12 %, below eq. 4's errors, so a route 2 step response
    # no better than eq. 4's fails; route 2 linearizes without leaf friction, so without it the
    # nearly linear 1 mm step must match better than with it.
    _, _, js, _ = short_run
    assert js["step_max_error_small_pct"] <= 10.0
    assert js["step_max_error_large_pct"] <= 12.0
    assert js["step_max_error_small_pct"] < js["step_max_error_small_pct_eq4"]
    assert js["step_max_error_large_pct"] < js["step_max_error_large_pct_eq4"]
    assert js["diagnostics_friction_off"]["step_max_error_small_pct"] < js["step_max_error_small_pct"]
    for key in ("small", "large"):
        size_mm = 1e3 * js["steps"][key]["step_m"]
        assert js["steps"][key]["route2"]["max_error_mm"] == pytest.approx(
            size_mm * js["steps"][key]["route2"]["max_error_pct"] / 100)


def test_validate_json_matches_the_numbers_printed(short_run):
    _, printed, js, _ = short_run
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
    out, printed, _, _ = short_run
    path = out / "validate.rrd"
    assert path.stat().st_size > 100_000
    assert "wrote recording" in printed
    from tests.scenarios.review.test_recording import read_rrd

    recordings = read_rrd(path)
    assert len(recordings) == 1
    (entities,) = recordings.values()
    assert any(p.startswith("/rig/fl") for p in entities)
    assert any(p.startswith("/scene/chassis") for p in entities)


def test_table1_ordering_road_above_rig(short_run):
    # Paper, Table 1: the rig test's DLC is below the road test's (the actuators cannot follow
    # the profile's high frequencies), and the linearized model lands near the rig, not the road.
    _, _, js, _ = short_run
    t1 = js["table1"]
    assert t1["road_test"] > t1["rig_test"]
    assert abs(t1["linearized_model"] - t1["rig_test"]) < abs(t1["road_test"] - t1["rig_test"])
    assert js["goals"]["table1_road_above_rig"] is True


def test_report_links_only_files_that_exist(short_run):
    out, _, _, _ = short_run
    report = (out / "report.md").read_text()
    links = re.findall(r"\]\(([^)]+)\)", report)
    assert "validate.json" in links and any(link.endswith(".png") for link in links)
    for link in links:
        assert (out / link).is_file(), link
    assert not list(out.glob("*.tmp")) and not list(out.glob(".*.tmp"))
    assert "Hydraulic events" in report


def test_events_are_reported_in_the_rigs_format():
    # Rig records give {event: {corner: {"samples", "first_time_s"}}}, only events that occurred.
    assert report.events_text({}) == "none"
    text = report.events_text({"spool_saturation": {"fl": {"samples": 12, "first_time_s": 3.25},
                                                    "rr": {"samples": 1, "first_time_s": 7.0}}})
    assert text == "spool saturation: fl 12 samples from 3.250 s, rr 1 samples from 7.000 s"


@pytest.mark.parametrize("bad", ["0", "-5", "nan", "4000"])
def test_bad_durations_are_refused_before_anything_runs(tmp_path, bad):
    args = _parse(["--out", str(tmp_path / "x"), "--duration-s", bad, "--quiet"])
    with pytest.raises(ScenarioError, match="duration"):
        args.func(args)
    assert not (tmp_path / "x").exists()


def test_bad_jobs_refused_with_one_sentence_before_any_work(tmp_path, capsys):
    rc = main(["validate", "--out", str(tmp_path / "x"), "--jobs", "-5", "--quiet"])
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert err.startswith("rigsim: error: --jobs") and "-5" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "x").exists()
