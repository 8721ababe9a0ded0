"""The model correction on a truck of its own: the description of TRUCK.toml's [vehicle] is the model's.

The plant is the shipped 4x2 tractor (scenarios/data/trucks/tractor_air.toml: 3.7 m wheelbase, wide
singles, rear air springs) with its air springs 15 % stiffer and its dampers 20 % softer than the
spec sheet says; the model starts from the spec sheet. References: the plant's own values (the fit
must find them from the rig's signals alone), and the catalogue truck's guess, which a scenario
without a description must leave exactly as it was.
"""

from __future__ import annotations

import dataclasses
import pathlib
from types import SimpleNamespace

import numpy as np
import pytest

from rigsim.mjcf.variant import TruckVariant
from rigsim.scenarios.core.config import load_scenario, paper_scenarios
from rigsim.scenarios.core.run import run
from rigsim.scenarios.records.model.calibrate import calibrate
from rigsim.scenarios.records.model.family import DEFAULT_NAMES
from rigsim.scenarios.records.model.first_guess import catalogue, description, spring_fields
from rigsim.scenarios.studies import scoring

TRUCKS = pathlib.Path(__file__).resolve().parents[3] / "scenarios" / "data" / "trucks"


def test_a_scenario_without_a_description_keeps_the_catalogue_guess():
    sc = load_scenario(next(p for p in paper_scenarios() if "medium_72" in p.stem))
    assert description(sc) == description(None)
    assert catalogue(description(sc)) == catalogue()
    assert spring_fields(description(sc)) == ((), ())


def test_the_shipped_trucks_are_described():
    tractor = description(load_scenario(TRUCKS / "tractor_air.toml"))
    assert (tractor.wheelbase_m, tractor.rear_tires, tractor.suspension_rear) == (3.7, "single", "air")
    fit, drop = spring_fields(tractor)
    assert fit == ("spring_rate_front_N_per_m", "spring_damping_front_Ns_per_m", "spring_rate_rear_N_per_m",
                   "spring_damping_rear_Ns_per_m")
    assert drop == ("spring_friction_factor_rl",)  # the air axle's left/right friction ratio; its friction is fitted
    guess = catalogue(tractor)
    assert guess["wheelbase_m"] == 3.7 and "spring_rate_rear_N_per_m" in guess
    long = description(load_scenario(TRUCKS / "rigid_long_leaf.toml"))
    assert long.wheelbase_m == 6.3 and spring_fields(long)[1] == ()  # leaves: their friction kept


@pytest.fixture(scope="module")
def tractor_record():
    spec = load_scenario(TRUCKS / "tractor_air.toml")
    plant = dataclasses.replace(spec.vehicle, spring_rate_rear_N_per_m=1.15 * spec.vehicle.spring_rate_rear_N_per_m,
                                spring_damping_rear_Ns_per_m=0.8 * spec.vehicle.spring_damping_rear_Ns_per_m)
    sc = dataclasses.replace(spec, duration_s=12.0, vehicle=plant)
    rig = run(sc, "rig")
    return spec, plant, rig, scoring.measured_force(rig, scoring.NOISE_N, sc.seed)


def test_the_air_springs_of_a_described_tractor_are_found_from_the_rig_signals(tractor_record):
    """From the spec sheet's catalogue guess (rate x 0.85, damper x 1.15: 26 % and 44 % off the plant's)
    the fit finds the plant's air-spring rate within 5 % and its damper within 10 % (one 5 s window with
    100 N of noise: measured 5.4 %; the 30 s record of the shipped tractor, 2 windows of 10 s, all
    fields: 0.8 %); the air axle's friction (its bushings', none on this plant) is fitted from its
    small guess and found below it, the geometry is held at the description's."""
    spec, plant, rig, force = tractor_record
    # the tires and the front leaves fitted too (their catalogue guess is 15 % off the plant's): held
    # off, they would be explained by the rear damper; the rear friction stands for its axle's springs
    names = ("payload_kg", "tire_stiffness_front_N_per_m", "tire_stiffness_rear_N_per_m",
             "tire_damping_front_Ns_per_m", "tire_damping_rear_Ns_per_m", "spring_friction_front_N",
             "spring_friction_rear_N")
    cal = calibrate(rig.t_s, rig.signals["pan_m"], force, base_scenario=spec, x_ref_m=rig.signals["profile_m"],
                    names=names, windows=1, window_s=5.0, lead_s=5.0, max_nfev=12, workers=2)
    fitted = dict(zip(cal.names, cal.fitted))
    assert fitted["spring_friction_rear_N"] < initial_friction(cal)
    assert {"spring_rate_rear_N_per_m", "spring_damping_rear_Ns_per_m", "spring_friction_front_N"} <= set(cal.names)
    initial = dict(zip(cal.names, cal.initial))
    assert abs(initial["spring_rate_rear_N_per_m"] / plant.spring_rate_rear_N_per_m - 1) > 0.2
    assert fitted["spring_rate_rear_N_per_m"] == pytest.approx(plant.spring_rate_rear_N_per_m, rel=0.05)
    assert fitted["spring_damping_rear_Ns_per_m"] == pytest.approx(plant.spring_damping_rear_Ns_per_m, rel=0.10)
    assert cal.fixed["wheelbase_m"] == 3.7 and cal.fixed["suspension_rear"] == "air"
    assert cal.variant().rear_tires == "single"
    assert np.all(np.array(cal.fit_nrmse) < np.array(cal.initial_nrmse))


