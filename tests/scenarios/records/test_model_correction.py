"""The model correction: differential correction, calibration from rig signals, fallback.

Short records (8 s of the paper's medium 72 km/h case) so that the file runs in well under a minute;
the plant differs from the XML's nominal truck (:func:`plant_scenario`), so calibration has work to do.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rigsim.mjcf.physics import tire_forces
from rigsim.mjcf.variant import TruckVariant
from rigsim.scenarios.core.config import ScenarioError, load_scenario, paper_scenarios
from rigsim.scenarios.core.pool import local_executor, run_jobs
from rigsim.scenarios.core.rig import Rig
from rigsim.scenarios.core.run import run
from rigsim.scenarios.studies import scoring
from rigsim.scenarios.records.model.calibrate import calibrate, with_sigma
from rigsim.scenarios.records.model.family import (AIR_FITTED, DAMPER_FITTED, DEFAULT_NAMES, EMPTY_STAND_IN,
                                                   ENGINE_FITTED, FITTED, FRAME_FITTED, STATION_FITTED)
from rigsim.scenarios.records.model.first_guess import (CATALOGUE_CAB_MOUNT_HZ, CATALOGUE_TIRE_RATIO, catalogue,
                                                        empty_truck_kg, is_light, xml_nominal)
from rigsim.scenarios.records.model.differential import correct_with_model, differential_correction, settled_mask
from rigsim.scenarios.records.model.fallback import DIFFERENTIAL_LIMIT
from rigsim.scenarios.records.model.model_runs import model_scenario, pan_motion_drive
from rigsim.scenarios.studies.correction_score import score_correction

DURATION_S = 8.0


def _paper(stem: str) -> str:
    return str(next(p for p in paper_scenarios() if stem in p.stem))


def plant_scenario(stem: str = "medium_72"):
    """A paper case with a plant truck that is not the XML's nominal one: payload -5 % and 0.1 m forward, tire
    stiffness +10 % front / -10 % rear of the XML's; tire damping and leaf friction at the calibration's
    catalogue values (XML x 1.15 or 0.85), its cab rigid and its tire linear, so that a fit of the
    payload and the tire stiffness alone has nothing else to absorb (the benchmark fits all of them on a plant off
    the catalogue in every field)."""
    sc = load_scenario(_paper(stem))
    nominal = xml_nominal()
    plant = TruckVariant(payload_kg=0.95 * sc.vehicle.payload_kg, payload_x_m=nominal["payload_x_m"] + 0.1,
                         tire_stiffness_front_N_per_m=1.1 * nominal["tire_stiffness_front_N_per_m"],
                         tire_stiffness_rear_N_per_m=0.9 * nominal["tire_stiffness_rear_N_per_m"],
                         **{k: v for k, v in catalogue().items()
                            if "stiffness" not in k and k != "cab_mount_hz" and not k.startswith("tire_progressive")})
    return dataclasses.replace(sc, duration_s=DURATION_S, vehicle=plant)


def _run(stem: str, mode: str):
    return run(plant_scenario(stem), mode)


@pytest.fixture(scope="module")
def record():
    """Road and rig runs of the medium case's plant, and a rig run of another case (high, 72 km/h)."""
    road, rig, other = run_jobs([(_run, ("medium_72", "road")), (_run, ("medium_72", "rig")),
                                 (_run, ("high_72", "rig"))], workers=2)
    sc = plant_scenario()
    measured = scoring.measured_force(rig, scoring.NOISE_N, sc.seed)
    other_measured = scoring.measured_force(other, scoring.NOISE_N, sc.seed)
    return {"sc": sc, "t": rig.t_s, "x_ref": rig.signals["profile_m"], "x_a": rig.signals["pan_m"],
            "F_rig": measured, "F_road": road.signals["tire_force_N"], "F_other": other_measured}


def test_the_pan_motion_is_splined_onto_the_model_steps():
    """The 1 kHz motion onto the road test's 1e-4 s steps: through every sample, the velocity of a 10 Hz sine
    within 0.1 % (a cubic spline's error at 100 samples per period is ~1e-5), held during the lead-in."""
    t = np.arange(0, 1.0001, 1e-3)
    z = 0.01 * np.sin(2 * np.pi * 10 * t)[:, None] * np.ones(4)
    drive = pan_motion_drive(t, z, 1e-4, settle_s=0.05)
    ahead = drive.t_s >= -1e-12
    assert drive.t_s[0] == pytest.approx(-0.05) and np.all(drive.z_m[~ahead] == z[0]) and np.all(drive.v_mps[~ahead] == 0)
    np.testing.assert_allclose(drive.z_m[ahead][::10], z, atol=1e-12)
    v = 0.01 * 2 * np.pi * 10 * np.cos(2 * np.pi * 10 * drive.t_s[ahead])
    inner = (drive.t_s[ahead] > 0.05) & (drive.t_s[ahead] < 0.95)
    assert np.max(np.abs(drive.v_mps[ahead][inner, 0] - v[inner])) < 1e-3 * np.max(np.abs(v))


