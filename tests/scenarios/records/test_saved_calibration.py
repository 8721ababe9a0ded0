"""A calibration as a file (scenarios/records/model/saved.py): written, read back, refused when odd.

Expected values: a calibration read back equals the one written, field by field (tuples stay
tuples, the XML's None stays None), and writing it again gives the same bytes; its truck is the
same :class:`~rigsim.mjcf.variant.TruckVariant`. Every corruption a file can carry (not JSON,
another format, a later layout, a key missing or unknown, a value that is no number, a field the
model does not fit, values that make no truck) is one ScenarioError sentence naming the file and
the key, never a Python error.
"""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import pytest

from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.records.model.result import Calibration
from rigsim.scenarios.records.model.saved import (FORMAT, VERSION, SavedCalibration, read_calibration,
                                                  truck_differs, write_calibration)

CAL = Calibration(names=("payload_kg", "payload_x_m", "tire_stiffness_front_N_per_m"), units=("kg", "m", "N/m"),
                  initial=(6000.0, -1.0, 9.0e5), fitted=(6352.4, -1.32, 8.7e5), sigma=(8.1, 0.004, 2.0e3),
                  sigma_robust=(21.0, 0.011, math.nan), fixed={"cab_mount_hz": None, "wheelbase_m": 4.6},
                  fit_nrmse=(0.041, 0.043, 0.052, 0.049), initial_nrmse=(0.31, 0.30, 0.42, 0.40),
                  windows_s=((5.0, 10.0), (15.0, 20.0)), weighted=True, evaluations=42, converged=True,
                  message="ftol reached", wall_time_s=95.0, bounds=((0.0, 2e4), (-3.5, 3.5), (4e5, 2e6)),
                  noise_nrmse=(0.01, 0.01, 0.01, 0.01), band_nrmse=(0.03, 0.03, 0.04, 0.04),
                  band_noise_nrmse=(0.005,) * 4, cell_mass_kg=12.0, cell_mass_sigma_kg=1.5)
SAVED = SavedCalibration(CAL, {"wheelbase_m": 4.6, "suspension_rear": "air"}, "truck.toml", "rec.csv", 60.0, 1000.0,
                         "0.1.0")


def test_a_calibration_read_back_is_the_one_written(tmp_path):
    path = write_calibration(tmp_path / "cal.json", SAVED)
    back = read_calibration(path)
    # NaN != NaN: the robust sigma written as null reads back as NaN
    assert math.isnan(back.calibration.sigma_robust[2])
    # and the wall time, a time and not a result, is left out of the file
    same = Calibration(**{**CAL.__dict__, "sigma_robust": back.calibration.sigma_robust, "wall_time_s": None})
    assert back.calibration == same and back.truck == SAVED.truck and back.record == "rec.csv"
    assert back.calibration.variant() == CAL.variant()
    assert back.model_error == CAL.excess_nrmse
    again = write_calibration(tmp_path / "again.json", back)
    assert again.read_bytes() == path.read_bytes()
    doc = json.loads(path.read_text())
    assert doc["format"] == FORMAT and doc["version"] == VERSION and len(doc["model_error"]) == 4
    assert doc["calibration"]["wall_time_s"] is None


def test_an_existing_file_or_an_input_is_not_overwritten(tmp_path):
    path = write_calibration(tmp_path / "cal.json", SAVED)
    before = path.read_bytes()
    with pytest.raises(ScenarioError, match="exists; pass --force"):
        write_calibration(path, SAVED)
    with pytest.raises(ScenarioError, match="is an input of this run"):
        write_calibration(path, SAVED, overwrite=True, inputs=[str(path)])
    assert path.read_bytes() == before


def _doc():
    return json.loads(json.dumps(json.loads(write_json_text())))


def write_json_text() -> str:
    from rigsim.scenarios.core.files import to_json

    return to_json(SAVED)


def _edit(doc, key, value):
    *head, last = key.split(".")
    d = doc
    for k in head:
        d = d[k]
    if value is KeyError:
        del d[last]
    else:
        d[last] = value
    return doc


