"""The progressive tire (``TruckVariant.tire_progressive_ratio``, bilinear: one kink at the onset) and
its spread stiffening (``TruckVariant.tire_progressive_spread_m``: 5 elements over a span of deflection),
the plant feature the calibrated model's bilinear tire cannot represent.

References, independent of the code under test: the XML compiled directly by MuJoCo (the model
without the option); the tire's constants as truck_rig.xml's comment derives them (kt 0.9 MN/m per
steer tire, 1.8 MN/m per dual pair, free radius R0 = 0.527 m of an 11R22.5, 1.054 m overall
diameter), with which the second element's force is computed by hand, F2 = ratio kt (d - onset)
for a deflection d = R0 - L beyond the onset and 0 before it (with a spread, the sum of 5 such
elements of ratio kt / 5 at onsets written out by hand); MuJoCo's own ``actuator_force`` of each
element for the sums.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from rigsim.mjcf import names
from rigsim.mjcf.build import build_model, build_spec, resource_path
from rigsim.mjcf.variant import TruckVariant
from rigsim.mjcf.physics import RigIndex, static_equilibrium, tire_forces, tire_law
from rigsim.mjcf.tires import TIRE_PROGRESSIVE_ONSET_M
from rigsim.scenarios.core.config import ScenarioError, parse_scenario
from rigsim.scenarios.core.rig import Rig

KT = np.array([0.9e6, 0.9e6, 1.8e6, 1.8e6])  # N/m, truck_rig.xml's comment (Cebon 1999)
R0 = 0.527  # m, 11R22.5 free radius (Tire and Rim Association: 1.054 m overall diameter)
SHORT = {"name": "progressive", "speed_kmh": 72.0, "duration_s": 1.0, "lead_in_s": 0.5, "seed": 3,
         "road": {"roughness": "C"}}


def _ids(model, kind, name_of) -> np.ndarray:
    return np.array([mujoco.mj_name2id(model, kind, name_of(c)) for c in names.CORNERS])


def test_without_the_option_the_model_is_the_xml_as_shipped():
    """``tire_progressive_ratio`` None: the compiled actuators and sensors are the XML's, compiled by MuJoCo."""
    xml = mujoco.MjModel.from_xml_path(str(resource_path("scene.xml")))
    for variant in (None, TruckVariant(tire_progressive_ratio=None)):
        built = build_model(variant)
        for n in ("nu", "nsensor", "nsensordata", "na", "ntendon"):
            assert getattr(built, n) == getattr(xml, n), n
        for field in ("actuator_biasprm", "actuator_gainprm", "actuator_forcerange", "actuator_trnid",
                      "sensor_type", "sensor_objid", "sensor_adr"):
            assert np.array_equal(getattr(built, field), getattr(xml, field)), field
    assert np.all(_ids(built, mujoco.mjtObj.mjOBJ_ACTUATOR, names.tire_progressive_actuator) == -1)


def test_second_element_force_against_a_hand_computation():
    """Pans moved about the static rest (velocities zero): the second element's force is
    ratio kt (d - onset) beyond the onset and exactly 0 before it; the tire force sensor and
    ``tire_forces`` report kt d plus it (both elements)."""
    ratio, onset = 0.5, TIRE_PROGRESSIVE_ONSET_M
    model = build_model(TruckVariant(tire_progressive_ratio=ratio))
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    idx = RigIndex.of(model)
    extra = _ids(model, mujoco.mjtObj.mjOBJ_ACTUATOR, names.tire_progressive_actuator)
    assert np.array_equal(idx.tire_extra, extra) and np.array_equal(idx.tire_extra_corner, np.arange(4))
    tendon = _ids(model, mujoco.mjtObj.mjOBJ_TENDON, names.tire_tendon)
    sensor = model.sensor_adr[_ids(model, mujoco.mjtObj.mjOBJ_SENSOR, names.tire_sensor)]
    q0 = data.qpos.copy()
    seen = set()
    for dz in np.linspace(-0.02, 0.02, 9):
        data.qpos[:] = q0
        data.qpos[idx.pan_qpos] += dz * np.array([1.0, -1.0, 1.0, -1.0])
        mujoco.mj_forward(model, data)
        d = R0 - data.ten_length[tendon]
        hand = np.where(d > onset, ratio * KT * (d - onset), 0.0)
        np.testing.assert_allclose(data.actuator_force[extra], hand, rtol=1e-9, atol=1e-6)
        assert np.all(data.actuator_force[extra][d < onset] == 0.0)
        total = np.clip(KT * d, 0.0, None) + hand
        np.testing.assert_allclose(data.sensordata[sensor], total, rtol=1e-9, atol=1e-6)
        np.testing.assert_allclose(tire_forces(model, data, idx), total, rtol=1e-9, atol=1e-6)
        seen.update(bool(b) for b in (d > onset))
    assert seen == {True, False}  # both sides of the onset were visited