def test_exact_model_differential_correction_beats_the_rig_by_far(record):
    """With the plant's own truck as the model, F_rig + F_model(x_ref) - F_model(x_a) reaches the road force to
    NRMSE ~0.01 (0.008 on the 60 s case; measured on this 8 s record 0.013-0.015 per wheel,
    0.009-0.012 at 20 s), against 0.71-0.78 for the uncorrected rig force: a factor 49-60 here. Pinned at
    > 25 and < 0.025 absolute; DLC within 1 % (measured 0.3 %)."""
    sc, t = record["sc"], record["t"]
    corrected = differential_correction(sc.vehicle, t, record["x_ref"], record["x_a"], record["F_rig"],
                                        base_scenario=sc, workers=2)
    rows = settled_mask(t)
    model = score_correction(corrected, record["F_road"], 1000.0, rows)
    rig = score_correction(record["F_rig"], record["F_road"], 1000.0, rows)
    assert np.all(rig["nrmse"] > 0.5), rig["nrmse"]
    assert np.all(model["nrmse"] < 0.025), model["nrmse"]
    assert np.all(rig["nrmse"] / model["nrmse"] > 25.0)
    assert np.all(np.abs(model["dlc_error"]) < 0.01), model["dlc_error"]


def test_calibration_recovers_the_plant_from_rig_signals(record):
    """Calibration from x_a and F_rig only: the payload (static guess then fit) within 2 % of the plant's, the
    tire stiffness per axle (catalogue guess 23 % / 28 % off the plant) within 5 %, and the fit NRMSE against
    F_rig at least halved on every wheel."""
    sc, t = record["sc"], record["t"]
    names = ("payload_kg", "tire_stiffness_front_N_per_m", "tire_stiffness_rear_N_per_m")
    # max_nfev 5: the Jacobian after the first is a Broyden update (problem.REUSE_MAX), a cheaper
    # step than a finite-difference one, so three evaluations leave the rear stiffness 6 % off, five 1 %
    cal = calibrate(t, record["x_a"], record["F_rig"], base_scenario=sc, x_ref_m=record["x_ref"], names=names,
                    windows=1, window_s=1.5, lead_s=2.0, max_nfev=5, workers=2)
    fitted = dict(zip(cal.names, cal.fitted))
    truth = sc.vehicle
    assert abs(fitted["payload_kg"] / truth.payload_kg - 1) < 0.02
    assert abs(cal.initial[1] / truth.tire_stiffness_front_N_per_m - 1) > 0.2  # the guess was far off
    assert abs(fitted["tire_stiffness_front_N_per_m"] / truth.tire_stiffness_front_N_per_m - 1) < 0.05
    assert abs(fitted["tire_stiffness_rear_N_per_m"] / truth.tire_stiffness_rear_N_per_m - 1) < 0.05
    assert np.all(np.array(cal.fit_nrmse) < 0.5 * np.array(cal.initial_nrmse)), (cal.fit_nrmse, cal.initial_nrmse)
    assert cal.fixed["spring_friction_front_N"] == pytest.approx(catalogue()["spring_friction_front_N"])
    assert cal.fixed["cab_mount_hz"] is None  # not named, not given: the XML's rigid cab, not the 2.5 Hz guess
    assert cal.fixed["tire_progressive_ratio"] is None  # and its linear tire, not the +20 % guess
    assert all(s > 0 for s in cal.sigma) and len(cal.sigma_robust) == len(names)
    # the load cells' share of the fit NRMSE: their 100 N rms (scoring.NOISE_N) over the force's std on the window
    a, b = cal.windows_s[0]
    std = record["F_rig"][(t >= a - 1e-9) & (t < b - 1e-9)].std(axis=0)
    np.testing.assert_allclose(cal.noise_nrmse, scoring.NOISE_N / std, rtol=0.05)
    assert all(e < f for e, f in zip(cal.excess_nrmse, cal.fit_nrmse))


def test_the_cab_is_fitted_only_on_request():
    """The default family holds the cab rigid (a smooth road may not pin its mount frequency: see
    family.DEFAULT_NAMES); FITTED, the fields that can be fitted, has it."""
    assert "cab_mount_hz" in FITTED and "cab_mount_hz" not in DEFAULT_NAMES
    assert set(DEFAULT_NAMES) == set(FITTED) - {"cab_mount_hz", "chassis_roll_inertia_kg_m2", *EMPTY_STAND_IN.values(),
                                                *AIR_FITTED, *FRAME_FITTED, *ENGINE_FITTED,
                                                *DAMPER_FITTED}  # roll, frame, engine, dampers: on a described truck only