@pytest.mark.parametrize("key, value, named", [
    ("format", "something else", "is not a calibration"),
    ("version", 2, "has layout version 2"),
    ("record", "rec.csv", "record must be a table"),
    ("record.fs_hz", "fast", "record holds 'fast'"),
    ("truck", [1, 2], "truck must be a table"),
    ("calibration", 3, "calibration must be a table"),
    ("calibration.fitted", KeyError, "calibration has no 'fitted'"),
    ("calibration.colour", "red", "unknown key 'colour'"),
    ("calibration.names", ["payload_kg", "wheel_colour", "x"], "calibration.names must be distinct fitted fields"),
    ("calibration.fitted", [1.0, 2.0], "calibration.fitted must be a list of 3 numbers"),
    ("calibration.fitted", [1.0, "x", 3.0], "calibration.fitted holds 'x'"),
    ("calibration.fitted", [1.0, None, 3.0], "calibration.fitted holds None"),
    ("calibration.fit_nrmse", [0.1], "calibration.fit_nrmse must be a list of 4 numbers"),
    ("calibration.windows_s", [[5.0]], "calibration.windows_s must be a list of 2 numbers"),
    ("calibration.fixed", {"cab_mount_hz": [1]}, "calibration.fixed must be a table"),
    ("calibration.fixed", {"wheelbase_m": "long"}, "make no truck"),
    ("calibration.window_records", [0, "x"], "calibration.window_records must list a record number"),
    ("calibration.window_records", [0], "calibration.window_records must list a record number (0, 1, ...) per window"),
    ("calibration.window_records", [0, 1], "names record 1, but also_records lists 0"),
    ("also_records", "rec2.csv", "also_records must be a list of the other records' paths"),
])
def test_a_corrupt_file_is_one_sentence_naming_the_key(tmp_path, key, value, named):
    path = tmp_path / "cal.json"
    path.write_text(json.dumps(_edit(_doc(), key, value)))
    with pytest.raises(ScenarioError) as err:
        read_calibration(path)
    message = str(err.value)
    assert "\n" not in message and message.startswith(f"calibration file {str(path)!r}") and named in message, message


@pytest.mark.parametrize("text, named", [("", "is not JSON"), ("{", "is not JSON"), ("[]", "is not a calibration"),
                                         ("\ufeff{\"format\": 1}", "is not a calibration")])
def test_a_file_that_is_no_calibration_is_named(tmp_path, text, named):
    path = tmp_path / "cal.json"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ScenarioError, match=named):
        read_calibration(path)
    with pytest.raises(ScenarioError, match="does not exist"):
        read_calibration(tmp_path / "absent.json")


def test_the_truck_description_is_compared_field_by_field():
    assert truck_differs(SAVED, {"wheelbase_m": 4.6, "suspension_rear": "air"}) == ""
    assert truck_differs(SAVED, {"wheelbase_m": 4.6 * (1 + 1e-12), "suspension_rear": "air"}) == ""
    said = truck_differs(SAVED, {"wheelbase_m": 5.06, "suspension_rear": "air"})
    assert said.startswith("the calibration was made for a truck described with wheelbase_m = 4.6, this one has 5.06")
    assert "suspension_rear = 'air', this one has None" in truck_differs(SAVED, {"wheelbase_m": 4.6})


# ---------------------------------------------------------------- reused on a record


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """10.5 s of the paper's high-roughness 72 km/h case on the hydraulic rig, as a lab's CSV, and
    its scenario as TRUCK.toml; the command's calibration of it (one window, the cab held)."""
    import dataclasses

    import numpy as np
    from test_correct_model import _write_csv as write_lab_csv

    from rigsim.scenarios.cli.main import main
    from rigsim.scenarios.core.config import load_scenario, paper_scenarios
    from rigsim.scenarios.core.run import run

    sc = dataclasses.replace(load_scenario(paper_scenarios()[2]), duration_s=10.5)
    res = run(sc, "rig")
    force = res.signals["tire_force_N"] + np.random.default_rng(7).normal(0.0, 100.0, res.signals["tire_force_N"].shape)
    d = tmp_path_factory.mktemp("lab")
    write_lab_csv(d / "messung.csv", res.t_s, force, res.signals["profile_m"], res.signals["pan_m"])
    argv = ["correct", str(d / "messung.csv"), "--model", str(paper_scenarios()[2]), "--pairs",
            "fl=Soll_FL:Weg_FL,fr=Soll_FR:Weg_FR,rl=Soll_RL:Weg_RL,rr=Soll_RR:Weg_RR", "--calibration-windows", "1",
            "--cab", "held", "--jobs", "2", "--quiet"]
    assert main([*argv, "-o", str(d / "first.csv")]) == 0
    return SimpleNamespace(dir=d, argv=argv)


def test_the_command_writes_the_calibration_beside_its_output(lab):
    saved = read_calibration(lab.dir / "first.calibration.json")
    assert saved.record == str(lab.dir / "messung.csv") and saved.record_s == pytest.approx(10.5, abs=0.01)
    assert saved.calibration.evaluations > 0 and max(saved.model_error) < 0.25


