"""Each wheel station's own values and the truck's masses (rigsim.mjcf.stations): the plant's asymmetries.

References: the XML's nominal values (a factor scales exactly one station's element), statics
(an axle's own weight goes to its own wheels; the truck's weight to its tires), the damper law
F = -c dL/dt with c = c_b in bump and c_r in rebound (rigsim.mjcf.stations.rebound_coefficients).
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rigsim.mjcf import names
from rigsim.mjcf.build import build_model
from rigsim.mjcf.physics import static_equilibrium, tire_forces
from rigsim.mjcf.stations import STATION_FACTORS, rebound_coefficients, station_factor_field
from rigsim.mjcf.variant import BOUNDS, TruckVariant

OBJ = mujoco.mjtObj
G = 9.81


def _id(model, kind, name):
    i = mujoco.mj_name2id(model, kind, name)
    assert i >= 0, name
    return i


def _station_values(model) -> dict[str, np.ndarray]:
    """Per corner: tire stiffness, tire damping, spring rate, spring damping, spring friction."""
    tire = [_id(model, OBJ.mjOBJ_ACTUATOR, names.tire_actuator(c)) for c in names.CORNERS]
    spring = [_id(model, OBJ.mjOBJ_TENDON, names.spring_tendon(c)) for c in names.CORNERS]
    return {"tire_stiffness": -model.actuator_biasprm[tire, 1], "tire_damping": -model.actuator_biasprm[tire, 2],
            "spring_rate": np.asarray(model.tendon_stiffness)[spring].reshape(4, -1)[:, 0],
            "spring_damping": np.asarray(model.tendon_damping)[spring].reshape(4, -1)[:, 0],
            "spring_friction": model.tendon_frictionloss[spring]}


@pytest.mark.parametrize("quantity", list(STATION_FACTORS))
@pytest.mark.parametrize("corner", names.CORNERS)
def test_a_station_factor_scales_that_station_only(quantity, corner):
    nominal = _station_values(build_model())
    changed = _station_values(build_model(TruckVariant(**{station_factor_field(quantity, corner): 1.25})))
    k = names.CORNERS.index(corner)
    for q, values in changed.items():
        expected = nominal[q].copy()
        if q == quantity:
            expected[k] *= 1.25
        np.testing.assert_allclose(values, expected, rtol=1e-12, err_msg=q)
    # the tire's free radius is kept: F = kt (R0 - L) with the XML's R0
    tire = _id(build_model(), OBJ.mjOBJ_ACTUATOR, names.tire_actuator(corner))
    m0, m1 = build_model(), build_model(TruckVariant(**{station_factor_field(quantity, corner): 1.25}))
    assert m1.actuator_biasprm[tire, 0] / m1.actuator_biasprm[tire, 1] == pytest.approx(
        m0.actuator_biasprm[tire, 0] / m0.actuator_biasprm[tire, 1], rel=1e-12)


def test_a_station_factor_applies_on_the_axle_value_and_before_the_progressive_tire():
    model = build_model(TruckVariant(tire_stiffness_front_N_per_m=1.0e6, tire_stiffness_factor_fr=0.8,
                                     spring_friction_front_N=1500.0, spring_friction_factor_fl=2.0,
                                     tire_progressive_ratio=0.5))
    values = _station_values(model)
    assert values["tire_stiffness"][:2] == pytest.approx([1.0e6, 0.8e6])
    assert values["spring_friction"][:2] == pytest.approx([3000.0, 1500.0])
    k2 = [-model.actuator_biasprm[_id(model, OBJ.mjOBJ_ACTUATOR, names.tire_progressive_actuator(c)), 1]
          for c in ("fl", "fr")]
    assert k2 == pytest.approx([0.5e6, 0.4e6])  # the ratio of each station's own kt


@pytest.mark.parametrize("ratio", [1.0, 2.0, 3.5])
def test_rebound_coefficients_keep_the_mean(ratio):
    bump, rebound = rebound_coefficients(6000.0, ratio)
    assert (bump + rebound) / 2 == pytest.approx(6000.0)
    assert rebound / bump == pytest.approx(ratio)


@pytest.mark.parametrize("axle_velocity", [-0.2, 0.2])
def test_the_rebound_damper_resists_extension_harder_than_compression(axle_velocity):
    """Spring tendon force from damping, F = -c dL/dt: c_r while the spring extends (the axle moving
    away from the frame, down), c_b while it compresses; their mean the XML's 6 kN s/m."""
    ratio = 3.0
    model = build_model(TruckVariant(damper_rebound_ratio=ratio))
    data = mujoco.MjData(model)
    data.qvel[model.jnt_dofadr[_id(model, OBJ.mjOBJ_JOINT, "front_axle_z")]] = axle_velocity
    mujoco.mj_forward(model, data)
    spring = _id(model, OBJ.mjOBJ_TENDON, names.spring_tendon("fl"))
    rate = data.ten_velocity[spring]
    assert np.sign(rate) == -np.sign(axle_velocity)  # the axle moving down extends the spring
    act = _id(model, OBJ.mjOBJ_ACTUATOR, names.spring_rebound_actuator("fl"))
    bump, rebound = rebound_coefficients(6000.0, ratio)
    viscous = -np.asarray(model.tendon_damping)[spring].reshape(-1)[0] * rate
    total = viscous + data.actuator_force[act]
    assert total == pytest.approx(-(rebound if rate > 0 else bump) * rate, rel=1e-9)