def test_forces_of_another_case_fall_back_to_the_linear_correction(record):
    """F_rig of another case (high roughness, 3640 kg) with this case's x_a: no truck reproduces it (fit NRMSE
    measured 1.03-1.18, against 0.05-0.07 for its own forces), and the answer is the linear correction with one
    sentence why."""
    sc, t = record["sc"], record["t"]
    out = correct_with_model(t, record["x_ref"], record["x_a"], record["F_other"], base_scenario=sc, workers=2,
                             names=("payload_kg", "spring_friction_front_N"), windows=1, window_s=2.0, lead_s=2.0,
                             max_nfev=2)
    assert out.use_linear and out.corrected_N is None
    assert out.calibration is not None and max(out.calibration.excess_nrmse) > DIFFERENTIAL_LIMIT
    assert out.reason.endswith("so the linear correction is to be used.")
    assert out.reason.count(". ") == 0 and out.reason[0].islower()


def test_forces_with_no_truck_in_them_fall_back_before_any_model_run(record):
    """Forces of the wrong sign imply a negative payload: refused by the static guess, one sentence."""
    out = correct_with_model(record["t"], record["x_ref"], record["x_a"], -record["F_rig"],
                             base_scenario=record["sc"], workers=1, windows=1, window_s=2.0, lead_s=2.0)
    assert out.use_linear and out.calibration is None
    assert "payload" in out.reason and out.reason.endswith("so the linear correction is to be used.")


def test_a_malformed_record_is_refused_before_any_run(record):
    with pytest.raises(ScenarioError, match="force_N"):
        correct_with_model(record["t"], record["x_ref"], record["x_a"], record["F_rig"][:, :3],
                           base_scenario=record["sc"])
    with pytest.raises(ScenarioError, match="shorter than a calibration window"):
        calibrate(record["t"][:2000], record["x_a"][:2000], record["F_rig"][:2000], base_scenario=record["sc"])


@pytest.mark.parametrize("drift_hz", [0.0, -0.5, float("nan"), 500.0])
def test_a_drift_corner_outside_the_band_is_refused_before_any_run(drift_hz, monkeypatch):
    """The hybrid's drift cut (rigsim.correction.output.denoise.check_drift_hz, the noise gain's own check)
    refused at the call, not after minutes of calibration: the calibration is never reached."""
    from rigsim.scenarios.records.model import differential

    def never(*_a, **_k):
        raise AssertionError("the calibration ran")

    monkeypatch.setattr(differential, "calibrate_truck", never)
    t = np.arange(0.0, 12.0, 1e-3)
    z = np.zeros((t.size, 4))
    with pytest.raises(ScenarioError, match=r"drift_hz must be None \(no drift cut\) or a corner in Hz between 0 "
                                            r"and fs / 2 \(500 Hz\)"):
        correct_with_model(t, z, z, z + 3.0e4, base_scenario=plant_scenario(), drift_hz=drift_hz)


def _road_record(**changes):
    """The road test of the medium case's plant with ``changes`` to its truck, and the force its load
    cells measure (100 N of noise): ``(scenario, road run, force)``."""
    sc = plant_scenario()
    sc = dataclasses.replace(sc, vehicle=dataclasses.replace(sc.vehicle, **changes))
    road = run(sc, "road")
    return sc, road, scoring.measured_force(road, scoring.NOISE_N, sc.seed)


def _fit_window(sc, road, force, names, guess=None, **options):
    """``names`` calibrated on one 3 s window (2 s lead-in) of the road record, every other field of
    FITTED but the cab's held at the plant's (``guess`` on top)."""
    held = {k: getattr(sc.vehicle, k) for k in FITTED if k not in names and k != "cab_mount_hz"}
    return calibrate(road.t_s, road.signals["pan_m"], force, base_scenario=sc, names=names,
                     fitted_guess=held | (guess or {}), windows=1, window_s=3.0, lead_s=2.0, workers=2, **options)


def test_calibration_recovers_a_cab_mount_frequency():
    """A short synthetic record: the road test (pans following the road exactly) of the medium case's plant
    with its cab on 2 Hz mounts, plus the load cells' 100 N noise. The cab's mount frequency fitted alone
    from the catalogue guess (2.5 Hz, 25 % off), the other fields held at the plant's (``fitted_guess``):
    recovered within 2 % from one 3 s window, and the fit NRMSE against F_rig falls by more than half."""
    sc, road, force = _road_record(cab_mount_hz=2.0)
    plant = sc.vehicle
    held = {k: getattr(plant, k) for k in FITTED
            if k not in ("cab_mount_hz", "payload_z_m", "chassis_roll_inertia_kg_m2", *EMPTY_STAND_IN.values())
            and not k.startswith("tire_progressive")
            and k not in STATION_FITTED + AIR_FITTED + FRAME_FITTED + ENGINE_FITTED + DAMPER_FITTED}
    assert all(v is not None for v in held.values())  # the stations: held symmetric, the plant's
    cal = calibrate(road.t_s, road.signals["pan_m"], force, base_scenario=sc, names=("cab_mount_hz",),
                    fitted_guess=held, windows=1, window_s=3.0, lead_s=2.0, max_nfev=6, workers=2)
    assert cal.initial == (CATALOGUE_CAB_MOUNT_HZ,)
    assert abs(cal.fitted[0] / 2.0 - 1) < 0.02, cal.fitted
    assert max(cal.fit_nrmse) < 0.5 * max(cal.initial_nrmse), (cal.fit_nrmse, cal.initial_nrmse)


