"""Build model variants of the truck on the DYNTRAC rig from the shipped MJCF.

The XML (``truck_rig.xml``) holds the nominal truck with every constant explained; the
variants a scenario asks for (payload, tire stiffness, pan mass, leaf friction...) are
made here by editing an :class:`mujoco.MjSpec`, never by copying XML.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
from dataclasses import dataclass

import mujoco

from mjcf import names

__all__ = [
    "MODEL_FILE",
    "SCENE_FILE",
    "TruckVariant",
    "resource_path",
    "load_spec",
    "build_spec",
    "build_model",
]

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
    ref = importlib.resources.files("mjcf").joinpath(name)
    if not ref.is_file():
        raise FileNotFoundError(f"MJCF resource {name!r} is not shipped with the mjcf package")
    # The package is installed as plain files (not zipped), so the traversable is a real path.
    import pathlib

    return pathlib.Path(str(ref))


def load_spec(name: str = SCENE_FILE) -> mujoco.MjSpec:
    """Load a shipped MJCF file as an editable :class:`mujoco.MjSpec`."""
    return mujoco.MjSpec.from_file(str(resource_path(name)))


def _positive(name: str, value: float | None, allow_zero: bool = False) -> None:
    if value is None:
        return
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        raise ValueError(f"vehicle.{name} must be a finite number, got {value!r}")
    if value < 0 or (value == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"vehicle.{name} must be {bound}, got {value!r}")


@dataclass(frozen=True)
class TruckVariant:
    """Changes to the nominal truck and rig of ``truck_rig.xml``.

    Every field left at ``None`` keeps the value of the XML (its source is in the comment
    beside it there). All values are SI.

    Parameters
    ----------
    payload_kg : float, kg, optional
        Payload mass (the paper's cases: 3640 and 6360 kg). The payload's inertia follows
        from its box geometry.
    payload_x_m : float, m, optional
        Payload centre of mass along x in the chassis frame (mid-wheelbase = 0, forward
        positive; front axle at +2.5, rear at -2.5). The XML places it at -1.3 m (3.8 m
        behind the front axle).
    tire_stiffness_front_N_per_m : float, N/m, optional
        Vertical stiffness of each front wheel station (one tire).
    tire_stiffness_rear_N_per_m : float, N/m, optional
        Vertical stiffness of each rear wheel station (a dual pair, both tires together).
    tire_damping_front_Ns_per_m, tire_damping_rear_Ns_per_m : float, N s/m, optional
        Vertical damping of each front / rear wheel station.
    tire_free_radius_m : float, m, optional
        Unloaded tire radius R0 (all wheel stations).
    spring_friction_front_N, spring_friction_rear_N : float, N, optional
        Interleaf Coulomb friction force of each front / rear leaf spring (0 disables it).
    pan_mass_kg : float, kg, optional
        Mass of each wheelpan with its actuator piston and rod.
    timestep_s : float, s, optional
        Integration time step.
    """

    payload_kg: float | None = None
    payload_x_m: float | None = None
    tire_stiffness_front_N_per_m: float | None = None
    tire_stiffness_rear_N_per_m: float | None = None
    tire_damping_front_Ns_per_m: float | None = None
    tire_damping_rear_Ns_per_m: float | None = None
    tire_free_radius_m: float | None = None
    spring_friction_front_N: float | None = None
    spring_friction_rear_N: float | None = None
    pan_mass_kg: float | None = None
    timestep_s: float | None = None

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name == "payload_x_m":
                if value is not None and (
                    not isinstance(value, (int, float)) or not math.isfinite(value) or abs(value) > 3.5
                ):
                    raise ValueError(
                        f"vehicle.payload_x_m must lie on the truck (between -3.5 and 3.5 m), got {value!r}"
                    )
                continue
            zero_ok = f.name.startswith(("spring_friction", "tire_damping", "payload_kg"))
            _positive(f.name, value, allow_zero=zero_ok)
        if self.timestep_s is not None and self.timestep_s > 1e-3:
            raise ValueError(
                f"vehicle.timestep_s = {self.timestep_s} s is too coarse for the tire and hydraulic modes; "
                "use 1e-3 s or less (1e-4 s is the default)"
            )

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Names of the parameters a scenario may override."""
        return tuple(f.name for f in dataclasses.fields(cls))


def _set_tire(spec: mujoco.MjSpec, corner: str, k: float | None, c: float | None, r0: float | None) -> None:
    act = spec.actuator(names.tire_actuator(corner))
    prm = list(act.biasprm)
    k_old = -prm[1]
    r0_old = prm[0] / k_old
    k_new = k_old if k is None else float(k)
    r0_new = r0_old if r0 is None else float(r0)
    prm[0] = k_new * r0_new
    prm[1] = -k_new
    if c is not None:
        prm[2] = -float(c)
    act.biasprm = prm


def build_spec(variant: TruckVariant | None = None, *, pans: str = "slide", scene: bool = True) -> mujoco.MjSpec:
    """Return an editable spec of the truck on the rig with ``variant`` applied.

    Parameters
    ----------
    variant : TruckVariant, optional
        Changes to the nominal model; ``None`` gives the XML as shipped.
    pans : {"slide", "fixed"}
        ``"slide"``: each pan moves on its vertical slide joint (road and rig modes).
        ``"fixed"``: the pan joints are removed, the pans are welded to the ground
        (modal analysis of the truck alone on rigid supports).
    scene : bool
        Load ``scene.xml`` (floor, light, cameras) instead of the bare model file.

    Returns
    -------
    mujoco.MjSpec
    """
    if pans not in ("slide", "fixed"):
        raise ValueError(f"pans must be 'slide' or 'fixed', got {pans!r}")
    v = variant or TruckVariant()
    spec = load_spec(SCENE_FILE if scene else MODEL_FILE)

    if v.payload_kg is not None:
        spec.geom("payload_box").mass = float(v.payload_kg)
    if v.payload_x_m is not None:
        body = spec.body("payload")
        body.pos = [float(v.payload_x_m), body.pos[1], body.pos[2]]
    for corner in names.CORNERS:
        front = corner in names.FRONT
        _set_tire(
            spec,
            corner,
            v.tire_stiffness_front_N_per_m if front else v.tire_stiffness_rear_N_per_m,
            v.tire_damping_front_Ns_per_m if front else v.tire_damping_rear_Ns_per_m,
            v.tire_free_radius_m,
        )
        friction = v.spring_friction_front_N if front else v.spring_friction_rear_N
        if friction is not None:
            spec.tendon(f"spring_{corner}").frictionloss = float(friction)
        if v.pan_mass_kg is not None:
            spec.body(names.pan_body(corner)).mass = float(v.pan_mass_kg)
        if pans == "fixed":
            spec.delete(spec.joint(names.pan_joint(corner)))
    if v.timestep_s is not None:
        spec.option.timestep = float(v.timestep_s)
    return spec


def build_model(variant: TruckVariant | None = None, *, pans: str = "slide") -> mujoco.MjModel:
    """Compile the truck on the rig with ``variant`` applied (see :func:`build_spec`)."""
    return build_spec(variant, pans=pans).compile()
