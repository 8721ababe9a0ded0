"""Scenario files, road-mode runs, results and the rigsim CLI."""

from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest

import rigsim.mjcf
import rigsim.scenarios
from rigsim.mjcf.build import resource_path
from rigsim.scenarios.cli.main import main
from rigsim.scenarios.core.config import ScenarioError, load_scenario, paper_scenarios, parse_scenario
from rigsim.scenarios.core.run import run

REPO = pathlib.Path(__file__).resolve().parents[3]

SHORT = """
name = "short"
speed_kmh = 72.0
duration_s = 2.0
lead_in_s = 1.0
seed = 7

[road]
roughness = "C"
cuton_wavelength_m = 40.0

[vehicle]
payload_kg = 3640.0
"""


def _write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


# ---------------------------------------------------------------- packaging


def test_packages_and_resources_belong_to_this_project():
    """A PyPI package named `scenarios` exists: make sure we import ours."""
    assert pathlib.Path(rigsim.scenarios.__file__).resolve().parent == REPO / "scenarios"
    assert pathlib.Path(rigsim.mjcf.__file__).resolve().parent == REPO / "mjcf"
    for name in ("truck_rig.xml", "scene.xml"):
        assert resource_path(name).resolve() == REPO / "mjcf" / name
    for p in paper_scenarios():
        assert p.resolve().parent == REPO / "scenarios" / "data" / "paper"


# ---------------------------------------------------------------- scenario files


def test_paper_scenarios_load_with_the_papers_cases():
    cases = [load_scenario(p) for p in paper_scenarios()]
    got = [(c.road.roughness, c.speed_kmh, c.vehicle.payload_kg) for c in cases]
    # Table 2 of the paper, in its order.
    assert got == [("medium", 72.0, 6360.0), ("high", 48.0, 3640.0), ("high", 72.0, 3640.0)]
    assert cases[0].speed_mps == pytest.approx(20.0)


@pytest.mark.parametrize(
    "edit,pattern",
    [
        (("payload_kg = 3640.0", "paylod_kg = 3640.0"), r"unknown key vehicle\.paylod_kg; did you mean 'payload_kg'"),
        (("seed = 7", "sed = 7"), r"unknown key sed; did you mean 'seed'"),
        (("speed_kmh = 72.0", "speed_kmh = 0.0"), r"speed_kmh must be > 0"),
        (("speed_kmh = 72.0", 'speed_kmh = "fast"'), r"speed_kmh must be a number"),
        (("payload_kg = 3640.0", "payload_kg = -5.0"), r"vehicle\.payload_kg must be >= 0"),
        (('roughness = "C"', 'roughness = "Q"'), r"road\.roughness must be one of"),
        (('roughness = "C"', 'roughness = "C"\ngd_n0_m3 = 1e-4'), r"exactly one of roughness, gd_n0_m3"),
        (("seed = 7", "seed = -1"), r"seed must be a non-negative integer"),
        (('roughness = "C"', 'roughness = "C"\nn_min_cyc_per_m = 20.0'), r"road\.n_min_cyc_per_m must be <= 10"),
        (("duration_s = 2.0", ""), r"missing required key duration_s"),
    ],
)
def test_bad_scenarios_are_refused_naming_the_field(tmp_path, edit, pattern):
    text = SHORT.replace(*edit)
    with pytest.raises(ScenarioError, match=pattern):
        load_scenario(_write(tmp_path, text))


def test_missing_and_malformed_files(tmp_path):
    with pytest.raises(ScenarioError, match="does not exist"):
        load_scenario(tmp_path / "nope.toml")
    with pytest.raises(ScenarioError, match="not valid TOML"):
        load_scenario(_write(tmp_path, "name = \n"))


def test_scenario_errors_are_one_sentence(tmp_path):
    with pytest.raises(ScenarioError) as info:
        load_scenario(_write(tmp_path, SHORT.replace("seed = 7", "sed = 7")))
    assert "\n" not in str(info.value)


# ---------------------------------------------------------------- road mode


@pytest.fixture(scope="module")
def short_road_result(tmp_path_factory):
    path = _write(tmp_path_factory.mktemp("sc"), SHORT)
    return run(load_scenario(path), "road")


def test_road_mode_pans_follow_the_profile_exactly(short_road_result):
    r = short_road_result
    assert np.max(np.abs(r.signals["pan_m"] - r.signals["profile_m"])) <= 1e-9
    # The drive is not trivially zero.
    assert np.std(r.signals["profile_m"]) > 1e-3