def test_calibration_recovers_a_progressive_tire():
    """As for the cab: the road test of the medium case's plant with tires that stiffen by 40 % beyond 3 cm
    of deflection (``TruckVariant.tire_progressive_ratio``, ``tire_progressive_onset_m``), 100 N of noise;
    the ratio and onset fitted from the catalogue's +20 % at the front wheels' static load (the onset's
    first guess, :mod:`rigsim.scenarios.records.model.onset_load`: 2.66 cm), the other fields held at
    the plant's: both recovered within 3 % from one 3 s window (measured 0.3954 and 3.000 cm; stopped at
    4 residual evaluations the ratio is still at 0.25, at 6 at 0.38), and the fit NRMSE falls by more
    than half (0.34-0.44 to 0.05-0.06, the noise's share)."""
    sc, road, force = _road_record(tire_progressive_ratio=0.4, tire_progressive_onset_m=0.03)
    plant = sc.vehicle
    cal = _fit_window(sc, road, force, ("tire_progressive_ratio", "tire_progressive_onset_m"), max_nfev=20)
    # the onset starts at the front wheels' median load over the 3 s scored (2-5 s): their static deflection
    static_m = np.median(force[2000:5000, :2]) / plant.tire_stiffness_front_N_per_m
    assert cal.initial == pytest.approx((CATALOGUE_TIRE_RATIO, static_m), rel=1e-12) and CATALOGUE_TIRE_RATIO == 0.2
    assert cal.converged, cal.message
    np.testing.assert_allclose(cal.fitted, (0.4, 0.03), rtol=0.03)
    assert max(cal.fit_nrmse) < 0.5 * max(cal.initial_nrmse), (cal.fit_nrmse, cal.initial_nrmse)


def test_calibration_recovers_the_payload_height():
    """As for the cab: the road test of the medium case's plant with its payload's centre of mass
    0.3 m above the XML's (0.86 m, ``TruckVariant.payload_z_m``: a taller stack), 100 N of noise; the
    height fitted from the XML's 0.56 m with the front tires' damping (catalogue guess, the plant's),
    the other fields held at the plant's: recovered within 3 cm from one 3 s window (the static
    loads say nothing of it; only the body's motion does), and the fit NRMSE falls by more than half."""
    sc, road, force = _road_record(payload_z_m=0.86)
    cal = _fit_window(sc, road, force, ("payload_z_m", "tire_damping_front_Ns_per_m"), max_nfev=12)
    assert cal.initial[0] == xml_nominal()["payload_z_m"] == 0.56 and cal.converged, cal.message
    assert abs(cal.values()["payload_z_m"] - 0.86) < 0.03, cal.values()
    assert max(cal.fit_nrmse) < 0.5 * max(cal.initial_nrmse), (cal.fit_nrmse, cal.initial_nrmse)


def test_uncertainties_left_for_later_are_the_fits_own():
    """calibrate(sigma=False) and then with_sigma (the cab choice's order, the pool still running)
    give the uncertainties calibrate computes at once: the same finite-difference Jacobian at the
    same optimum (the fit is deterministic); until then they are NaN and the state has no Jacobian."""
    sc, road, force = _road_record(payload_z_m=0.86)
    names = ("payload_z_m", "tire_damping_front_Ns_per_m")
    held = {k: getattr(sc.vehicle, k) for k in FITTED if k not in names and k != "cab_mount_hz"}
    kw = dict(base_scenario=sc, names=names, fitted_guess=held, windows=1, window_s=3.0, lead_s=2.0, max_nfev=6)
    with local_executor(2) as ex:
        now = calibrate(road.t_s, road.signals["pan_m"], force, executor=ex, **kw)
        later, state = calibrate(road.t_s, road.signals["pan_m"], force, executor=ex, with_state=True, sigma=False,
                                 **kw)
        assert np.isnan(later.sigma).all() and np.isnan(later.sigma_robust).all() and state.jacobian is None
        done, state = with_sigma(later, state)
    assert done.fitted == now.fitted and done.evaluations == now.evaluations
    np.testing.assert_allclose(done.sigma, now.sigma, rtol=1e-9)
    np.testing.assert_allclose(done.sigma_robust, now.sigma_robust, rtol=1e-9)
    assert np.all(np.asarray(now.sigma) > 0) and state.jacobian.shape == (state.residual.size, 2)
    with pytest.raises(ScenarioError, match="with_state=True"):  # NaN uncertainties with no way to complete them
        calibrate(road.t_s, road.signals["pan_m"], force, sigma=False, **kw)


