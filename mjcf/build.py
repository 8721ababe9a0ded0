"""Build model variants of the truck on the DYNTRAC rig from the shipped MJCF.

The XML (``truck_rig.xml``) holds the nominal truck with every constant explained; the
variants a scenario asks for (payload, tire stiffness, pan mass, leaf friction...) are
made here by editing an :class:`mujoco.MjSpec`, never by copying XML.
"""

from __future__ import annotations

import functools
import importlib.resources

import mujoco

from rigsim.mjcf import names
from rigsim.mjcf.cab import CAB_MASS_KG, add_cab_mount
from rigsim.mjcf.dampers import add_digressive_damping
from rigsim.mjcf.engine import ENGINE_MASS_KG, add_engine_mount
from rigsim.mjcf.frame import add_frame_flex
from rigsim.mjcf.description import (SINGLE_TIRE_DAMPING_NS_PER_M, SINGLE_TIRE_STIFFNESS_N_PER_M, apply_geometry,
                                     apply_suspension)
from rigsim.mjcf.physics import RigIndex, tire_stiffness
from rigsim.mjcf.stations import add_rebound_damping, apply_station_factors, set_masses
from rigsim.mjcf.tires import add_progressive_tire, axle_progressive, set_tire, tire_elements
from rigsim.mjcf.variant import TruckVariant

__all__ = ["MODEL_FILE", "SCENE_FILE", "resource_path", "load_spec", "build_spec", "build_model", "nominal_values"]

MODEL_FILE = "truck_rig.xml"
SCENE_FILE = "scene.xml"


def resource_path(name: str = SCENE_FILE):
    """Return the path of a shipped MJCF file.

    Parameters
    ----------
    name : str
        File name inside the ``mjcf`` package (``"scene.xml"`` or ``"truck_rig.xml"``).

    Returns
    -------
    pathlib.Path
        Absolute path of the file as installed.
    """
    ref = importlib.resources.files("rigsim.mjcf").joinpath(name)
    if not ref.is_file():
        raise FileNotFoundError(f"MJCF resource {name!r} is not shipped with the mjcf package")
    # The package is installed as plain files (not zipped), so the traversable is a real path.
    import pathlib

    return pathlib.Path(str(ref))


def load_spec(name: str = SCENE_FILE) -> mujoco.MjSpec:
    """Load a shipped MJCF file as an editable :class:`mujoco.MjSpec`."""
    return mujoco.MjSpec.from_file(str(resource_path(name)))


def _prescribe_pan(spec: mujoco.MjSpec, corner: str) -> None:
    """Make ``corner``'s pan (its joint already removed) a mocap body whose motion the caller sets.

    A mocap body has no velocity in MuJoCo, so the tire's damping would not see the pan's own
    velocity: the tire's gain becomes its damping (N s/m), so that ``ctrl`` carries the pan's
    vertical velocity (m/s, + up). The force stays the XML's affine law, clamped to the same
    range: kt (R0 - L) - ct (dL/dt) with dL/dt = (truck side) - v_pan, for the near-vertical
    tendon. Two sensors report the tendon's length (m) and its truck-side rate (m/s), from
    which the force at any other pan position follows (:func:`rigsim.mjcf.physics.tire_law`).
    """
    spec.body(names.pan_body(corner)).mocap = True
    for act in tire_elements(spec, corner):  # each element's gain is its own damping (the progressive one: 0)
        gain = list(act.gainprm)
        gain[0] = -act.biasprm[2]
        act.gainprm = gain
    tendon = names.tire_tendon(corner)
    for name, kind in ((names.tire_length_sensor(corner), mujoco.mjtSensor.mjSENS_TENDONPOS),
                       (names.tire_rate_sensor(corner), mujoco.mjtSensor.mjSENS_TENDONVEL)):
        spec.add_sensor(name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_TENDON, objname=tendon)