def test_a_calibration_reused_on_its_own_record_keeps_its_values_and_forces(lab, capsys):
    """The same truck, the same windows: the check's model error is the saved one, and the refit of the
    tire's progressive stiffening on the record's loads (refine.REFINED) starts at the fit's own
    optimum and stays there: every other value byte for byte the saved one, the refitted ones within
    their sigma, the corrected forces the first run's within 1e-3 of their spread (the metadata says
    where the calibration came from); nothing else is fitted."""
    import numpy as np

    from rigsim.scenarios.cli.main import main
    from rigsim.correction.io.measured import read_channels
    from rigsim.scenarios.records.model.refine import refined_names

    capsys.readouterr()
    argv = [*lab.argv, "--calibration", str(lab.dir / "first.calibration.json"), "-o", str(lab.dir / "again.csv")]
    assert main([a for a in argv if a != "--quiet"]) == 0
    printed = capsys.readouterr()
    assert "holds on this record: model error" in printed.err and "calibrating" not in printed.err.split("holds")[1]
    assert "progressive stiffening refitted on its loads" in printed.err
    again = read_calibration(lab.dir / "again.calibration.json").calibration
    first = read_calibration(lab.dir / "first.calibration.json").calibration
    refined = refined_names(first)
    assert refined and 0 < again.evaluations < first.evaluations
    for k, a, f, s in zip(first.names, again.fitted, first.fitted, first.sigma_robust):
        assert a == f if k not in refined else abs(a - f) <= s, (k, a, f, s)
    # the check reads the model from its one run over the record, the fit from runs started at each
    # window's lead-in: after the lead-in's settling they differ by ~1e-4 of the error (measured 8e-5)
    np.testing.assert_allclose(again.fit_nrmse, first.fit_nrmse, rtol=1e-3)
    a, f = (read_channels(lab.dir / n) for n in ("again.csv", "first.csv"))
    np.testing.assert_array_equal(a.time_s, f.time_s)
    for c in f.names:
        assert np.abs(a.data[c] - f.data[c]).max() <= 1e-3 * f.data[c].std(), c


def test_a_saved_tire_stiffening_is_refitted_on_the_records_loads(lab, tmp_path):
    """A calibration whose tire stiffening was fitted on other loads: the record's own fit (the
    reference, fitted on this record, whose plant's tires are linear: ratios of 0.0015 and 0.0002)
    with the tires 5 % stiffer beyond their onsets, front and rear, every other value the fit's. It
    holds on the record, and the refit on the record's windows brings both ratios back to the
    record's own, each within a fifth of the offset; every other fitted value is kept as saved."""
    from rigsim.scenarios.cli.main import main

    doc = json.loads((lab.dir / "first.calibration.json").read_text())
    cal = doc["calibration"]
    offset = {"tire_progressive_ratio": 0.05, "tire_progressive_ratio_rear": 0.05}
    for k, d in offset.items():
        cal["fitted"][cal["names"].index(k)] += d
    (tmp_path / "other_loads.json").write_text(json.dumps(doc))
    argv = [*lab.argv, "--calibration", str(tmp_path / "other_loads.json"), "-o", str(tmp_path / "out.csv")]
    assert main(argv) == 0
    got = read_calibration(tmp_path / "out.calibration.json").calibration
    first = read_calibration(lab.dir / "first.calibration.json").calibration.values()
    assert not got.second_start
    for k, v in zip(got.names, got.fitted):
        if k in offset:
            assert abs(v - first[k]) <= 0.2 * offset[k], (k, v, first[k])
        elif "onset" not in k:
            assert v == pytest.approx(first[k], rel=1e-12), k


def test_a_refit_that_cannot_run_keeps_the_saved_calibration(lab, tmp_path, monkeypatch):
    """The tire's refit on the record refused (a ScenarioError from its model runs): the record is still
    corrected, with the saved values as the check found them, none fitted."""
    from rigsim.scenarios.cli.main import main
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.records.model import differential

    def refused(*a, **k):
        raise ScenarioError("no rest for this variant")

    monkeypatch.setattr(differential, "refine_on_record", refused)
    argv = [*lab.argv, "--calibration", str(lab.dir / "first.calibration.json"), "-o", str(tmp_path / "out.csv")]
    assert main(argv) == 0
    got = read_calibration(tmp_path / "out.calibration.json").calibration
    first = read_calibration(lab.dir / "first.calibration.json").calibration
    assert got.evaluations == 0 and got.fitted == first.fitted and not got.second_start


