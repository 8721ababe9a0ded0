"""benchmarks/model_correction.py's bookkeeping: which cases and plants it runs, how it names a
plant's mismatch under each cab mode, how it counts the goals and lays out its tables.

No simulation runs here (the benchmark's numbers are its own, docs/model_correction.md); the
shares and cells below are counted by hand from the synthetic rows.
"""

from __future__ import annotations


import pytest

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.records.model.result import Calibration

_NAMES = {"rigid": "rigid cab", "cab": "cab on 2 Hz mounts", "tire": "progressive tire +25 %",
          "smooth": "tire stiffening +50 % over 2 cm"}


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("model_correction")


def _cal(names=("payload_kg",), fitted=(4000.0,), cab_choice=""):
    n = len(names)
    return Calibration(names=tuple(names), units=("",) * n, initial=tuple(fitted), fitted=tuple(fitted),
                       sigma=(0.0,) * n, sigma_robust=(0.0,) * n, fixed={}, fit_nrmse=(0.05,) * 4,
                       initial_nrmse=(0.1,) * 4, windows_s=((5.0, 10.0),), weighted=True, evaluations=7,
                       converged=True, message="ok", wall_time_s=1.0, cab_choice=cab_choice)


def _row(mismatch, floor, linear, linear_dlc, model=None, model_dlc=None, cpu=10.0, plant="rigid", case="c",
         cal=None):
    wheels = {"floor": floor, "linear": linear, "linear_dlc_error": linear_dlc, "rig": [0.3] * 4}
    if model is not None:
        wheels |= {"model": model, "model_dlc_error": model_dlc}
    return {"case": case, "mismatch": mismatch, "plant": _NAMES[plant], "plant_key": plant,
            "method": "model" if model else "linear", "reason": "" if model else "fit.", "cpu_s": cpu,
            "wall_s": cpu, "calibration": cal, "truth": {}, "scored_s": 12.0,
            "wheels": {k: dict(zip(CORNERS, v)) for k, v in wheels.items()},
            "mean": {k: sum(v) / 4 for k, v in wheels.items()}}


def test_summary_counts_what_the_method_delivers(bench):
    rows = [
        # rigid cab: model / floor 0.4, 0.6, 0.2, 0.1 -> 3 of 4 at <= 0.5; |DLC| 0.5 %, 2 %, 0.1 %, 0.9 % -> 3 of 4
        _row("off", [0.1] * 4, [0.2] * 4, [0.05] * 4, [0.04, 0.06, 0.02, 0.01], [0.005, -0.02, 0.001, -0.009], 20.0),
        # cab with --cab auto: in the family, 0.5 x floor exactly on every wheel (<= 0.5 meets the goal)
        _row("off", [0.1] * 4, [0.2] * 4, [0.0] * 4, [0.05] * 4, [0.0] * 4, 25.0, plant="cab"),
        # smooth tire, model: 0.9, 1.2 x floor; the fallback row scores its linear correction (1.5 x floor)
        _row("on", [0.1] * 4, [0.2] * 4, [0.0] * 4, [0.09, 0.12, 0.09, 0.09], [0.0, 0.03, 0.0, 0.0], 30.0,
             plant="smooth"),
        _row("on", [0.1] * 4, [0.15] * 4, [0.008, -0.02, 0.0, 0.0], cpu=40.0, plant="smooth", case="d"),
    ]
    s = bench.summary(rows)
    assert s["off"]["plants"] == ["rigid cab", "cab on 2 Hz mounts"] and s["on"]["plants"] == ["tire stiffening +50 % over 2 cm"]
    assert s["off"]["wheels"] == 8 and s["off"]["runs"] == 2
    assert s["off"]["floor_goal_share"] == 7 / 8 and s["off"]["dlc_within_1pct_share"] == 7 / 8
    assert s["off"]["fallbacks"] == 0 and s["off"]["worst_ratio"] == pytest.approx(0.6)
    assert s["on"]["wheels"] == 8 and s["on"]["fallbacks"] == 1 and s["on"]["runs"] == 2
    assert s["on"]["floor_goal_share"] == 3 / 8  # 0.9 x on three wheels of the model row; 1.5 x on the fallback's
    assert s["on"]["worst_ratio"] == pytest.approx(1.5)
    assert s["on"]["dlc_within_1pct_share"] == 6 / 8 and s["on"]["worst_dlc_error"] == pytest.approx(0.03)
    assert s["cpu_s"] == {"median": 27.5, "max": 40.0}
    lines = bench.goals(rows, 30.0).splitlines()
    assert lines[0].startswith("- mismatch off (rigid cab, cab on 2 Hz mounts; 8 wheels, 0 of 2 runs fell back")
    assert "88% of wheels, NOT met" in lines[0]
    assert lines[1].startswith("- mismatch on (tire stiffening +50 % over 2 cm; 8 wheels, 1 of 2 runs fell back")
    only_off = bench.goals(rows[:1], 30.0).splitlines()
    assert only_off[1].startswith("- mismatch on: not run") and "100%" not in only_off[0]