def test_no_rebound_element_without_the_ratio():
    for variant in (TruckVariant(), TruckVariant(damper_rebound_ratio=1.0)):
        model = build_model(variant)
        assert mujoco.mj_name2id(model, OBJ.mjOBJ_ACTUATOR, names.spring_rebound_actuator("fl")) == -1
        assert model.nu == 4


@pytest.mark.parametrize("field, axle, extra_kg", [("axle_mass_front_kg", 0, 200.0), ("axle_mass_rear_kg", 1, -300.0)])
def test_an_axles_own_weight_goes_to_its_own_wheels(field, axle, extra_kg):
    """Statics: the chassis' springs carry the same forces (vertical and pitch balance of the chassis
    fix each axle's spring-force sum), so an axle's added weight adds to its own tires' sum only."""
    nominal_kg = {0: 700.0, 1: 1200.0}[axle]

    def axle_sums(variant):
        model = build_model(variant)
        data = mujoco.MjData(model)
        static_equilibrium(model, data)
        f = tire_forces(model, data)
        return np.array([f[:2].sum(), f[2:].sum()])

    base = axle_sums(TruckVariant(payload_kg=5000.0))
    changed = axle_sums(TruckVariant(payload_kg=5000.0, **{field: nominal_kg + extra_kg}))
    expected = base.copy()
    expected[axle] += extra_kg * G
    np.testing.assert_allclose(changed, expected, rtol=2e-4)


def test_an_axle_mass_scales_its_inertia():
    m0, m1 = build_model(), build_model(TruckVariant(axle_mass_rear_kg=1800.0))
    rear = _id(m0, OBJ.mjOBJ_BODY, "rear_axle")
    assert m1.body_mass[rear] == pytest.approx(1800.0)
    np.testing.assert_allclose(m1.body_inertia[rear], m0.body_inertia[rear] * 1.5, rtol=1e-12)


def test_chassis_mass_and_moments():
    m0 = build_model()
    m1 = build_model(TruckVariant(chassis_mass_kg=6000.0, chassis_roll_inertia_kg_m2=3000.0,
                                  chassis_pitch_inertia_kg_m2=20_000.0))
    chassis = _id(m0, OBJ.mjOBJ_BODY, "chassis")
    assert m1.body_mass[chassis] == pytest.approx(6000.0)
    roll, pitch, yaw = m1.body_inertia[chassis]
    assert (roll, pitch) == pytest.approx((3000.0, 20_000.0))
    r0, p0, y0 = m0.body_inertia[chassis]
    assert yaw / (roll + pitch) == pytest.approx(y0 / (r0 + p0))
    assert roll + pitch >= yaw