def test_a_check_followed_by_a_refit_runs_the_measured_pans_alone(lab, tmp_path, monkeypatch):
    """Where the saved tire is refitted after the check, the check's model run on the drive would be
    thrown away: the check runs the model on the measured pans alone, and the correction both pans
    with the refitted values (three record-length runs, not four)."""
    from rigsim.scenarios.cli.main import main
    from rigsim.scenarios.records.model import differential

    calls = []
    real = differential.model_forces_on

    def counted(variant, t_s, pans_m, **kw):
        calls.append(len(pans_m))
        return real(variant, t_s, pans_m, **kw)

    monkeypatch.setattr(differential, "model_forces_on", counted)
    argv = [*lab.argv, "--calibration", str(lab.dir / "first.calibration.json"), "-o", str(tmp_path / "out.csv")]
    assert main(argv) == 0
    assert calls == [1, 2]


def test_a_calibration_the_record_refutes_is_fitted_again_from_its_values(lab, capsys, tmp_path):
    """A saved payload 40 % off (the truck loaded otherwise since): the model error on the record is
    past the limit, so the truck is calibrated again from the saved values, and the output says so."""
    from rigsim.scenarios.cli.main import main

    doc = json.loads((lab.dir / "first.calibration.json").read_text())
    cal = doc["calibration"]
    i = cal["names"].index("payload_kg")
    cal["fitted"][i] *= 1.4
    (tmp_path / "off.json").write_text(json.dumps(doc))
    argv = [*lab.argv, "--calibration", str(tmp_path / "off.json"), "-o", str(tmp_path / "out.csv")]
    assert main(argv) == 0
    refit = read_calibration(tmp_path / "out.calibration.json")
    assert refit.calibration.evaluations > 0
    assert refit.calibration.second_start.startswith("the saved calibration's model error on this record (")
    assert "so the truck was calibrated again from its values" in (tmp_path / "out.csv").read_text()
    assert refit.calibration.values()["payload_kg"] == pytest.approx(
        read_calibration(lab.dir / "first.calibration.json").calibration.values()["payload_kg"], rel=0.05)


def test_a_calibration_of_another_truck_is_refused_before_any_work(lab, tmp_path, capsys):
    from rigsim.scenarios.cli.main import main

    doc = json.loads((lab.dir / "first.calibration.json").read_text())
    doc["truck"] = {"wheelbase_m": 5.6}
    (tmp_path / "other.json").write_text(json.dumps(doc))
    argv = [*lab.argv, "--calibration", str(tmp_path / "other.json"), "-o", str(tmp_path / "out.csv")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--calibration" in err and "wheelbase_m = 5.6, this one has None" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["other.json"]


def test_a_calibration_file_beside_the_output_is_refused_before_any_work(lab, tmp_path, capsys):
    """``-o out.csv`` writes ``out.calibration.json``: where that file exists (without --force) or is
    the run's own --calibration, the command stops with one sentence and exit code 2 before any
    model run, and nothing is written or changed."""
    from rigsim.scenarios.cli.main import main

    (tmp_path / "out.calibration.json").write_text("{}")
    assert main([*lab.argv, "-o", str(tmp_path / "out.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "out.calibration.json' of -o " in err and "exists; pass --force" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.calibration.json"]
    assert (tmp_path / "out.calibration.json").read_text() == "{}"
    own = tmp_path / "own.calibration.json"
    own.write_bytes((lab.dir / "first.calibration.json").read_bytes())
    assert main([*lab.argv, "--calibration", str(own), "-o", str(tmp_path / "own.csv"), "--force"]) == 2
    assert "is an input of this run; name another output" in capsys.readouterr().err
    assert own.read_bytes() == (lab.dir / "first.calibration.json").read_bytes()


def test_a_calibration_on_several_records_names_them_and_reads_back(tmp_path):
    """Windows of two records (calibrate(more=...)): also_records and window_records round-trip, the
    same bytes written again."""
    import dataclasses

    saved = dataclasses.replace(SAVED, calibration=dataclasses.replace(CAL, window_records=(0, 1)), also=("rec2.csv",))
    path = write_calibration(tmp_path / "cal.json", saved)
    back = read_calibration(path)
    assert back.also == ("rec2.csv",) and back.calibration.window_records == (0, 1)
    assert json.loads(path.read_text())["also_records"] == ["rec2.csv"]
    assert write_calibration(tmp_path / "again.json", back).read_bytes() == path.read_bytes()
    assert "also_records" not in json.loads(write_calibration(tmp_path / "one.json", SAVED).read_text())