def test_a_rig_run_records_both_elements():
    """The rig test's recorded tire force (the tendon-force sensor) and the road test's (``tire_law``)
    carry the second element: with it the mean loads stay the weight and the force's fluctuation grows (a stiffer tire on the same road); every static load is the tire force plus
    the pan's weight (``Rig.static_loads_N`` through ``tire_forces``): in all the same weight."""
    plain = parse_scenario(SHORT)
    prog = dataclasses.replace(plain, vehicle=TruckVariant(tire_progressive_ratio=1.0, tire_progressive_onset_m=0.0))
    for mode in ("rig", "road"):
        a, b = Rig(plain, hydraulic=mode == "rig"), Rig(prog, hydraulic=mode == "rig")
        fa = a.run(a.road_source(), rate_hz=1000.0).tire_force_N
        fb = b.run(b.road_source(), rate_hz=1000.0).tire_force_N
        np.testing.assert_allclose(fb.mean(axis=0), fa.mean(axis=0), rtol=0.03)  # on average the weight
        assert np.all(fb.std(axis=0) > 1.2 * fa.std(axis=0)), (mode, fa.std(axis=0), fb.std(axis=0))
    loads, plain_loads = Rig(prog).static_loads_N(), Rig(plain).static_loads_N()
    assert loads.sum() == pytest.approx(plain_loads.sum(), rel=1e-9)  # the truck's and pans' weight
    np.testing.assert_allclose(loads, plain_loads, rtol=1e-3)  # the split: the stiffer tires tilt the truck slightly


def test_the_mocap_pans_give_the_second_element_no_damping():
    """Prescribed pans: the tire element's gain is its damping (ctrl carries the pan velocity), the
    progressive element's is 0 (it has none)."""
    model = build_spec(TruckVariant(tire_progressive_ratio=0.3), pans="mocap").compile()
    idx = RigIndex.of(model)
    assert np.array_equal(model.actuator_gainprm[idx.tire_actuator, 0], -model.actuator_biasprm[idx.tire_actuator, 2])
    assert np.all(model.actuator_gainprm[idx.tire_extra, 0] == 0.0)
    assert np.all(model.actuator_biasprm[idx.tire_extra, 2] == 0.0)


@pytest.mark.parametrize("vehicle,field", [({"tire_progressive_ratio": -0.1}, "tire_progressive_ratio"),
                                           ({"tire_progressive_ratio": 5.0}, "tire_progressive_ratio"),
                                           ({"tire_progressive_ratio": 0.5, "tire_progressive_onset_m": 0.3},
                                            "tire_progressive_onset_m"),
                                           ({"tire_progressive_onset_m": 0.01}, "tire_progressive_onset_m")])
def test_bad_progressive_tires_are_refused_naming_the_field(vehicle, field):
    with pytest.raises(ScenarioError, match=field):
        parse_scenario({**SHORT, "vehicle": vehicle})


# The spread progressive tire (``TruckVariant.tire_progressive_spread_m``): the stiffening split over
# 5 equal elements whose onsets are spread evenly over the span (ends included), computed by hand here.


def test_no_spread_compiles_the_single_kink():
    """Spread None and 0.0: the same compiled model, bit for bit, as the one-kink tire, whose one
    element per corner is ratio kt (R0 - onset - L) with the XML's kt and R0 (by hand)."""
    ratio, onset = 0.5, 0.02
    one = build_model(TruckVariant(tire_progressive_ratio=ratio, tire_progressive_onset_m=onset))
    xml = mujoco.MjModel.from_xml_path(str(resource_path("scene.xml")))
    assert one.nu == xml.nu + 4
    extra = _ids(one, mujoco.mjtObj.mjOBJ_ACTUATOR, names.tire_progressive_actuator)
    np.testing.assert_allclose(one.actuator_biasprm[extra, :3],
                               np.column_stack([ratio * KT * (R0 - onset), -ratio * KT, np.zeros(4)]), rtol=1e-12)
    for spread in (None, 0.0):
        built = build_model(TruckVariant(tire_progressive_ratio=ratio, tire_progressive_onset_m=onset,
                                         tire_progressive_spread_m=spread))
        for n in ("nu", "nsensor", "nsensordata", "ntendon"):
            assert getattr(built, n) == getattr(one, n), n
        for field in ("actuator_biasprm", "actuator_gainprm", "actuator_forcerange", "actuator_trnid",
                      "actuator_trntype", "actuator_biastype", "sensor_type", "sensor_objid", "sensor_adr"):
            assert np.array_equal(getattr(built, field), getattr(one, field)), field
        assert [built.actuator(i).name for i in range(built.nu)] == [one.actuator(i).name for i in range(one.nu)]
        assert all(mujoco.mj_name2id(built, mujoco.mjtObj.mjOBJ_ACTUATOR, f"tire_progressive_{c}_2") == -1
                   for c in names.CORNERS)


