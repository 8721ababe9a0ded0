"""The progressive tire (``TruckVariant.tire_progressive_ratio``): the plant feature the calibrated
model's linear tire lacks (issue 17, second round).

References, independent of the code under test: the XML compiled directly by MuJoCo (the model
without the option); the tire's constants as truck_rig.xml's comment derives them (kt 0.9 MN/m per
steer tire, 1.8 MN/m per dual pair, free radius R0 = 0.527 m of an 11R22.5, 1.054 m overall
diameter), with which the second element's force is computed by hand, F2 = ratio kt (d - onset)
for a deflection d = R0 - L beyond the onset and 0 before it; MuJoCo's own ``actuator_force`` of
each element for the sums.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from mjcf import names
from mjcf.build import TruckVariant, build_model, build_spec, resource_path
from mjcf.physics import RigIndex, static_equilibrium, tire_forces
from mjcf.tires import TIRE_PROGRESSIVE_ONSET_M
from scenarios.core.config import ScenarioError, parse_scenario
from scenarios.core.rig import Rig

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