@pytest.mark.parametrize("payload_kg", [0.0, 500.0], ids=["empty", "light"])
def test_an_empty_or_light_truck_fits_the_chassis_pitch_inertia_in_the_payload_heights_place(payload_kg):
    """The same on the medium case's plant emptied, or loaded with 500 kg (7 % of the empty truck,
    below first_guess.LIGHT_FRACTION), its chassis' pitch inertia 30 % above the XML's (32 760 kg m^2,
    a chassis with its tanks and equipment): the static loads make it an empty or a light truck,
    whose payload height barely moves its pitch inertia; the chassis' pitch inertia is fitted in its
    place (family.EMPTY_STAND_IN), from the XML's 25 200 kg m^2, and recovered within 5 % from one
    3 s window."""
    plant_inertia = 1.3 * xml_nominal()["chassis_pitch_inertia_kg_m2"]
    sc, road, force = _road_record(payload_kg=payload_kg, chassis_pitch_inertia_kg_m2=plant_inertia)
    held = {k: getattr(sc.vehicle, k) for k in FITTED
            if k not in ("payload_kg", "payload_x_m", "payload_z_m", "cab_mount_hz", *EMPTY_STAND_IN.values())}
    cal = calibrate(road.t_s, road.signals["pan_m"], force, base_scenario=sc, names=("payload_z_m",),
                    fitted_guess=held, windows=1, window_s=3.0, lead_s=2.0, workers=2, max_nfev=12)
    assert cal.names == ("chassis_pitch_inertia_kg_m2",) and cal.initial == (25200.0,)
    assert abs(cal.fitted[0] / plant_inertia - 1) < 0.05, cal.fitted
    assert cal.fixed["payload_kg"] == pytest.approx(payload_kg, abs=30.0)


def test_a_payload_is_light_below_a_tenth_of_the_empty_truck():
    """first_guess.is_light against the catalogue truck's own weight (its static loads over g, a
    second path to the same number: the XML's masses summed)."""
    sc = plant_scenario()
    rig = Rig(model_scenario(TruckVariant(payload_kg=0.0, **catalogue()), sc, 1.0, 0.5), hydraulic=False)
    empty_kg = empty_truck_kg(sc)
    assert empty_kg == pytest.approx(rig.truck_mass_kg, rel=1e-3)
    assert is_light(0.09 * empty_kg, sc) and is_light(0.0, sc) and not is_light(0.11 * empty_kg, sc)
@pytest.mark.parametrize("plant, rtol, fall", [
    ({"tire_stiffness_factor_fl": 0.85, "spring_rate_factor_rl": 1.1}, (0.03, 0.03), 0.5),
    ({"spring_friction_factor_fl": 1.6, "spring_friction_factor_rl": 0.6}, (0.05, 0.05), 0.5),
    ({"tire_damping_factor_fl": 1.5, "tire_damping_factor_rl": 0.7}, (0.02, 0.08), 0.6),
], ids=["tire-and-spring-rate", "leaf-friction", "tire-damping"])
def test_calibration_recovers_a_left_right_difference(plant, rtol, fall):
    """The per-station family (family.STATION_FITTED, fitted by default): the road test of the medium
    case's plant whose left stations differ from their right neighbours (rigsim.mjcf.stations: each factor
    scales the left station's value), 100 N of noise; the two left factors fitted from 1 (a symmetric
    truck), the axles' and every other value held at the plant's: both recovered, and the worst
    wheel's fit NRMSE falls to ``fall`` of where it started or below (the noise's share is left).
    The front-left tire 15 % softer and the rear-left spring 10 % stiffer within 3 %; the front-left
    leaves rubbing 1.6 times and the rear-left 0.6 times their neighbours' within 5 % (measured 1.595,
    0.609; fit NRMSE 0.11-0.26 to 0.056-0.067); the front-left tire damping 1.5 times its
    neighbour's within 2 % and the rear-left 0.7 times within 8 % (measured 1.496, 0.744: the rear's
    stiff dual tires carry little damping force, robust sigma 0.018; worst fit NRMSE 0.115 ->
    0.062). A symmetric model cannot do this: it splits the difference and errs on both wheels of the
    axle, in opposite directions."""
    sc, road, force = _road_record(**plant)
    names = tuple(plant)
    assert set(names) <= set(STATION_FITTED) <= set(DEFAULT_NAMES)
    cal = _fit_window(sc, road, force, names, max_nfev=20)
    assert cal.initial == (1.0, 1.0)
    assert cal.converged, cal.message
    for got, want, tol in zip(cal.fitted, plant.values(), rtol):
        assert got == pytest.approx(want, rel=tol), (cal.names, cal.fitted)
    assert max(cal.fit_nrmse) < fall * max(cal.initial_nrmse), (cal.fit_nrmse, cal.initial_nrmse)