def test_spread_elements_force_against_a_hand_computation():
    """Ratio 0.5, onset 0.02 m, spread 0.02 m: 5 elements of 0.1 kt at onsets 0.01, 0.015, 0.02,
    0.025, 0.03 m (by hand: onset -/+ spread / 2 and 3 equal gaps between). Pans moved about the
    static rest (velocities zero): the elements' sum is sum_i 0.1 kt max(d - o_i, 0); the tire force
    sensor, ``tire_forces`` and ``tire_law`` report kt d plus it."""
    ratio = 0.5
    onsets = np.array([0.01, 0.015, 0.02, 0.025, 0.03])  # m, by hand
    model = build_model(TruckVariant(tire_progressive_ratio=ratio, tire_progressive_onset_m=0.02,
                                     tire_progressive_spread_m=0.02))
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    idx = RigIndex.of(model)
    tendon = _ids(model, mujoco.mjtObj.mjOBJ_TENDON, names.tire_tendon)
    sensor = model.sensor_adr[_ids(model, mujoco.mjtObj.mjOBJ_SENSOR, names.tire_sensor)]
    steps = np.array([[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, n)
                       for n in ([f"tire_progressive_{c}"] + [f"tire_progressive_{c}_{k}" for k in range(2, 6)])]
                      for c in names.CORNERS])  # (4, 5) by the names spelled by hand
    assert np.all(steps >= 0)
    q0 = data.qpos.copy()
    seen = np.zeros((4, 3), dtype=bool)  # per corner: below the span, inside it, beyond it
    for dz in np.linspace(-0.025, 0.025, 21):
        data.qpos[:] = q0
        data.qpos[idx.pan_qpos] += dz * np.array([1.0, -1.0, 1.0, -1.0])
        mujoco.mj_forward(model, data)
        d = R0 - data.ten_length[tendon]
        each = ratio / 5 * KT[:, None] * np.maximum(d[:, None] - onsets[None, :], 0.0)
        np.testing.assert_allclose(data.actuator_force[steps], each, rtol=1e-9, atol=1e-6)
        hand = each.sum(axis=1)
        total = np.clip(KT * d, 0.0, None) + hand
        np.testing.assert_allclose(data.sensordata[sensor], total, rtol=1e-9, atol=1e-6)
        np.testing.assert_allclose(tire_forces(model, data, idx), total, rtol=1e-9, atol=1e-6)
        np.testing.assert_allclose(tire_law(model, idx, data.ten_length[tendon], np.zeros(4)), total,
                                   rtol=1e-9, atol=1e-6)
        seen |= np.column_stack([d < 0.01, (d > 0.01) & (d < 0.03), d > 0.03])
    assert seen.all(), seen  # every corner below, inside and beyond the span


def test_the_rig_index_finds_every_spread_element():
    """20 extra elements, each corner 5 times in step order; with prescribed pans none has damping."""
    variant = TruckVariant(tire_progressive_ratio=0.25, tire_progressive_spread_m=0.02)
    model = build_model(variant)
    idx = RigIndex.of(model)
    assert idx.tire_extra.size == 20
    assert np.array_equal(np.bincount(idx.tire_extra_corner), [5, 5, 5, 5])
    by_name = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, names.tire_progressive_actuator(c, k))
               for c in names.CORNERS for k in range(5)]
    assert np.array_equal(idx.tire_extra, by_name) and np.array_equal(idx.tire_extra_corner, np.repeat(np.arange(4), 5))
    assert names.tire_progressive_actuator("rl", 4) == "tire_progressive_rl_5"
    assert sum(model.sensor(i).name.startswith("tire_force_") for i in range(model.nsensor)) == 4
    mocap = build_spec(variant, pans="mocap").compile()
    midx = RigIndex.of(mocap)
    assert midx.tire_extra.size == 20 and np.all(mocap.actuator_gainprm[midx.tire_extra, 0] == 0.0)


