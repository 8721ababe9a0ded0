"""A calibration fitted on windows of several records of one truck (scenarios/records/model/joined.py).

References: the records' own samples and clocks (every window, its lead-in included, inside one
record, its times on that record's clock); the plant's own payload (the paper's truck, the same on
two paper roads), which the fit on windows of both must find; and the one-record calibration, which
a call without other records must leave exactly as it was (the same arrays, not copies).
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from rigsim.scenarios.core.config import ScenarioError, load_scenario, paper_scenarios
from rigsim.scenarios.core.run import run
from rigsim.scenarios.records.model.calibrate import fit_windows
from rigsim.scenarios.records.model.joined import join
from rigsim.scenarios.records.model.model_runs import check_record

PAIRS = "fl=Soll_FL:Weg_FL,fr=Soll_FR:Weg_FR,rl=Soll_RL:Weg_RL,rr=Soll_RR:Weg_RR"


def _record(n: int, t0: float = 0.0, fs: float = 1000.0, value: float = 1.0, drive: bool = True):
    t = t0 + np.arange(n) / fs
    a = np.full((n, 4), value)
    return t, a, a * 1e4, a if drive else None


def test_one_record_is_its_own_arrays():
    first = _record(12_000)
    joined = join(first, (), check_record)
    assert joined.t_s is first[0] and joined.x_a_m is first[1] and joined.force_N is first[2]
    assert joined.starts == (0, 12_000)
    wins, owners = joined.windows(2, 5.0, 5.0, fit_windows)
    assert wins == fit_windows(first[0], 2, 5.0, 5.0) and owners == (0, 0)


def test_windows_lie_inside_their_record_on_its_clock():
    """Two records of 12 s and 15 s (the second's clock starting at 100 s): two windows each, every
    window's lead-in and scored span inside its own record, its times on that record's clock."""
    a, b = _record(12_000, value=1.0), _record(15_000, t0=100.0, value=2.0)
    joined = join(a, [b], check_record)
    assert joined.starts == (0, 12_000, 27_000) and joined.t_s.size == 27_000
    np.testing.assert_allclose(np.diff(joined.t_s), 1e-3)
    wins, owners = joined.windows(2, 5.0, 5.0, fit_windows)
    assert owners == (0, 0, 1, 1)
    for (lead, s, e), i in zip(wins, owners):
        lo, hi = joined.starts[i], joined.starts[i + 1]
        assert lo <= lead < s < e <= hi and np.all(joined.x_a_m[lead:e] == (1.0, 2.0)[i])
    times = joined.window_times(wins, owners, 1000.0)
    assert times[0] == pytest.approx((5.0, 10.0)) and times[1] == pytest.approx((7.0, 12.0))
    assert times[2] == pytest.approx((105.0, 110.0)) and times[3] == pytest.approx((110.0, 115.0))
    acc = joined.each(lambda x: x - x[0], joined.x_a_m)  # per record: no step at the join
    assert not acc.any()


def test_records_that_do_not_match_are_named():
    a = _record(12_000)
    with pytest.raises(ScenarioError, match="the second record given is sampled at 500 Hz, the record corrected "
                                            "at 1000 Hz"):
        join(a, [_record(12_000, fs=500.0)], check_record)
    with pytest.raises(ScenarioError, match="the second record given has no drive"):
        join(a, [_record(12_000, drive=False)], check_record)
    with pytest.raises(ScenarioError, match=r"calibration record 1 \(the second record given\): the record \(6 s\) "
                                            r"is shorter than a calibration window"):
        join(a, [_record(6_000)], check_record).windows(1, 5.0, 5.0, fit_windows)


@pytest.fixture(scope="module")
def two_roads():
    """The paper's truck with its 3640 kg payload on its high-roughness road at 72 and 48 km/h, 10.5 s
    each on the hydraulic rig, load cells' noise 100 N."""
    out = []
    for path in (paper_scenarios()[2], paper_scenarios()[1]):
        sc = dataclasses.replace(load_scenario(path), duration_s=10.5)
        rig = run(sc, "rig")
        force = rig.signals["tire_force_N"] + np.random.default_rng(7).normal(0.0, 100.0, (rig.t_s.size, 4))
        out.append((sc, rig, force))
    return out


def test_a_calibration_on_two_roads_finds_the_truck(two_roads):
    """The payload and the front tires fitted on one window of each speed: window_records (0, 1), the
    windows' times on each record's clock, the payload within 1 % of the plant's (the XML's)."""
    from rigsim.scenarios.records.model.calibrate import calibrate
    from rigsim.scenarios.records.model.first_guess import description, xml_nominal

    (sc, rig, force), (_, rig2, force2) = two_roads
    cal = calibrate(rig.t_s, rig.signals["pan_m"], force, base_scenario=sc, x_ref_m=rig.signals["profile_m"],
                    names=("payload_kg", "tire_stiffness_front_N_per_m"), windows=1, window_s=4.0, lead_s=4.0,
                    workers=2, sigma=False, with_state=True,
                    more=[(rig2.t_s, rig2.signals["pan_m"], force2, rig2.signals["profile_m"])])[0]
    assert cal.window_records == (0, 1) and len(cal.windows_s) == 2
    assert cal.windows_s[0] == pytest.approx(cal.windows_s[1])  # one window each, on its own clock
    assert cal.values()["payload_kg"] == pytest.approx(xml_nominal(description(sc))["payload_kg"], rel=0.01)


def test_the_command_calibrates_on_the_records_it_is_given(two_roads, tmp_path, capsys):
    """rigsim correct --calibrate-also: one window of each record fitted, the calibration file naming the
    other record, the corrected file's metadata too; the other record is an input (never written)."""
    from test_correct_model import _write_csv

    from rigsim.correction.io.measured import read_channels
    from rigsim.scenarios.cli.main import main
    from rigsim.scenarios.records.model.saved import read_calibration

    paths = []
    for i, (sc, rig, force) in enumerate(two_roads):
        paths.append(tmp_path / f"rec{i}.csv")
        _write_csv(paths[-1], rig.t_s, force, rig.signals["profile_m"], rig.signals["pan_m"])
    before = paths[1].read_bytes()
    argv = ["correct", str(paths[0]), "--model", str(paper_scenarios()[2]), "--pairs", PAIRS, "--calibration-windows",
            "1", "--cab", "held", "--jobs", "2", "--max-evaluations", "6", "--calibrate-also", str(paths[1])]
    assert main([*argv, "-o", str(tmp_path / "out.csv")]) == 0
    assert "the calibration fits 1 window(s) of each of 1 other record(s) too" in capsys.readouterr().err
    saved = read_calibration(tmp_path / "out.calibration.json")
    assert saved.also == (str(paths[1]),) and saved.calibration.window_records == (0, 1)
    assert json.loads((tmp_path / "out.calibration.json").read_text())["also_records"] == [str(paths[1])]
    assert read_channels(tmp_path / "out.csv").metadata["cal_also"] == str(paths[1])
    assert paths[1].read_bytes() == before
    # refused before any work: the record itself, one of another rate, an output onto it, without --model
    for extra, said in (([str(paths[0])], "is the record corrected itself"),
                        (["-o", str(paths[1]), "--force"], "")):
        capsys.readouterr()
        args = [*argv[:-1], *extra] if extra[0] != "-o" else [*argv, *extra]
        if extra[0] != "-o":
            args.extend(["-o", str(tmp_path / "x.csv")])
        assert main(args) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and said in err, err
    assert paths[1].read_bytes() == before and not (tmp_path / "x.csv").exists()
    assert main(["correct", str(paths[0]), "--actuator", "a.toml", "--calibrate-also", str(paths[1]),
                 "-o", str(tmp_path / "y.csv")]) == 2
    assert "--calibrate-also goes with --model" in capsys.readouterr().err


def test_the_api_refuses_what_is_not_a_list_of_records():
    import rigsim

    options = rigsim.ModelOptions(paper_scenarios()[2], pairs=PAIRS, calibration_records="rec.csv")
    with pytest.raises(rigsim.RigsimError, match="calibration_records must be a list of other records"):
        rigsim.correct_record("absent.csv", options)
