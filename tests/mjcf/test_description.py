"""A truck of its own (mjcf/description.py, mjcf/standing.py): geometry, suspension kinds, refusal of a truck
that cannot stand.

References, independent of the code under test: the XML as compiled (a description of no fields, or of
the XML's own values, must compile the same numbers); the lever rule by hand on the wheelbase; an air
spring's static deflection F / k (a constant-frequency spring: k proportional to the load it carries,
so F / k is the same at any payload, and the ride frequency sqrt(k g / F) / 2 pi too); the design gap
0.3 m of truck_rig.xml.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rigsim.mjcf import description, names
from rigsim.mjcf.build import build_model
from rigsim.mjcf.physics import static_equilibrium, tire_forces
from rigsim.mjcf.standing import check_stands, truck_layout
from rigsim.mjcf.variant import TruckVariant

G = 9.81  # m/s^2, the model's gravity


def _rest(variant):
    model = build_model(variant, pans="fixed")
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    return model, data


def _spring(model, corner):
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, names.spring_tendon(corner))


def _arrays(model):
    return [model.body_pos, model.body_ipos, model.body_inertia, model.body_mass, model.site_pos,
            model.tendon_stiffness, model.tendon_damping, model.tendon_lengthspring, model.tendon_frictionloss,
            model.actuator_biasprm]


def test_the_xml_values_described_compile_the_xml():
    xml = build_model(TruckVariant(payload_kg=3640.0))
    same = build_model(TruckVariant(payload_kg=3640.0, wheelbase_m=5.0, track_front_m=2.05, track_rear_m=1.83,
                                    rear_tires="dual", suspension_front="leaf", suspension_rear="leaf",
                                    spring_rate_front_N_per_m=3e5, spring_rate_rear_N_per_m=7e5,
                                    spring_damping_front_Ns_per_m=6e3, spring_damping_rear_Ns_per_m=1e4))
    for a, b in zip(_arrays(xml), _arrays(same)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_a_shorter_wheelbase_moves_axles_pans_and_sites_and_splits_by_the_lever_rule():
    wb, x_payload = 3.8, -1.0
    model, data = _rest(TruckVariant(payload_kg=5000.0, payload_x_m=x_payload, wheelbase_m=wb))
    design = mujoco.MjData(model)
    mujoco.mj_kinematics(model, design)
    layout = truck_layout(model, data)
    assert layout["wheelbase_m"] == pytest.approx(wb, abs=1e-12)
    for corner in names.CORNERS:  # every pan under its wheel centre at the design pose
        wheel = design.site_xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, names.wheel_site(corner))]
        pan = design.xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, names.pan_body(corner))]
        np.testing.assert_allclose(wheel[:2], pan[:2], atol=1e-12)
    # Lever rule by hand: chassis 5200 kg at 40 % of the wheelbase behind the front axle (60 % front),
    # payload at -1.0 m: (x + wb/2) / wb front, axles wholly on their own wheels.
    front = G * (5200 * 0.6 + 5000 * (x_payload + wb / 2) / wb + 700)
    rear = G * (5200 * 0.4 + 5000 * (wb / 2 - x_payload) / wb + 1200)
    loads = tire_forces(model, data)
    assert loads[:2].sum() == pytest.approx(front, rel=2e-3)
    assert loads[2:].sum() == pytest.approx(rear, rel=2e-3)


def test_tracks_move_wheels_and_pans():
    model, data = _rest(TruckVariant(payload_kg=3640.0, track_front_m=2.0, track_rear_m=1.95))
    layout = truck_layout(model, data)
    assert layout["track_front_m"] == pytest.approx(2.0, abs=1e-12)
    assert layout["track_rear_m"] == pytest.approx(1.95, abs=1e-12)
    pans_y = [model.body_pos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, names.pan_body(c)), 1]
              for c in names.CORNERS]
    np.testing.assert_allclose(pans_y, [1.0, -1.0, 0.975, -0.975], atol=1e-12)


@pytest.mark.parametrize("payload_kg", (0.0, 3640.0, 6360.0))
def test_an_air_axle_is_levelled_and_its_rate_follows_its_load(payload_kg):
    model, data = _rest(TruckVariant(payload_kg=payload_kg, suspension_rear="air"))
    rate = description.AIR_RATE_N_PER_M["rear"]
    # The empty catalogue truck's rear spring load by the lever rule: 5200 kg x 0.4 / 2 springs.
    empty = G * 5200 * 0.4 / 2
    for corner in names.REAR:
        i = _spring(model, corner)
        gap = data.ten_length[i]
        assert gap == pytest.approx(0.3, abs=2e-3)  # levelled at the design gap
        force = model.tendon_stiffness[i] * (model.tendon_lengthspring[i, 0] - gap)
        # constant static deflection F / k = F_empty / k_empty: the same ride frequency at any load
        assert force / model.tendon_stiffness[i] == pytest.approx(empty / rate, rel=0.02)
        assert model.tendon_frictionloss[i] == 0.0
        assert model.tendon_damping[i] == description.AIR_DAMPING_NS_PER_M["rear"]
    front = _spring(model, "fl")
    assert model.tendon_frictionloss[front] == 1e3  # the front leaves keep the XML's friction


def test_an_air_spring_given_friction_keeps_it():
    model = build_model(TruckVariant(suspension_front="air", spring_friction_front_N=150.0))
    assert model.tendon_frictionloss[_spring(model, "fl")] == 150.0


def test_a_given_leaf_rate_keeps_the_design_ride_height():
    model, data = _rest(TruckVariant(payload_kg=3640.0, spring_rate_rear_N_per_m=4.5e5))
    i = _spring(model, "rl")
    assert model.tendon_stiffness[i] == 4.5e5
    assert data.ten_length[i] == pytest.approx(0.3, abs=2e-3)


def test_wide_single_rear_tires():
    model = build_model(TruckVariant(rear_tires="single"))
    geom = lambda n: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, n)  # noqa: E731
    assert geom("wheel_rl") >= 0 and geom("wheel_rl_outer") < 0 and geom("wheel_rl_inner") < 0
    tire = model.actuator_biasprm[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, names.tire_actuator("rl"))]
    assert -tire[1] == description.SINGLE_TIRE_STIFFNESS_N_PER_M
    assert -tire[2] == description.SINGLE_TIRE_DAMPING_NS_PER_M
    given = build_model(TruckVariant(rear_tires="single", tire_stiffness_rear_N_per_m=1.2e6))
    tire = given.actuator_biasprm[mujoco.mj_name2id(given, mujoco.mjtObj.mjOBJ_ACTUATOR, names.tire_actuator("rr"))]
    assert -tire[1] == 1.2e6


def test_a_word_field_takes_only_its_words():
    with pytest.raises(ValueError, match=r"vehicle.suspension_rear must be 'leaf' or 'air'"):
        TruckVariant(suspension_rear="coil")
    with pytest.raises(ValueError, match=r"vehicle.wheelbase_m = 9 m is outside 3 to 7 m"):
        TruckVariant(wheelbase_m=9.0)


def test_a_truck_that_cannot_stand_is_refused_naming_the_field():
    # 9 t behind the rear axle of a 3.6 m truck: the steer tires leave their pans.
    with pytest.raises(ValueError, match=r"fl tire .* lifts off .*vehicle.payload_x_m"):
        check_stands(TruckVariant(payload_kg=9000.0, payload_x_m=-3.4, wheelbase_m=3.6))
    # Soft leaves under 14 t: the rear springs close onto their stops.
    with pytest.raises(ValueError, match=r"rl spring closes onto its bump stop.*vehicle.spring_rate_rear_N_per_m"):
        check_stands(TruckVariant(payload_kg=14000.0, spring_rate_rear_N_per_m=1.5e5))
    check_stands(TruckVariant(payload_kg=6360.0, wheelbase_m=3.8, suspension_rear="air", rear_tires="single"))


def test_a_truck_that_leans_over_on_soft_air_springs_is_refused():
    """Air on both axles (101 and 61 kN/m at the empty load) under 6.9 t: at a payload height of 1.4 m
    the rest is one the body rolls away from, at 1.0 m it stands. The growth rate is the same as the
    rig's closed loop under that truck gave with the pans on their actuators (fleet suite, fresh draw
    of seed 185872953, truck 5: pole 0.681 1/s on the rig, 0.678 1/s here; seed 754827997, truck 14:
    0.207 and 0.205), where the rig's refusal named the actuator's gains."""
    air = dict(wheelbase_m=3.74, rear_tires="dual", suspension_front="air", suspension_rear="air",
               spring_rate_front_N_per_m=101e3, spring_rate_rear_N_per_m=61e3, payload_kg=6900.0)
    with pytest.raises(ValueError, match=r"does not stand upright at rest: its body roll grows at 0\.5\d* 1/s .*"
                                         r"vehicle\.spring_rate_rear_N_per_m, or lower vehicle\.payload_z_m"):
        check_stands(TruckVariant(**air, payload_z_m=1.4))
    with pytest.raises(ValueError, match=r"body roll grows at 0\.05"):  # slower nearer the edge
        check_stands(TruckVariant(**air, payload_z_m=1.2))
    check_stands(TruckVariant(**air, payload_z_m=1.0))