def test_calibration_recovers_each_axles_stiffening():
    """As above with each axle's own stiffening (the default family): front tires +40 % beyond 3 cm, rear
    +25 % beyond 2.2 cm (the heavy truck's rear static deflection is about 2 cm, its fronts' about 3 cm,
    so both cross their onsets), the four fitted from the catalogue's +20 % at each axle's static load,
    the rest held at the plant's: all four within 3 % (measured 0.394, 3.000 cm, 0.248, 2.192 cm; stopped
    at 4 residual evaluations the front ratio is still at 0.25, at 6 at 0.38), the fit NRMSE more than
    halved."""
    sc, road, force = _road_record(tire_progressive_ratio=0.4, tire_progressive_onset_m=0.03,
                                   tire_progressive_ratio_rear=0.25, tire_progressive_onset_rear_m=0.022)
    plant = sc.vehicle
    names = ("tire_progressive_ratio", "tire_progressive_onset_m", "tire_progressive_ratio_rear",
             "tire_progressive_onset_rear_m")
    cal = _fit_window(sc, road, force, names, max_nfev=20)
    static_m = np.median(force[2000:5000, :2]) / plant.tire_stiffness_front_N_per_m, \
        np.median(force[2000:5000, 2:]) / plant.tire_stiffness_rear_N_per_m  # each axle's median load (2-5 s)
    assert cal.initial == pytest.approx((0.2, static_m[0], 0.2, static_m[1]), rel=1e-12)
    assert cal.converged, cal.message
    np.testing.assert_allclose(cal.fitted, (0.4, 0.03, 0.25, 0.022), rtol=0.03)
    assert max(cal.fit_nrmse) < 0.5 * max(cal.initial_nrmse), (cal.fit_nrmse, cal.initial_nrmse)


def test_an_onset_given_beyond_the_measured_loads_starts_at_the_static_load():
    """A rear onset of 4 cm given as the first guess: at the rear tires' stiffness that load lies beyond
    every rear load of the window, where neither the onset nor the ratio moves a model force. The
    calibration starts it at the rear's median load instead (onset_load.load_guess: 2.33 cm) and
    recovers the plant's +25 % at 2.2 cm within 3 % (measured 0.247, 2.191 cm; rear fit NRMSE 0.13 ->
    0.055). Searched in metres from 4 cm, the onset would never move (measured: 0.2 and 4 cm, "gtol"
    after one residual and its Jacobian, rear fit NRMSE 0.29 as it starts)."""
    sc, road, force = _road_record(tire_progressive_ratio_rear=0.25, tire_progressive_onset_rear_m=0.022,
                                   tire_progressive_ratio=0.0)
    plant = sc.vehicle
    assert force[2000:5000, 2:].max() < 0.04 * plant.tire_stiffness_rear_N_per_m  # the guess lies beyond them
    cal = _fit_window(sc, road, force, ("tire_progressive_ratio_rear", "tire_progressive_onset_rear_m"),
                      guess={"tire_progressive_onset_rear_m": 0.04}, max_nfev=20)
    static_m = np.median(force[2000:5000, 2:]) / plant.tire_stiffness_rear_N_per_m
    assert cal.initial == pytest.approx((0.2, static_m), rel=1e-12)
    np.testing.assert_allclose(cal.fitted, (0.25, 0.022), rtol=0.03)


def test_a_stiffening_beyond_every_measured_load_is_held_linear(monkeypatch):
    """An onset fitted at the top of its load range leaves its ratio where the fit wandered (no measured
    load lies beyond it); the calibration sets that ratio to 0 and says so. Forced here: the optimizer's
    answer is moved to the onset's upper bound (the walk-through's front tires end there by
    themselves, ratio 0.70)."""
    import scipy.optimize

    real = scipy.optimize.least_squares

    def to_the_top(fun, x0, *args, bounds, **kwargs):
        res = real(fun, x0, *args, bounds=bounds, **{**kwargs, "max_nfev": 2})
        res.x = np.array(res.x, float)
        res.x[1] = bounds[1][1]  # names below: (ratio, onset)
        return res

    monkeypatch.setattr(scipy.optimize, "least_squares", to_the_top)
    sc, road, force = _road_record()
    cal = _fit_window(sc, road, force, ("tire_progressive_ratio", "tire_progressive_onset_m"))
    assert cal.fitted[0] == 0.0 and cal.fitted[1] == pytest.approx(cal.bounds[1][1])
    assert "tire_progressive_ratio set to 0 (its onset lies beyond every measured load)" in cal.message


def test_the_onset_alone_is_refused_before_any_run(record):
    with pytest.raises(ScenarioError, match="tire_progressive_onset_m"):
        calibrate(record["t"], record["x_a"], record["F_rig"], base_scenario=record["sc"],
                  names=("payload_kg", "tire_progressive_onset_m"))
    with pytest.raises(ScenarioError, match="tire_progressive_onset_m"):  # a held linear tire has no onset either
        calibrate(record["t"], record["x_a"], record["F_rig"], base_scenario=record["sc"],
                  names=("payload_kg", "tire_progressive_onset_m"), fitted_guess={"tire_progressive_ratio": None})
    for rear in ("tire_progressive_ratio_rear", "tire_progressive_onset_rear_m"):  # the rear's: only with the ratio
        with pytest.raises(ScenarioError, match=rear):
            calibrate(record["t"], record["x_a"], record["F_rig"], base_scenario=record["sc"], names=("payload_kg", rear))


