"""Tests of the truck-on-rig MJCF model (mjcf/).

References are independent of the code under test: the total weight is the sum of the
compiled body masses times g; the front/rear split is the lever rule on the actual body
positions; tire deflection is measured geometrically between sites; the frequency bands are
Cebon's (Handbook of Vehicle-Road Interaction, 1999: body bounce 1.5-4 Hz, axle hop 8-15 Hz).
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rigsim.mjcf.build import build_model, build_spec, resource_path
from rigsim.mjcf.variant import TruckVariant
from rigsim.mjcf.names import CORNERS
from rigsim.mjcf.physics import RigIndex, static_equilibrium, tire_forces
from rigsim.mjcf.modes import modal_analysis

G = 9.81  # m/s^2, the model's gravity (checked below)
PAPER_PAYLOADS_KG = (3640.0, 6360.0)  # the paper's two payloads


def _rest(payload_kg: float, pans: str = "slide", **kw):
    model = build_model(TruckVariant(payload_kg=payload_kg, **kw), pans=pans)
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    return model, data


def _site(model, data, name):
    return data.site_xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, name)].copy()


def test_gravity_is_standard():
    model = build_model()
    assert np.allclose(model.opt.gravity, [0, 0, -G])


@pytest.mark.parametrize("payload_kg", PAPER_PAYLOADS_KG)
def test_static_wheel_loads_sum_to_weight_and_split_by_lever_rule(payload_kg):
    model, data = _rest(payload_kg)
    forces = tire_forces(model, data)
    truck_bodies = ["chassis", "payload", "front_axle", "rear_axle"]
    bid = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in truck_bodies]
    masses = model.body_mass[bid]
    weight = masses.sum() * G
    # Reference 1: the sum of all truck body masses times g (not the solver's output).
    assert forces.sum() == pytest.approx(weight, rel=1e-3)
    assert masses[1] == pytest.approx(payload_kg)

    # Reference 2: lever rule on the actual centres of mass and wheel-centre positions.
    x_com = data.xipos[bid, 0]
    x_front = _site(model, data, "wheel_fl")[0]
    x_rear = _site(model, data, "wheel_rl")[0]
    front_share = (x_com - x_rear) / (x_front - x_rear)
    front_expected = G * np.sum(masses * front_share)
    front = forces[0] + forces[1]
    rear = forces[2] + forces[3]
    print(f"payload {payload_kg:.0f} kg: wheel loads {np.round(forces)} N, front {front:.0f} N, rear {rear:.0f} N")
    assert front == pytest.approx(front_expected, rel=1e-3)
    assert rear == pytest.approx(weight - front_expected, rel=1e-3)
    # Laterally symmetric truck: left equals right.
    assert forces[0] == pytest.approx(forces[1], rel=1e-9)
    assert forces[2] == pytest.approx(forces[3], rel=1e-9)


#: The calibration's first guess for an empty truck with stiffening tires (gen15 of the generalization suite):
#: catalogue tires whose rear ones stiffen beyond 6.3 mm, less than their static deflection.
_STIFFENING = dict(tire_stiffness_front_N_per_m=765000.0, tire_stiffness_rear_N_per_m=2070000.0,
                   tire_damping_front_Ns_per_m=1725.0, tire_damping_rear_Ns_per_m=2550.0, spring_friction_front_N=850.0,
                   spring_friction_rear_N=2300.0, tire_progressive_ratio=0.2, tire_progressive_onset_m=0.02455,
                   tire_progressive_ratio_rear=0.2, tire_progressive_onset_rear_m=0.0063, payload_x_m=-1.3)


@pytest.mark.parametrize("tires", ["xml", "stiffening"])
def test_the_empty_truck_rests_on_pans_pitched_45_mm(tires):
    """A rough road's first sample (class D at 100 km/h: front pans +12.1 mm, rear -33.4 mm): Newton from
    the mid-stroke pose starts with the empty truck's rear tires off their pans (no restoring force, a
    singular step); the rest is reached from mid-stroke (physics.CONTINUATION_STEP; the stiffening tires need
    steps shorter than a quarter of the way). Checked against the
    statics, not the solver: the tire loads carry the truck's weight (sum of its body masses times g),
    every tire is loaded, and the truck is at rest there (no joint acceleration)."""
    model = build_model(TruckVariant(payload_kg=0.0, **(_STIFFENING if tires == "stiffening" else {})), pans="slide")
    data = mujoco.MjData(model)
    pans = np.array([0.0121, 0.0121, -0.0334, -0.0334])
    static_equilibrium(model, data, pan_z_m=pans)
    idx = RigIndex.of(model)
    np.testing.assert_allclose(data.qpos[idx.pan_qpos], pans, atol=1e-12)
    forces = tire_forces(model, data)
    bid = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in ("chassis", "payload", "front_axle", "rear_axle")]
    assert forces.sum() == pytest.approx(model.body_mass[bid].sum() * G, rel=1e-3)
    assert np.all(forces > 0.1 * forces.mean())
    assert np.max(np.abs(data.qacc[idx.truck_dof])) < 1e-8


def test_heavier_payload_loads_the_rear_more():
    f_light = tire_forces(*_rest(3640.0))
    f_heavy = tire_forces(*_rest(6360.0))
    assert f_heavy[2] - f_light[2] > f_heavy[0] - f_light[0] > 0


@pytest.mark.parametrize("corner,k_nominal", [("fl", 0.9e6), ("fr", 0.9e6), ("rl", 1.8e6), ("rr", 1.8e6)])
def test_tire_force_linear_in_geometric_deflection_and_zero_after_liftoff(corner, k_nominal):
    """Force against deflection measured between the wheel-centre and pan sites.

    Expected stiffness: the value stated in truck_rig.xml (0.9 MN/m per steer tire, dual
    pair 1.8 MN/m), and the value a TruckVariant sets (1.1 MN/m) - the model must honour it.
    """
    for k_set in (None, 1.1e6):
        key = "tire_stiffness_front_N_per_m" if corner in ("fl", "fr") else "tire_stiffness_rear_N_per_m"
        model, data = _rest(3640.0, **({key: k_set} if k_set else {}))
        k_expected = k_set or k_nominal
        idx = RigIndex.of(model)
        i = CORNERS.index(corner)
        r0 = 0.527  # free radius of an 11R22.5 tire, as stated in truck_rig.xml
        deflections, forces = [], []
        for z in np.linspace(-0.01, 0.01, 9):  # stays in contact (static deflection >= 16 mm)
            data.qpos[idx.pan_qpos[i]] = z
            mujoco.mj_forward(model, data)
            gap = np.linalg.norm(_site(model, data, f"wheel_{corner}") - _site(model, data, f"pan_{corner}"))
            deflections.append(r0 - gap)
            forces.append(tire_forces(model, data)[i])
        slope, intercept = np.polyfit(deflections, forces, 1)
        assert slope == pytest.approx(k_expected, rel=0.01)
        assert abs(intercept) < 0.01 * max(forces)
        residual = np.array(forces) - (slope * np.array(deflections) + intercept)
        assert np.max(np.abs(residual)) < 0.01 * max(forces)
        # Lift-off: pan far below the free radius -> exactly zero force (unilateral).
        data.qpos[idx.pan_qpos[i]] = -0.07
        data.qvel[idx.pan_dof[i]] = -1.0  # even while moving apart (no sticky damping)
        mujoco.mj_forward(model, data)
        assert tire_forces(model, data)[i] == 0.0
        data.qvel[:] = 0.0


def test_tire_damping_honoured():
    """A pan velocity v changes the tire force by ct v (ct = 1.5 kN s/m front, truck_rig.xml)."""
    model, data = _rest(3640.0)
    idx = RigIndex.of(model)
    f0 = tire_forces(model, data)[0]
    data.qvel[idx.pan_dof[0]] = 0.2  # pan moving up at 0.2 m/s compresses the tire
    mujoco.mj_forward(model, data)
    # rel 1e-4: the tendon is tilted by the chassis pitch at rest (~2 mrad), so the pan's
    # vertical velocity projects onto it with cos(tilt) ~ 1 - 2e-6.
    assert tire_forces(model, data)[0] - f0 == pytest.approx(1500.0 * 0.2, rel=1e-4)


@pytest.mark.parametrize("payload_kg", PAPER_PAYLOADS_KG)
def test_natural_frequencies_in_cebon_bands(payload_kg):
    model, data = _rest(payload_kg, pans="fixed")
    modes = {m.name: m for m in modal_analysis(model, data)}
    print(f"\npayload {payload_kg:.0f} kg, pans fixed, leaf friction off:")
    for m in modes.values():
        print(f"  {m.name:16s} {m.frequency_hz:6.2f} Hz  damping ratio {m.damping_ratio:.3f}")
    for name in ("body bounce", "body pitch"):
        assert 1.5 <= modes[name].frequency_hz <= 4.0, name
    for name in ("front axle hop", "rear axle hop"):
        assert 8.0 <= modes[name].frequency_hz <= 15.0, name
    # Second, independent estimate of the front axle hop: the axle alone on its two tires
    # and two springs, chassis held still: sqrt(2 (kt + ks) / m) with XML values.
    f_single = np.sqrt(2 * (0.9e6 + 3e5) / 700.0) / (2 * np.pi)
    assert modes["front axle hop"].frequency_hz == pytest.approx(f_single, rel=0.03)


def test_every_element_named_with_parallel_corners():
    model = build_model()
    kinds = {
        "body": (mujoco.mjtObj.mjOBJ_BODY, model.nbody, 1),  # skip the world body
        "joint": (mujoco.mjtObj.mjOBJ_JOINT, model.njnt, 0),
        "geom": (mujoco.mjtObj.mjOBJ_GEOM, model.ngeom, 0),
        "site": (mujoco.mjtObj.mjOBJ_SITE, model.nsite, 0),
        "tendon": (mujoco.mjtObj.mjOBJ_TENDON, model.ntendon, 0),
        "actuator": (mujoco.mjtObj.mjOBJ_ACTUATOR, model.nu, 0),
        "sensor": (mujoco.mjtObj.mjOBJ_SENSOR, model.nsensor, 0),
        "camera": (mujoco.mjtObj.mjOBJ_CAMERA, model.ncam, 0),
        "light": (mujoco.mjtObj.mjOBJ_LIGHT, model.nlight, 0),
    }
    for kind, (obj, n, start) in kinds.items():
        for i in range(start, n):
            assert mujoco.mj_id2name(model, obj, i), f"unnamed {kind} #{i}"
    per_corner = {
        mujoco.mjtObj.mjOBJ_BODY: "pan_{}",
        mujoco.mjtObj.mjOBJ_JOINT: "pan_{}_z",
        mujoco.mjtObj.mjOBJ_TENDON: "tire_{}",
        mujoco.mjtObj.mjOBJ_ACTUATOR: "tire_{}",
        mujoco.mjtObj.mjOBJ_SENSOR: "tire_force_{}",
    }
    for obj, pattern in per_corner.items():
        for c in CORNERS:
            assert mujoco.mj_name2id(model, obj, pattern.format(c)) >= 0, pattern.format(c)
    for pattern in ("wheel_{}", "pan_{}", "hanger_{}", "seat_{}"):
        for c in CORNERS:
            assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, pattern.format(c)) >= 0


def test_every_name_of_mjcf_names_exists_in_the_compiled_model():
    """rigsim.mjcf.names is the one home of element names: each name it gives is an element of the
    compiled rig (the hydraulic actuators once rigsim.hydraulics.bridge has added them), of the
    right kind and attached where its docstring says."""
    from rigsim.hydraulics import ActuatorParams
    from rigsim.hydraulics.bridge import add_hydraulic_actuators
    from rigsim.mjcf import names

    spec = build_spec()
    add_hydraulic_actuators(spec, ActuatorParams(), names.CORNERS)
    model = spec.compile()
    obj = mujoco.mjtObj

    def eid(kind, name):
        i = mujoco.mj_name2id(model, kind, name)
        assert i >= 0, f"{kind.name} {name!r} of rigsim.mjcf.names is not in the compiled model"
        return i

    assert names.CORNERS == names.FRONT + names.REAR
    for c in names.CORNERS:
        pan = eid(obj.mjOBJ_BODY, names.pan_body(c))
        joint = eid(obj.mjOBJ_JOINT, names.pan_joint(c))
        assert model.jnt_bodyid[joint] == pan and model.jnt_type[joint] == mujoco.mjtJoint.mjJNT_SLIDE
        tire = eid(obj.mjOBJ_ACTUATOR, names.tire_actuator(c))
        sensor = eid(obj.mjOBJ_SENSOR, names.tire_sensor(c))
        assert model.sensor_objid[sensor] == tire
        site = eid(obj.mjOBJ_SITE, names.wheel_site(c))
        assert model.site_bodyid[site] == eid(obj.mjOBJ_BODY, names.axle_body(c))
        hyd = eid(obj.mjOBJ_ACTUATOR, names.hydraulic_actuator(c))
        assert model.actuator_trnid[hyd, 0] == joint
    # The truck bodies are every body but the world and the pans.
    pans = {names.pan_body(c) for c in names.CORNERS}
    others = {mujoco.mj_id2name(model, obj.mjOBJ_BODY, i) for i in range(1, model.nbody)} - pans
    assert others == set(names.TRUCK_BODIES)
    with pytest.raises(ValueError, match="corner must be one of fl, fr, rl, rr"):
        names.pan_joint("front")


def test_angles_in_radians_and_stroke():
    spec = build_spec()
    assert spec.compiler.degree == 0
    model = spec.compile()
    j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "pan_fl_z")
    # DYNTRAC stroke 15.2 cm total (paper).
    assert model.jnt_range[j, 1] - model.jnt_range[j, 0] == pytest.approx(0.152)


VARIANTS = {
    "nominal": (TruckVariant(), "slide"),
    "heavy": (TruckVariant(payload_kg=6360.0), "slide"),
    "stiff_tires": (TruckVariant(tire_stiffness_front_N_per_m=1.2e6, tire_stiffness_rear_N_per_m=2.4e6), "slide"),
    "fixed_pans": (TruckVariant(), "fixed"),
}


@pytest.mark.parametrize("name", VARIANTS)
def test_every_model_steps_one_second_without_warning(name):
    variant, pans = VARIANTS[name]
    model = build_model(variant, pans=pans)
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    # Pans on slides are held in place by their actuators in a run; here they are free and
    # fall onto their lower end stops, a harsher test of the model than standing still.
    mujoco.mj_step(model, data, int(round(1.0 / model.opt.timestep)))
    assert data.time == pytest.approx(1.0)
    assert all(w.number == 0 for w in data.warning), [w.number for w in data.warning]
    assert np.all(np.isfinite(data.qpos))


def test_scene_is_loadable_on_its_own():
    model = mujoco.MjModel.from_xml_path(str(resource_path("scene.xml")))
    assert model.nu == 4


def test_variant_validation_names_the_field():
    with pytest.raises(ValueError, match="vehicle.payload_kg"):
        TruckVariant(payload_kg=-1.0)
    with pytest.raises(ValueError, match="vehicle.tire_stiffness_front_N_per_m"):
        TruckVariant(tire_stiffness_front_N_per_m=float("nan"))
    with pytest.raises(ValueError, match="vehicle.timestep_s"):
        TruckVariant(timestep_s=0.01)


@pytest.mark.parametrize("y_m", [0.2, -0.5])
def test_payload_off_the_centreline_shifts_the_load_by_the_moment_balance(y_m):
    """Static moment balance about the x axis (reference: statics, not the model): the tire forces'
    moment about the centreline is the truck's weight times its centre of mass's lateral offset,
    which the rolled truck carries further out than the payload's share alone."""
    import mujoco

    from rigsim.mjcf import names
    from rigsim.mjcf.build import build_model
    from rigsim.mjcf.variant import TruckVariant
    from rigsim.mjcf.physics import static_equilibrium, tire_forces

    model = build_model(TruckVariant(payload_kg=5000.0, payload_y_m=y_m))
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    force = tire_forces(model, data)
    y = np.array([data.xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"pan_{c}")][1]
                  for c in names.CORNERS])
    chassis = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "chassis")
    weight = model.body_subtreemass[chassis] * 9.81
    com_y = data.subtree_com[chassis][1]
    assert force @ y == pytest.approx(weight * com_y, rel=5e-3)
    assert abs(com_y) > 5000.0 * abs(y_m) / model.body_subtreemass[chassis]  # the truck rolls towards it
    left, right = force[[0, 2]].sum(), force[[1, 3]].sum()
    assert np.sign(left - right) == np.sign(y_m)  # the side under the payload carries more


@pytest.mark.parametrize("bad", [0.81, -1.0, float("nan"), True, "0.2"])
def test_payload_y_beyond_the_bed_is_refused(bad):
    from rigsim.mjcf.variant import TruckVariant

    with pytest.raises(ValueError, match="vehicle.payload_y_m must lie within 0.8 m"):
        TruckVariant(payload_y_m=bad)


@pytest.mark.parametrize("bad", [3.6, -4.0, float("inf"), True])
def test_payload_x_off_the_truck_or_not_a_number_is_refused(bad):
    """A bool is not a position: True would otherwise read as 1 m."""
    with pytest.raises(ValueError, match=r"vehicle.payload_x_m must lie on the truck \(between -3.5 and 3.5 m\)"):
        TruckVariant(payload_x_m=bad)