def test_road_mode_statistics_are_std_over_mean(short_road_result):
    r = short_road_result
    f = r.signals["tire_force_N"]
    stats = r.statistics()
    for i, c in enumerate(r.corners):
        # Reference: numpy's population std and mean of the recorded series.
        assert stats[c]["dlc"] == pytest.approx(np.std(f[:, i]) / np.mean(f[:, i]), rel=1e-12)
    # Mean wheel loads add up to the truck's weight (the road's mean is zero, the lead-in
    # starts at static equilibrium): within 1 % over a 2 s record.
    assert sum(s["mean_force_N"] for s in stats.values()) == pytest.approx(r.vehicle_mass_kg * 9.81, rel=0.01)


def test_output_rate_and_time_axis(short_road_result):
    r = short_road_result
    assert r.rate_hz == pytest.approx(1000.0)
    assert r.t_s[0] == pytest.approx(0.0, abs=1e-12)
    assert r.t_s[-1] == pytest.approx(2.0)
    assert r.t_s.size == 2001


def test_same_seed_gives_bit_identical_runs(tmp_path, short_road_result):
    again = run(load_scenario(_write(tmp_path, SHORT)), "road")
    for key, arr in short_road_result.signals.items():
        assert np.array_equal(arr, again.signals[key]), key
    other = run(load_scenario(_write(tmp_path, SHORT.replace("seed = 7", "seed = 8"))), "road")
    assert not np.array_equal(other.signals["profile_m"], short_road_result.signals["profile_m"])


def test_rougher_road_gives_higher_dlc(tmp_path, short_road_result):
    """DLC is linear in the profile amplitude for a linear truck: class D has twice the
    RMS elevation of class C (4x the PSD), so the DLC roughly doubles (leaf friction and
    tire lift-off make it not exactly 2)."""
    rough = run(load_scenario(_write(tmp_path, SHORT.replace('roughness = "C"', 'roughness = "D"'))), "road")
    ratio = rough.summary()["dlc_mean"] / short_road_result.summary()["dlc_mean"]
    assert 1.6 < ratio < 2.4


def test_drive_beyond_stroke_is_refused_before_the_run(tmp_path):
    text = SHORT.replace('roughness = "C"', 'roughness = "F"').replace("cuton_wavelength_m = 40.0", "cuton_wavelength_m = 200.0")
    with pytest.raises(ScenarioError, match=r"beyond the \+-76.0 mm stroke"):
        run(load_scenario(_write(tmp_path, text)), "road")


def test_measured_profile_csv_and_nan(tmp_path):
    x = np.arange(0, 400.0, 0.02)
    z = 0.004 * np.sin(2 * np.pi * x / 5.0)
    np.savetxt(tmp_path / "p.csv", np.c_[x, z, z], delimiter=",", header="distance_m,left_m,right_m", comments="")
    text = SHORT.replace('roughness = "C"', 'profile_csv = "p.csv"')
    r = run(load_scenario(_write(tmp_path, text)), "road")
    # 5 m wavelength at 20 m/s excites 4 Hz; amplitude 4 mm after the fade-in.
    assert np.max(np.abs(r.signals["profile_m"])) == pytest.approx(0.004, rel=0.01)
    z[1234] = np.nan
    np.savetxt(tmp_path / "p.csv", np.c_[x, z, z], delimiter=",", header="distance_m,left_m,right_m", comments="")
    with pytest.raises(ScenarioError, match=r"line 1236, column left_m: 'nan' is not finite"):
        run(load_scenario(_write(tmp_path, text)), "road")


def test_spatial_band_reaches_the_profile(tmp_path):
    """A band limited to 1 cycle/m (wavelengths >= 1 m) leaves no content above 20 Hz at
    72 km/h; the default band (to 10 cycle/m, then the tire's 0.25 m enveloping) does."""
    from scipy.signal import welch

    def hf_share(extra):
        r = run(load_scenario(_write(tmp_path, SHORT.replace('roughness = "C"', 'roughness = "C"' + extra))), "road")
        f, p = welch(r.signals["profile_m"][:, 0], fs=r.rate_hz, nperseg=512)
        return p[f > 25].sum() / p.sum()

    assert hf_share("\nn_max_cyc_per_m = 1.0") < 1e-6
    assert hf_share("") > 1e-4