def test_an_empty_truck_is_held_empty_not_refused():
    """The static loads of an empty truck put the payload a few kg either side of zero (the
    generalization suite's four empty cases: -11 to -6 kg, not to be refused as 'no payload'): within
    EMPTY_FRACTION of the empty truck's weight it is an empty truck, (0 kg, the XML's x), and the
    calibration holds it; so is a truck up to LIGHTER_FRACTION lighter than the catalogue's (another
    body or axles); a real payload (500 kg, the loads of the catalogue truck carrying it) is still
    estimated, to within 1 %, and loads further below the empty truck's are still refused."""
    from rigsim.scenarios.records.model.first_guess import EMPTY_FRACTION, LIGHTER_FRACTION, static_guess
    from rigsim.scenarios.records.model.model_runs import static_axle_loads

    sc = load_scenario(_paper("high_48"))
    empty = static_axle_loads(TruckVariant(payload_kg=0.0, **catalogue()), sc)
    g = 9.80665
    limit = EMPTY_FRACTION * empty.sum() / g
    assert 50.0 < limit < 150.0  # ~1 % of a ~7.6 t truck
    lighter = LIGHTER_FRACTION * empty.sum() / g
    for kg in (-0.5 * limit, 0.0, 0.5 * limit, -500.0, -0.99 * lighter):
        payload, x = static_guess(np.tile(empty + kg * g / 4, (10, 1)), sc)
        assert (payload, x) == (0.0, xml_nominal()["payload_x_m"])
    loaded = static_axle_loads(TruckVariant(payload_kg=500.0, **catalogue()), sc)
    payload, _ = static_guess(np.tile(loaded, (10, 1)), sc)
    assert payload == pytest.approx(500.0, rel=0.01)
    with pytest.raises(ScenarioError, match="payload"):
        static_guess(np.tile(empty - 1.05 * lighter * g / 4, (10, 1)), sc)


def test_a_light_payload_off_the_truck_is_the_trucks_own_balance_not_a_wiring_fault():
    """The front/rear split of a light payload (below LIGHT_FRACTION of the empty truck) is the empty
    truck's own balance off the catalogue's: the fleet suite's fresh empty truck read as 74 kg whose
    lever-rule place was x = -6.94 m, and the calibration was refused as miswired. Such a payload is
    placed at the nearest end of the bed (PAYLOAD_X_LIMIT_M, the fit's bound); a load (3 t) whose
    split puts it as far off the truck is still refused, naming the front and rear channels. The
    lever rule x = x_r + (x_f - x_r) dF_front / dF is the reference: a split of -0.9 puts a payload
    0.9 wheelbases behind the rear axle."""
    from rigsim.scenarios.records.model.first_guess import LIGHT_FRACTION, PAYLOAD_X_LIMIT_M, static_guess
    from rigsim.scenarios.records.model.model_runs import static_axle_loads

    sc = load_scenario(_paper("high_48"))
    empty = static_axle_loads(TruckVariant(payload_kg=0.0, **catalogue()), sc)
    g = 9.80665

    def split(kg, front_share):  # the empty truck's loads and kg more, front_share of it on the front axle
        return np.tile(empty + kg * g / 2 * np.array([front_share, front_share, 1 - front_share, 1 - front_share]), (10, 1))

    light = 0.3 * LIGHT_FRACTION * empty.sum() / g
    for share, end in ((-0.9, -1.0), (1.9, 1.0)):
        payload, x = static_guess(split(light, share), sc)
        assert payload == pytest.approx(light, rel=1e-3) and x == end * PAYLOAD_X_LIMIT_M
    payload, x = static_guess(split(light, 0.5), sc)  # a light payload on the truck keeps its place
    assert abs(x) < PAYLOAD_X_LIMIT_M
    with pytest.raises(ScenarioError, match="off the truck .* front and rear"):
        static_guess(split(3000.0, -0.9), sc)