def test_the_three_plants(bench):
    (empty,) = bench.pick("generalization", ["gen03"], 20.0)
    assert empty["vehicle"]["payload_kg"] == 0.0 and len(bench.pick("generalization", None, 30.0)) == 24
    with pytest.raises(SystemExit):
        bench.pick("generalization", ["gen0"], 30.0)  # gen00 ... gen09: not unique
    nominal = bench.xml_nominal()
    rigid = bench.plant_scenario(empty, 20.0, "rigid")
    assert rigid.duration_s == 20.0 and rigid.vehicle.payload_kg == 0.0  # -5 % of the case's own payload
    assert rigid.vehicle.tire_stiffness_front_N_per_m == pytest.approx(1.1 * nominal["tire_stiffness_front_N_per_m"])
    assert rigid.vehicle.spring_friction_rear_N == pytest.approx(0.7 * nominal["spring_friction_rear_N"])
    assert rigid.vehicle.cab_mount_hz is None and rigid.vehicle.tire_progressive_ratio is None
    cab = bench.plant_scenario(empty, 20.0, "cab").vehicle
    assert cab.cab_mount_hz == 2.0 == bench.CAB_HZ and cab.tire_progressive_ratio is None
    tire = bench.plant_scenario(empty, 20.0, "tire").vehicle
    assert tire.cab_mount_hz is None and tire.tire_progressive_ratio == 0.25 == bench.TIRE_RATIO
    assert bench.plant_variant(1000.0, "tire", 0.4).tire_progressive_ratio == 0.4
    smooth = bench.plant_scenario(empty, 20.0, "smooth").vehicle
    assert (smooth.tire_progressive_ratio, smooth.tire_progressive_spread_m, smooth.tire_progressive_onset_m) \
        == (0.5, 0.02, None)  # 1 to 3 cm about the default onset, 2 cm
    # the four differ only in the cab and the tire: the same catalogue offsets on the same payload
    same = ("payload_kg", "payload_x_m", *bench.PLANT_FACTORS)
    assert {k: getattr(cab, k) for k in same} == {k: getattr(tire, k) for k in same} \
        == {k: getattr(smooth, k) for k in same} == {k: getattr(rigid.vehicle, k) for k in same}
    (laden,) = bench.pick("generalization", ["gen00"], 20.0)
    assert bench.plant_scenario(laden, 20.0, "tire").vehicle.payload_kg == pytest.approx(0.95 * 4500.0)
    assert [bench.plant_name(p) for p in bench.PLANT_KEYS] == list(_NAMES.values())
    assert bench.plant_name("tire", 0.1) == "progressive tire +10 %"
    with pytest.raises(ValueError):
        bench.plant_variant(1000.0, "soft")


def test_mismatch_is_whether_the_plant_is_outside_the_calibrated_family(bench):
    # the model family: a bilinear tire (ratio and onset fitted) always, so the gradual stiffening is outside it;
    # the cab rigid (held), fitted, or whichever fits better (auto)
    expected = {"auto": {"rigid": "off", "cab": "off", "tire": "off", "smooth": "on"},
                "held": {"rigid": "off", "cab": "on", "tire": "off", "smooth": "on"},
                "fitted": {"rigid": "off", "cab": "off", "tire": "off", "smooth": "on"}}
    assert {c: {p: bench.mismatch(p, c) for p in bench.PLANT_KEYS} for c in expected} == expected