@pytest.mark.parametrize("vehicle,fix", [({"tire_progressive_spread_m": 0.01}, "set vehicle.tire_progressive_ratio"),
                                         ({"tire_progressive_ratio": 0.5, "tire_progressive_spread_m": 0.06},
                                          "outside 0 to 0.05 m"),
                                         ({"tire_progressive_ratio": 0.5, "tire_progressive_spread_m": -0.01}, ">= 0"),
                                         ({"tire_progressive_ratio": 0.5, "tire_progressive_onset_m": 0.005,
                                           "tire_progressive_spread_m": 0.02},
                                          "lower it or raise vehicle.tire_progressive_onset_m")])
def test_bad_spreads_are_refused_naming_the_field(vehicle, fix):
    with pytest.raises(ScenarioError, match="tire_progressive_spread_m") as err:
        parse_scenario({**SHORT, "vehicle": vehicle})
    assert fix in str(err.value)


def test_a_spread_reaching_zero_deflection_is_accepted():
    """onset - spread / 2 = 0 m exactly (0.01 - 0.02 / 2): the lowest element engages at contact."""
    parse_scenario({**SHORT, "vehicle": {"tire_progressive_ratio": 0.5, "tire_progressive_onset_m": 0.01,
                                         "tire_progressive_spread_m": 0.02}})


# The rear tires' own stiffening (``TruckVariant.tire_progressive_ratio_rear``, ``_onset_rear_m``):
# the rear corners' element takes them, the front corners' the all-wheel values.


def test_rear_tires_take_their_own_stiffening():
    """Ratio 0.5 at 2 cm, the rear's 0.25 at 1.5 cm: one element per corner, ratio kt (R0 - onset - L)
    with the XML's kt and R0 and each axle's ratio and onset (by hand); the rear fields None compile
    the all-wheel tire bit for bit, and a front ratio of 0 leaves the front tires linear."""
    model = build_model(TruckVariant(tire_progressive_ratio=0.5, tire_progressive_onset_m=0.02,
                                     tire_progressive_ratio_rear=0.25, tire_progressive_onset_rear_m=0.015))
    extra = _ids(model, mujoco.mjtObj.mjOBJ_ACTUATOR, names.tire_progressive_actuator)
    ratio, onset = np.array([0.5, 0.5, 0.25, 0.25]), np.array([0.02, 0.02, 0.015, 0.015])  # fl fr rl rr
    np.testing.assert_allclose(model.actuator_biasprm[extra, :3],
                               np.column_stack([ratio * KT * (R0 - onset), -ratio * KT, np.zeros(4)]), rtol=1e-12)
    every = build_model(TruckVariant(tire_progressive_ratio=0.5, tire_progressive_onset_m=0.02))
    same = build_model(TruckVariant(tire_progressive_ratio=0.5, tire_progressive_onset_m=0.02,
                                    tire_progressive_ratio_rear=None, tire_progressive_onset_rear_m=None))
    for field in ("actuator_biasprm", "actuator_gainprm", "actuator_forcerange", "sensor_type", "sensor_objid"):
        assert np.array_equal(getattr(same, field), getattr(every, field)), field
    rear_only = build_model(TruckVariant(tire_progressive_ratio=0.0, tire_progressive_ratio_rear=0.25))
    extra = _ids(rear_only, mujoco.mjtObj.mjOBJ_ACTUATOR, names.tire_progressive_actuator)
    assert np.array_equal(rear_only.actuator_biasprm[extra, 1], [-0.0, -0.0, -0.25 * KT[2], -0.25 * KT[3]])


@pytest.mark.parametrize("vehicle,field,fix", [
    ({"tire_progressive_ratio_rear": 0.25}, "tire_progressive_ratio_rear", "set vehicle.tire_progressive_ratio"),
    ({"tire_progressive_onset_rear_m": 0.01}, "tire_progressive_onset_rear_m", "set vehicle.tire_progressive_ratio"),
    ({"tire_progressive_ratio": 0.5, "tire_progressive_ratio_rear": 5.0}, "tire_progressive_ratio_rear",
     "outside 0 to 3 1"),
    ({"tire_progressive_ratio": 0.5, "tire_progressive_onset_rear_m": 0.2}, "tire_progressive_onset_rear_m",
     "outside 0 to 0.1 m"),
    ({"tire_progressive_ratio": 0.5, "tire_progressive_onset_rear_m": 0.005, "tire_progressive_spread_m": 0.02},
     "tire_progressive_spread_m", "raise vehicle.tire_progressive_onset_rear_m")])
def test_bad_rear_stiffening_is_refused_naming_the_field(vehicle, field, fix):
    with pytest.raises(ScenarioError, match=field) as err:
        parse_scenario({**SHORT, "vehicle": vehicle})
    assert fix in str(err.value)