def build_spec(variant: TruckVariant | None = None, *, pans: str = "slide", scene: bool = True) -> mujoco.MjSpec:
    """Return an editable spec of the truck on the rig with ``variant`` applied.

    Parameters
    ----------
    variant : TruckVariant, optional
        Changes to the nominal model; ``None`` gives the XML as shipped.
    pans : {"slide", "mocap", "fixed"}
        ``"slide"``: each pan moves on its vertical slide joint (the rig test: the actuators
        drive it). ``"mocap"``: the pans are mocap bodies whose motion the caller prescribes
        (the road test, :func:`_prescribe_pans`). ``"fixed"``: the pan joints are removed, the
        pans are welded to the ground (modal analysis of the truck alone on rigid supports).
    scene : bool
        Load ``scene.xml`` (floor, light, cameras) instead of the bare model file.

    Returns
    -------
    mujoco.MjSpec
    """
    if pans not in ("slide", "mocap", "fixed"):
        raise ValueError(f"pans must be 'slide', 'mocap' or 'fixed', got {pans!r}")
    v = variant or TruckVariant()
    spec = load_spec(SCENE_FILE if scene else MODEL_FILE)
    apply_geometry(spec, v)  # the described truck's wheelbase, tracks and rear tires (None: the XML's)
    if v.payload_kg is not None:
        spec.geom("payload_box").mass = float(v.payload_kg)
    body = spec.body("payload")
    body.pos = [float(given) if given is not None else float(old)
                for old, given in zip(body.pos, (v.payload_x_m, v.payload_y_m, v.payload_z_m))]
    set_masses(spec, v)
    apply_suspension(spec, v)  # each axle's kind, rate and damping: after the masses (an air spring's rate reads them)
    single = v.rear_tires == "single"
    for corner in names.CORNERS:
        front = corner in names.FRONT
        k_rear = SINGLE_TIRE_STIFFNESS_N_PER_M if single and v.tire_stiffness_rear_N_per_m is None else \
            v.tire_stiffness_rear_N_per_m
        c_rear = SINGLE_TIRE_DAMPING_NS_PER_M if single and v.tire_damping_rear_Ns_per_m is None else \
            v.tire_damping_rear_Ns_per_m
        set_tire(
            spec,
            corner,
            v.tire_stiffness_front_N_per_m if front else k_rear,
            v.tire_damping_front_Ns_per_m if front else c_rear,
            v.tire_free_radius_m,
        )
        friction = v.spring_friction_front_N if front else v.spring_friction_rear_N
        if friction is not None:
            spec.tendon(names.spring_tendon(corner)).frictionloss = float(friction)
        apply_station_factors(spec, corner, v)  # on the axle's values; before the progressive tire takes kt
        stiffening = axle_progressive(v, front)
        if stiffening is not None:
            add_progressive_tire(spec, corner, *stiffening, v.tire_progressive_spread_m)
        if v.damper_rebound_ratio is not None and v.damper_rebound_ratio != 1.0:
            add_rebound_damping(spec, corner, v.damper_rebound_ratio)
        if v.damper_digressive_knee_m_per_s is not None:  # after the rebound ratio: it reads both sides' slopes
            add_digressive_damping(spec, corner, v.damper_digressive_knee_m_per_s, v.damper_digressive_ratio)
        if v.pan_mass_kg is not None:
            spec.body(names.pan_body(corner)).mass = float(v.pan_mass_kg)
        if pans in ("fixed", "mocap"):
            spec.delete(spec.joint(names.pan_joint(corner)))
        if pans == "mocap":
            _prescribe_pan(spec, corner)
    if v.timestep_s is not None:
        spec.option.timestep = float(v.timestep_s)
    if v.cab_mount_hz is not None:
        add_cab_mount(spec, v.cab_mount_hz, CAB_MASS_KG if v.cab_mass_kg is None else float(v.cab_mass_kg))
    if v.engine_mount_hz is not None:  # before the frame is cut: the engine rides on the front half
        add_engine_mount(spec, ENGINE_MASS_KG if v.engine_mass_kg is None else float(v.engine_mass_kg),
                         v.engine_mount_hz)
    if v.frame_torsion_hz is not None:  # last: it cuts the chassis as everything above left it
        add_frame_flex(spec, v.frame_torsion_hz, v.frame_bending_hz, v.frame_hinge_share, v.frame_damping_ratio)
    return spec


def build_model(variant: TruckVariant | None = None, *, pans: str = "slide") -> mujoco.MjModel:
    """Compile the truck on the rig with ``variant`` applied (see :func:`build_spec`)."""
    return build_spec(variant, pans=pans).compile()


def nominal_values(model: mujoco.MjModel | None = None) -> dict[str, float]:
    """The XML's value of each :class:`~rigsim.mjcf.variant.TruckVariant` field that holds one number in the
    nominal truck (SI; the axle fields read from the front-left and rear-left stations), read from the
    compiled model (``model``: the caller's own compile of ``build_model()``; without it the XML is
    compiled once per process): the values a factor or an offset on "the catalogue truck" applies to."""
    return dict(_xml_values() if model is None else _values(model))


@functools.cache
def _xml_values() -> dict[str, float]:
    return _values(build_model())


def _values(model: mujoco.MjModel) -> dict[str, float]:
    def body(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)

    def friction(corner: str) -> float:
        return float(model.tendon_frictionloss[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON,
                                                                  names.spring_tendon(corner))])

    index = RigIndex.of(model)
    f, r = names.CORNERS.index("fl"), names.CORNERS.index("rl")
    stiffness = tire_stiffness(model, index)
    tire = model.actuator_biasprm[index.tire_actuator]  # kt R0, -kt, -ct per station
    payload, chassis = body("payload"), body("chassis")
    return {"payload_kg": float(model.body_mass[payload]), "payload_x_m": float(model.body_pos[payload, 0]),
            "payload_y_m": float(model.body_pos[payload, 1]), "payload_z_m": float(model.body_pos[payload, 2]),
            "tire_stiffness_front_N_per_m": float(stiffness[f]), "tire_stiffness_rear_N_per_m": float(stiffness[r]),
            "tire_damping_front_Ns_per_m": float(-tire[f, 2]), "tire_damping_rear_Ns_per_m": float(-tire[r, 2]),
            "tire_free_radius_m": float(tire[f, 0] / stiffness[f]),
            "spring_friction_front_N": friction("fl"), "spring_friction_rear_N": friction("rl"),
            "pan_mass_kg": float(model.body_mass[body(names.pan_body("fl"))]),
            "axle_mass_front_kg": float(model.body_mass[body(names.axle_body("fl"))]),
            "axle_mass_rear_kg": float(model.body_mass[body(names.axle_body("rl"))]),
            "chassis_mass_kg": float(model.body_mass[chassis]),
            "chassis_roll_inertia_kg_m2": float(model.body_inertia[chassis, 0]),
            "chassis_pitch_inertia_kg_m2": float(model.body_inertia[chassis, 1])}