def initial_friction(cal) -> float:
    return dict(zip(cal.names, cal.initial))["spring_friction_rear_N"]


def test_default_names_on_a_described_truck_fit_its_springs_an_air_axle_its_friction_and_the_roll_inertia():
    from rigsim.scenarios.records.model.calibrate import _spring_names

    tractor = description(load_scenario(TRUCKS / "tractor_air.toml"))
    names = _spring_names(DEFAULT_NAMES, tractor)
    assert "spring_friction_rear_N" in names and "spring_friction_factor_rl" not in names
    assert "chassis_roll_inertia_kg_m2" in names  # beside the body's pitch, on a described truck only
    assert not {"frame_torsion_hz", "frame_bending_hz"} & set(names)  # the frame: frame_choice adds it
    assert "spring_friction_front_N" in names  # the steer axle's leaves keep theirs, and fit their rate and damper
    i = names.index("spring_friction_front_N")
    assert names[i + 1:i + 3] == ("spring_rate_front_N_per_m", "spring_damping_front_Ns_per_m")
    assert {"spring_rate_rear_N_per_m", "spring_damping_rear_Ns_per_m"} <= set(names)
    assert _spring_names(DEFAULT_NAMES, description(None)) == DEFAULT_NAMES  # the catalogue truck's as before


def test_a_described_truck_can_fit_its_frame_and_the_catalogue_truck_keeps_its_rigid_chassis(tractor_record):
    """Asked to fit the frame's modes, the described tractor's calibration fits them from 9 Hz within
    3-20 Hz (its model's frame flexible); the catalogue truck's, on a paper record, has no frame field
    fitted or held, its model's chassis is rigid, and asking for its frame is refused (one short window,
    two evaluations: the fields, not the fit, are tested)."""
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.records.model.family import FRAME_FITTED
    from rigsim.scenarios.records.model.first_guess import CATALOGUE_FRAME_HZ

    names = ("payload_kg", "payload_z_m")
    quick = dict(names=names + FRAME_FITTED, windows=1, window_s=2.0, lead_s=2.0, max_nfev=2, workers=2, sigma=False,
                 with_state=True)
    spec, plant, rig, force = tractor_record
    cal, _ = calibrate(rig.t_s, rig.signals["pan_m"], force, base_scenario=spec, x_ref_m=rig.signals["profile_m"],
                       **quick)
    assert cal.names[-2:] == ("frame_torsion_hz", "frame_bending_hz") and CATALOGUE_FRAME_HZ == 9.0
    for k in ("frame_torsion_hz", "frame_bending_hz"):
        i = cal.names.index(k)
        assert (cal.initial[i], cal.units[i]) == (9.0, "Hz") and cal.bounds[i] == pytest.approx((3.0, 20.0))
        assert 3.0 <= cal.fitted[i] <= 20.0 and getattr(cal.variant(), k) == cal.fitted[i]
    paper = dataclasses.replace(load_scenario(next(p for p in paper_scenarios() if "medium_72" in p.stem)),
                                duration_s=4.5)
    rig = run(paper, "rig")
    measured = scoring.measured_force(rig, scoring.NOISE_N, paper.seed)
    with pytest.raises(ScenarioError, match="frame_torsion_hz is fitted on a described truck only"):
        calibrate(rig.t_s, rig.signals["pan_m"], measured, base_scenario=paper, **quick)
    catalogue_cal, _ = calibrate(rig.t_s, rig.signals["pan_m"], measured, base_scenario=paper,
                                 x_ref_m=rig.signals["profile_m"], **(quick | {"names": names}))
    assert catalogue_cal.names == names
    assert not {"frame_torsion_hz", "frame_bending_hz"} & set(catalogue_cal.fixed)  # the XML's rigid chassis
    assert catalogue_cal.variant().frame_torsion_hz is None