def test_a_bad_tire_ratio_is_refused_before_any_run(bench, capsys):
    with pytest.raises(SystemExit, match="--tire-ratio"):
        bench.main(["--plants", "tire", "--tire-ratio", "5", "--cases", "gen00", "--suite", "generalization"])
    with pytest.raises(SystemExit):
        bench.main(["--plants", "family"])  # argparse: not a plant
    assert "invalid choice" in capsys.readouterr().err


def test_suite_table_lists_the_plants_in_their_order(bench):
    fitted = _cal(("payload_kg", "cab_mount_hz"), (4000.0, 2.0123))
    rows = [_row("off", [0.1] * 4, [0.2] * 4, [0.0] * 4, [0.04, 0.03, 0.02, 0.01], [0.005, -0.007, 0.0, 0.0], 20.0,
                 cal=_cal()),
            _row("off", [0.2] * 4, [0.3] * 4, [0.0] * 4, [0.08] * 4, [0.0, 0.0, -0.002, 0.001], 25.0, plant="cab",
                 cal=fitted),
            _row("on", [0.3] * 4, [0.35] * 4, [0.012, -0.02, 0.0, 0.0], cpu=30.0, plant="smooth")]
    lines = bench.suite_table(rows).splitlines()
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    assert head == ["case", "wheels", "linear floor, rigid / cab / smooth", "linear correction, rigid / cab / smooth",
                    "model (x floor), rigid / cab / smooth", "DLC error delivered, rigid / cab / smooth",
                    "cab, rigid / cab / smooth", "CPU s, rigid / cab / smooth", "fallback"]
    front = [c.strip() for c in lines[2].strip("|").split("|")]
    assert front == ["c", "front", "0.100 / 0.200 / 0.300", "0.200 / 0.300 / 0.350",
                     "0.040 (0.40 x) / 0.080 (0.40 x) / fallback", "-0.70% / +0.00% / -2.00%",
                     "held / fitted 2.01 Hz / -", "20 / 25 / 30", "smooth: fit."]
    rear = [c.strip() for c in lines[3].strip("|").split("|")]
    assert rear[:6] == ["", "rear", "0.100 / 0.200 / 0.300", "0.200 / 0.300 / 0.350",
                        "0.020 (0.20 x) / 0.080 (0.40 x) / fallback", "+0.00% / -0.20% / +0.00%"]
    assert rear[6:] == ["", "", ""]
    assert lines[-1] == ("Plants: rigid, rigid cab (mismatch off); cab, cab on 2 Hz mounts (mismatch off); "
                         "smooth, tire stiffening +50 % over 2 cm (mismatch on).")
    # --plants smooth rigid: that order, and a case without a plant's row shows "-"
    swapped = bench.suite_table([rows[2], rows[0], dict(rows[0], case="d")]).splitlines()
    assert "linear floor, smooth / rigid" in swapped[0]
    assert [c.strip() for c in swapped[4].strip("|").split("|")][2] == "- / 0.100"


def test_paper_table_says_which_cab_the_calibration_chose(bench):
    chose = _cal(cab_choice="cab held: the cab fitted on 1 Hz mounts reproduces ..., but its fit did not converge.")
    rows = [_row("off", [0.1] * 4, [0.2] * 4, [0.0] * 4, [0.04] * 4, [0.0] * 4, cal=chose),
            _row("on", [0.1] * 4, [0.2] * 4, [0.0] * 4, [0.09] * 4, [0.0] * 4, plant="smooth", cal=_cal())]
    text = bench.table(rows)
    assert text.count("Cab held: the cab fitted on 1 Hz mounts") == 1 and "cab held:" not in text
    assert "| rigid (off) | fl |" in text and "| smooth (on) | mean |" in text
    assert "smooth, tire stiffening +50 % over 2 cm (mismatch on): model correction" in text