def test_parse_scenario_in_memory():
    s = parse_scenario({"name": "x", "speed_kmh": 36.0, "duration_s": 1.0, "road": {"roughness": "medium"}})
    assert s.speed_mps == pytest.approx(10.0)


# ---------------------------------------------------------------- CLI


def test_cli_run_writes_result_and_timeseries(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["run", str(_write(tmp_path, SHORT)), "--mode", "road", "--out", str(out), "--quiet"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "DLC" in printed and "fl" in printed
    summary = json.loads((out / "result.json").read_text())
    assert summary["scenario"] == "short" and summary["mode"] == "road"
    assert summary["vehicle_mass_kg"] == pytest.approx(5200 + 3640 + 700 + 1200)
    for c in ("fl", "fr", "rl", "rr"):
        assert set(summary["wheels"][c]) >= {"mean_force_N", "std_force_N", "dlc"}
    # The time series reads in one line and matches result.json.
    ts = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    assert ts["time_s"][1] - ts["time_s"][0] == pytest.approx(1e-3)
    f = ts["tire_force_fl_N"]
    assert np.std(f) / np.mean(f) == pytest.approx(summary["wheels"]["fl"]["dlc"], rel=1e-6)
    assert not list(out.glob(".*tmp"))  # no temporary files left behind


@pytest.mark.parametrize(
    "text_edit",
    [
        ("payload_kg = 3640.0", "paylod_kg = 3640.0"),
        ("speed_kmh = 72.0", "speed_kmh = 0"),
        ("payload_kg = 3640.0", "payload_kg = -1.0"),
    ],
)
def test_cli_bad_input_exit_2_one_sentence_nothing_written(tmp_path, capsys, text_edit):
    out = tmp_path / "out"
    code = main(["run", str(_write(tmp_path, SHORT.replace(*text_edit))), "--out", str(out), "--quiet"])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rigsim: error:") and "\n" not in err and "Traceback" not in err
    assert not out.exists()


def test_cli_missing_file_exit_2(tmp_path, capsys):
    code = main(["run", str(tmp_path / "missing.toml"), "--out", str(tmp_path / "o"), "--quiet"])
    assert code == 2
    assert "does not exist" in capsys.readouterr().err


def test_cli_model_prints_loads_and_modes(capsys):
    assert main(["model", "--payload-kg", "6360"]) == 0
    out = capsys.readouterr().out
    assert "body bounce" in out and "rear axle hop" in out


def test_cli_paper_short_run_writes_table_with_papers_values(tmp_path, capsys):
    out = tmp_path / "paper"
    assert main(["paper", "--out", str(out), "--duration-s", "12", "--jobs", "2", "--quiet"]) == 0
    printed = capsys.readouterr().out
    doc = json.loads((out / "paper.json").read_text())
    assert doc["configuration"] == "dyntrac" and "Configuration: the simulated DYNTRAC fitted" in printed
    assert (out / "paper.json").stat().st_size < 100_000  # the figures only, never a run's signals
    cases = {c["case"]: c for c in doc["cases"]}
    assert list(cases) == ["paper-medium-72kmh-6360kg", "paper-high-48kmh-3640kg", "paper-high-72kmh-3640kg"]
    # The paper's Table 2 values travel with the results (reference: the paper).
    assert cases["paper-high-72kmh-3640kg"]["paper"] == {"road": 0.2105, "rig": 0.1754, "corrected": 0.2139}
    keys = ("dlc_road", "dlc_rig", "dlc_corrected_paper", "dlc_corrected", "dlc_road_lowpassed", "nrmse_corrected")
    for case in cases.values():
        assert set(keys) <= set(case)
        assert case["dlc_rig"] < case["dlc_road"]
        assert f"{case['dlc_road']:.4f}" in printed
        # The mean over the wheels is the mean of the per-wheel values written beside it.
        for key in keys:
            assert case[key] == pytest.approx(np.mean([w[key] for w in case["wheels"].values()]), abs=2e-6)
        for mode in ("road", "rig"):
            assert (out / case["case"] / mode / "result.json").is_file()
        assert (out / f"figure8_{case['case']}.png").stat().st_size > 10_000
    assert "figure8_paper-high-72kmh-3640kg.png" in (out / "report.md").read_text()


def test_cli_paper_refuses_a_too_short_duration(tmp_path, capsys):
    assert main(["paper", "--out", str(tmp_path / "p"), "--duration-s", "3", "--quiet"]) == 2
    assert "too short" in capsys.readouterr().err
    assert not (tmp_path / "p").exists()