def test_the_payloads_lateral_offset_comes_from_the_left_right_moment():
    """The measured static loads' moment about the centreline pins the payload's lateral offset
    (moment balance about the x axis, the truck rolled on its springs): the nominal truck's loads
    with a payload 0.2 m left or 0.4 m right give it back on the catalogue truck to within 5 mm; a
    centred payload, or one within LATERAL_FLOOR_M, is on the centreline; a moment no payload on
    the bed explains (left and right channels swapped on one axle) is refused in one sentence."""
    from rigsim.scenarios.records.model.first_guess import LATERAL_FLOOR_M, static_guess, static_lateral
    from rigsim.scenarios.records.model.model_runs import static_axle_loads

    sc = load_scenario(_paper("high_48"))
    for y in (0.2, -0.4, 0.0, 0.5 * LATERAL_FLOOR_M):
        loads = np.tile(static_axle_loads(TruckVariant(payload_kg=5000.0, payload_y_m=y), sc), (10, 1))
        payload, x = static_guess(loads, sc)
        got = static_lateral(loads, sc, payload, x)
        assert got == (pytest.approx(y, abs=5e-3) if abs(y) >= LATERAL_FLOOR_M else 0.0)
    loads = static_axle_loads(TruckVariant(payload_kg=5000.0, payload_y_m=0.3), sc)
    swapped = np.tile(loads[[0, 1, 3, 2]] * np.array([1.0, 1.0, 3.0, 0.2]), (10, 1))
    with pytest.raises(ScenarioError, match="off the centreline, off the bed"):
        static_lateral(swapped, sc, 5000.0, -1.3)


def test_a_twisted_first_pose_rests_and_runs():
    """A record whose first pan pose is twisted 45 mm on the diagonal (generalization case gen11's
    third window starts so): Newton from the mid-stroke pose finds no rest there, the continuation
    from mid-stroke does (rigsim.mjcf.physics.static_equilibrium), with every tire loaded and the loads
    carrying the truck (their sum the same as on level pans); the twist moves load onto one diagonal.
    A pose that even the continuation cannot rest on starts on its planar part, twisted in over the
    settling lead-in (a half-cosine, at rest at both ends): that drive checked on this pose. The run's
    forces are finite and every wheel stays loaded."""
    from rigsim.scenarios.core.rig import Rig
    from rigsim.scenarios.records.model.model_runs import model_forces, pan_motion_drive, planar_part

    sc = load_scenario(_paper("high_48"))
    rig = Rig(sc, hydraulic=False)
    tw = 0.045
    first = np.array([tw, -tw, -tw, tw])
    level = tire_forces(rig.model, rig.rest_state(), rig.index)
    twisted = tire_forces(rig.model, rig.rest_state(pan_z_m=first), rig.index)
    assert twisted.min() > 0.5 * level.min()
    assert twisted.sum() == pytest.approx(level.sum(), rel=1e-5)  # the tilted pans: 2e-6
    assert twisted[0] + twisted[3] > level[0] + level[3]  # the raised diagonal (fl, rr) carries more
    flat = planar_part(rig, first)
    assert np.abs(flat).max() < 0.1 * tw  # nearly all twist (the rear track is narrower than the front)
    rig.rest_state(pan_z_m=flat)  # and the truck rests on its planar part
    t = np.arange(2000) * 1e-3
    pan = first[None, :] * np.cos(2 * np.pi * 0.5 * t)[:, None]
    drive = pan_motion_drive(t, pan, rig.dt_s, start_m=flat)
    lead = drive.t_s < 0
    np.testing.assert_allclose(drive.z_m[0], flat, atol=1e-15)
    np.testing.assert_allclose(drive.z_m[~lead][0], first, atol=1e-15)
    assert np.abs(drive.v_mps[0]).max() < 1e-12 and np.abs(drive.v_mps[lead][-1]).max() < 1e-3
    force = model_forces(TruckVariant(), t, pan, base_scenario=sc)
    assert np.all(np.isfinite(force)) and force.min() > 0.0


def test_formal_uncertainties_are_the_least_squares_standard_errors():
    """For a straight-line fit the formal 1-sigma is the textbook OLS standard error,
    sqrt(s^2 (X^T X)^-1) with s^2 = RSS / (m - p) (e.g. Montgomery & Peck, Introduction to Linear
    Regression Analysis, eq. 2.14); with a white residual the block-robust one agrees to sampling
    error, and a residual correlated over a block makes the robust one larger."""
    from rigsim.scenarios.records.model.uncertainty import uncertainties

    rng = np.random.default_rng(7)
    x = np.linspace(0.0, 1.0, 4000)
    jac = np.column_stack([x, np.ones_like(x)])
    r = rng.normal(0.0, 0.3, x.size)
    beta, *_ = np.linalg.lstsq(jac, 2.0 * x + 1.0 + r, rcond=None)
    res = 2.0 * x + 1.0 + r - jac @ beta
    formal, robust = uncertainties(jac, res, block=25)
    s2 = res @ res / (x.size - 2)
    np.testing.assert_allclose(formal, np.sqrt(s2 * np.diag(np.linalg.inv(jac.T @ jac))), rtol=1e-12)
    assert np.all(np.abs(robust / formal - 1) < 0.3)
    walk = np.repeat(rng.normal(0.0, 0.3, x.size // 100), 100)  # constant over 100 rows: correlated
    _, robust_corr = uncertainties(jac, walk - jac @ np.linalg.lstsq(jac, walk, rcond=None)[0], block=25)
    formal_corr, _ = uncertainties(jac, walk - jac @ np.linalg.lstsq(jac, walk, rcond=None)[0], block=25)
    assert np.all(robust_corr > 2.0 * formal_corr)