def test_a_softer_spring_unloads_its_diagonal():
    """Warp: on four pans at one height a softer spring lets its corner sink, and the diagonal through
    it (rl with fr) carries less than the other (fl with rr); each axle's sum is statics' and stays,
    but for the shift of the centre of mass as the sunk corner pitches the truck (< 0.1 %)."""
    def forces(variant):
        model = build_model(variant)
        data = mujoco.MjData(model)
        static_equilibrium(model, data)
        return tire_forces(model, data)

    base = forces(TruckVariant(payload_kg=5000.0))
    soft = forces(TruckVariant(payload_kg=5000.0, spring_rate_factor_rl=0.7))
    assert soft[2] + soft[1] < soft[0] + soft[3] - 100.0
    np.testing.assert_allclose([soft[:2].sum(), soft[2:].sum()], [base[:2].sum(), base[2:].sum()], rtol=1e-3)


def test_payload_height():
    model = build_model(TruckVariant(payload_z_m=1.2))
    assert model.body_pos[_id(model, OBJ.mjOBJ_BODY, "payload")][2] == pytest.approx(1.2)


@pytest.mark.parametrize("field", [station_factor_field(q, "rr") for q in STATION_FACTORS]
                         + ["payload_z_m", "axle_mass_front_kg", "axle_mass_rear_kg", "chassis_mass_kg",
                            "chassis_roll_inertia_kg_m2", "chassis_pitch_inertia_kg_m2", "damper_rebound_ratio"])
def test_each_new_field_is_bounded_and_named_in_the_error(field):
    lo, hi, _, _ = BOUNDS[field]
    TruckVariant(**{field: lo})
    TruckVariant(**{field: hi})
    with pytest.raises(ValueError, match=f"vehicle.{field} = .* is outside"):
        TruckVariant(**{field: hi * 1.01})
    with pytest.raises(ValueError, match=f"vehicle.{field}"):
        TruckVariant(**{field: float("nan")})


def test_a_station_factor_may_not_take_the_tire_past_its_axles_bounds():
    with pytest.raises(ValueError, match="tire_stiffness_front_N_per_m x vehicle.tire_stiffness_factor_fl .* nearer 1"):
        TruckVariant(tire_stiffness_front_N_per_m=9e7, tire_stiffness_factor_fl=1.2)
    with pytest.raises(ValueError, match="tire_damping_rear_Ns_per_m x vehicle.tire_damping_factor_rr"):
        TruckVariant(tire_damping_rear_Ns_per_m=4e4, tire_damping_factor_rr=2.0)


def test_nominal_values_are_the_xmls():
    """The XML's numbers as written in truck_rig.xml (tire law F = kt R0 - kt L - ct dL/dt)."""
    from rigsim.mjcf.build import nominal_values

    v = nominal_values()
    assert v == pytest.approx({"payload_kg": 3640.0, "payload_x_m": -1.3, "payload_y_m": 0.0, "payload_z_m": 0.56,
                               "tire_stiffness_front_N_per_m": 9e5, "tire_stiffness_rear_N_per_m": 1.8e6,
                               "tire_damping_front_Ns_per_m": 1500.0, "tire_damping_rear_Ns_per_m": 3000.0,
                               "tire_free_radius_m": 0.527, "spring_friction_front_N": 1000.0,
                               "spring_friction_rear_N": 2000.0, "pan_mass_kg": 500.0, "axle_mass_front_kg": 700.0,
                               "axle_mass_rear_kg": 1200.0, "chassis_mass_kg": 5200.0,
                               "chassis_roll_inertia_kg_m2": 2600.0, "chassis_pitch_inertia_kg_m2": 25200.0})
    assert set(v) <= set(TruckVariant.field_names())
