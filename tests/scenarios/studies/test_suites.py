"""The shipped suites are data (``scenarios/data/suites/*.toml``), read by
:mod:`rigsim.scenarios.studies.suites`: the generalization suite is exactly the 24 cases its rule made
(the rule is the reference, copied here), the plant trucks are the study's numbers, picking by
name refuses what is not unique, and the files are installed with the package."""

from __future__ import annotations

import fnmatch
import importlib.resources
import json
import pathlib
import tomllib

import pytest

from rigsim.scenarios.core.config import parse_scenario, paper_scenarios
from rigsim.scenarios.studies import suites
from rigsim.scenarios.studies.model_suite import plants

ROOT = pathlib.Path(__file__).resolve().parents[3]

# The generalization suite's rule: case i cycles through class, speed, payload and tracks.
CLASSES = ("A", "B", "C", "D")
SPEEDS_KMH = (30.0, 45.0, 60.0, 75.0, 90.0, 100.0)
PAYLOADS_KG = (0.0, 1500.0, 3000.0, 4500.0, 6000.0, 8000.0)
TRACKS = ("identical", "independent", "coherent")


def reference_cases(n: int = 24, duration_s: float = 30.0) -> list[dict]:
    """The suite made by its rule: the documents the data file must hold."""
    docs = []
    for i in range(n):
        cls = CLASSES[i % 4]
        speed = SPEEDS_KMH[(i * 5 + i // 6) % 6]
        payload = PAYLOADS_KG[(i * 7 + 3) % 6]
        tracks = TRACKS[(i + i // 4) % 3]
        road = {"roughness": cls, "tracks": tracks, **({"cuton_wavelength_m": 25.0} if cls == "D" else {})}
        docs.append({"name": f"gen{i:02d}-{cls}-{speed:g}kmh-{payload:g}kg-{tracks}", "speed_kmh": speed,
                     "duration_s": duration_s, "seed": 7001 + 13 * i, "road": road,
                     "vehicle": {"payload_kg": payload}})
    return docs


def test_the_generalization_suite_is_the_rules_24_cases():
    cases = suites.generalization_cases()
    assert cases == reference_cases() and len(cases) == 24
    assert json.dumps(cases) == json.dumps(reference_cases())  # the keys in the same order, floats as floats
    for n, d in ((1, 12.0), (7, 30.0), (24, 60.0)):
        assert suites.generalization_cases(n, d) == reference_cases(n, d)
    assert suites.generalization_cases(24, None) == reference_cases(24, 30.0)  # the file's own 30 s
    assert len({c["name"] for c in cases}) == 24 and len({c["seed"] for c in cases}) == 24
    # every class, speed, payload and kind of tracks occurs, and only class D has the 25 m cut-on
    assert {c["road"]["roughness"] for c in cases} == set(CLASSES)
    assert {c["speed_kmh"] for c in cases} == set(SPEEDS_KMH)
    assert {c["vehicle"]["payload_kg"] for c in cases} == set(PAYLOADS_KG)
    assert {c["road"]["tracks"] for c in cases} == set(TRACKS)
    assert all(("cuton_wavelength_m" in c["road"]) == (c["road"]["roughness"] == "D") for c in cases)


def test_the_rule_and_the_checks_can_fail():
    """The comparison sees one changed value, and a fresh list is returned every time."""
    cases = suites.generalization_cases()
    cases[5]["seed"] += 1
    cases[6]["road"]["tracks"] = "identical" if cases[6]["road"]["tracks"] != "identical" else "coherent"
    assert cases != reference_cases()
    assert suites.generalization_cases() == reference_cases()  # the caller's change did not stick


def test_every_suite_document_is_a_valid_scenario():
    for doc in suites.generalization_cases(24, 12.0):
        sc = parse_scenario(doc)
        assert sc.name == doc["name"] and sc.duration_s == 12.0 and sc.seed == doc["seed"]


@pytest.mark.parametrize("n", [0, 25, -1])
def test_a_suite_size_outside_the_file_is_refused(n):
    with pytest.raises(ValueError, match="holds 24 cases"):
        suites.generalization_cases(n)


def test_picking_cases_by_parts_of_their_names():
    assert suites.pick_cases("generalization", ["gen03", "gen10"], 20.0) == \
        [reference_cases(24, 20.0)[3], reference_cases(24, 20.0)[10]]
    assert suites.pick_cases("generalization", None, 20.0) == reference_cases(24, 20.0)
    with pytest.raises(ValueError, match="'gen0' matches 10 of the generalization suite's cases"):
        suites.pick_cases("generalization", ["gen0"])
    with pytest.raises(ValueError, match="matches 0"):
        suites.pick_cases("generalization", ["gen99"])
    paths = paper_scenarios()
    assert suites.paper_cases() == paths and suites.pick_cases("paper") == [str(p) for p in paths]
    assert suites.paper_cases(["high_72", "medium"]) == [paths[2], paths[0]]
    with pytest.raises(ValueError, match="'high' matches 2 of the paper suite's cases"):
        suites.paper_cases(["high"])
    with pytest.raises(ValueError, match="suite must be one of paper, generalization"):
        suites.pick_cases("table1")
    assert suites.case_name(paths[1]) == "high_48kmh_3640kg" and suites.case_name({"name": "x"}) == "x"


def test_the_plant_trucks_are_the_studys_numbers():
    data = suites.model_plants()
    assert dict(data.factors) == {"payload_kg": 0.95, "tire_stiffness_front_N_per_m": 1.10,
                                  "tire_stiffness_rear_N_per_m": 0.90, "tire_damping_front_Ns_per_m": 1.20,
                                  "tire_damping_rear_Ns_per_m": 0.80, "spring_friction_front_N": 1.30,
                                  "spring_friction_rear_N": 0.70}
    assert data.payload_x_shift_m == 0.1
    assert plants.plant_keys() == ("rigid", "cab", "tire", "smooth")
    assert {k: dict(p.truck) for k, p in data.plants.items()} == {
        "rigid": {}, "cab": {"cab_mount_hz": 2.0}, "tire": {"tire_progressive_ratio": 0.25},
        "smooth": {"tire_progressive_ratio": 0.5, "tire_progressive_spread_m": 0.02}}
    expected = {"auto": {"rigid": "off", "cab": "off", "tire": "off", "smooth": "on"},
                "held": {"rigid": "off", "cab": "on", "tire": "off", "smooth": "on"},
                "fitted": {"rigid": "off", "cab": "off", "tire": "off", "smooth": "on"}}
    assert {c: {p: plants.mismatch(p, c) for p in plants.plant_keys()} for c in expected} == expected
    assert [plants.plant_name(p) for p in plants.plant_keys()] == [
        "rigid cab", "cab on 2 Hz mounts", "progressive tire +25 %", "tire stiffening +50 % over 2 cm"]
    with pytest.raises(TypeError):
        data.plants["cab"].truck["cab_mount_hz"] = 3.0  # read once per process, and read-only


def test_a_plant_file_with_an_unknown_field_is_refused(monkeypatch):
    real = suites._read

    def typo(name):
        doc = real(name)
        doc["plants"]["cab"]["truck"] = {"cab_mount_hertz": 2.0}
        return doc

    monkeypatch.setattr(suites, "_read", typo)
    suites.model_plants.cache_clear()
    try:
        with pytest.raises(ValueError, match="cab_mount_hertz"):
            suites.model_plants()
    finally:
        monkeypatch.undo()
        suites.model_plants.cache_clear()
    assert suites.model_plants().plants["cab"].truck["cab_mount_hz"] == 2.0


def test_the_suite_files_are_installed_with_the_package():
    """Each file is a resource of the installed package, and pyproject.toml's package-data ships it."""
    base = importlib.resources.files("rigsim.scenarios").joinpath("data", "suites")
    on_disk = sorted(p.name for p in (ROOT / "scenarios" / "data" / "suites").glob("*"))
    assert on_disk == sorted(suites.SUITE_FILES)
    for name in suites.SUITE_FILES:
        assert base.joinpath(name).is_file() and suites.suite_file(name).read_text(encoding="utf-8")
    globs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["rigsim.scenarios"]
    for name in suites.SUITE_FILES:
        assert any(fnmatch.fnmatch(f"data/suites/{name}", g) for g in globs), f"{name} not in package-data"
    with pytest.raises(ValueError, match="no suite file"):
        suites.suite_file("paper.toml")