def test_a_wrong_description_shows_in_the_model_error_and_is_said(tractor_record):
    """The same record calibrated from a spec sheet that declares leaves where the tractor rides on air
    (at the catalogue's leaf rate and friction), and one whose wheelbase is 10 % long: the rear wheels'
    model error is at least 1.5 times the right description's (measured: 0.080 right, 0.196 leaves, 0.145 the
    long wheelbase, on one 5 s window; the leaves' rate, damper and friction are
    fitted, so a leaf model can take an air spring's part but for its rate's rise with load); a model
    error past the fallback's limit gets the note naming the description's fields, one within it none."""
    from rigsim.scenarios.records.model.fallback import HYBRID_LIMIT
    from rigsim.scenarios.records.model_record import description_note

    spec, plant, rig, force = tractor_record
    names = ("payload_kg", "tire_stiffness_rear_N_per_m", "spring_friction_rear_N")

    def model_error(vehicle):
        sc = dataclasses.replace(spec, vehicle=vehicle)
        return calibrate(rig.t_s, rig.signals["pan_m"], force, base_scenario=sc, x_ref_m=rig.signals["profile_m"],
                         names=names, windows=1, window_s=5.0, lead_s=5.0, max_nfev=8, workers=2)

    right = model_error(spec.vehicle)
    leaves = model_error(dataclasses.replace(spec.vehicle, suspension_rear="leaf", spring_rate_rear_N_per_m=7e5,
                                             spring_damping_rear_Ns_per_m=1e4))
    long = model_error(dataclasses.replace(spec.vehicle, wheelbase_m=1.1 * spec.vehicle.wheelbase_m))
    assert max(right.excess_nrmse[2:]) < HYBRID_LIMIT  # the rear wheels (only the rear axle's fields fitted)
    for wrong in (leaves, long):
        print(f"rear model error: right {max(right.excess_nrmse[2:]):.3f}, wrong {max(wrong.excess_nrmse[2:]):.3f}")
        assert max(wrong.excess_nrmse[2:]) > 1.5 * max(right.excess_nrmse[2:])
    note = description_note(SimpleNamespace(excess_nrmse=(0.1, 0.1, 0.3, 0.1)), "TRUCK.toml")
    assert note.startswith("note: a model error of 0.30 on rl") and "'TRUCK.toml' [vehicle] wheelbase_m" in note
    assert description_note(SimpleNamespace(excess_nrmse=(0.1, 0.1, 0.1, 0.1)), "TRUCK.toml") == ""


def test_a_trial_truck_with_no_rest_is_the_worst_fit_not_the_end_of_the_calibration(tractor_record, monkeypatch):
    """A fit's trial far from its first guess may find no rest (soft air springs rolling a high load
    over): fit_window_job returns None where window_job raises NoRestError, and the fit's runs read
    it as a truck that predicts no force (zeros), so the residual is the whole measured force."""
    import numpy as np

    import rigsim.scenarios.records.model.problem as problem
    from rigsim.scenarios.records.model.model_runs import NoRestError, fit_window_job, window_job

    spec, plant, rig, force = tractor_record
    t, x = rig.t_s[:500], rig.signals["pan_m"][:500]
    tipping = TruckVariant(**{**{k: v for k, v in vars(spec.vehicle).items() if v is not None},
                              "payload_kg": 20000.0, "payload_z_m": 1.6, "spring_rate_rear_N_per_m": 2e4,
                              "spring_rate_front_N_per_m": 2e4})
    with pytest.raises(NoRestError, match="model truck"):
        window_job(tipping, t, x, spec, 0.5)
    assert fit_window_job(tipping, t, x, spec, 0.5) is None
    fake = SimpleNamespace(windows=[(0, 100, 300)], t=t, x_a=x, base=spec, executor=None, evaluations=0, step_s=None)
    monkeypatch.setattr(problem, "run_jobs", lambda jobs, executor=None: [None])
    out = problem.FitProblem.runs(fake, [tipping])
    assert out[0][0].shape == (300, 4) and not out[0][0].any() and fake.evaluations == 1
