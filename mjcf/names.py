"""The names of the model's elements: the one home of every string other packages look up.

The MJCF (``truck_rig.xml``) names each element after its wheel station; :mod:`hydraulics`
adds one user actuator per station and :mod:`scenarios` reads joints, actuators, sensors and
sites. All of them spell the names through this module, so a renamed element is renamed here
once (``tests/mjcf/test_mjcf.py`` checks every name below exists in the compiled model).
"""

from __future__ import annotations

__all__ = [
    "CORNERS", "FRONT", "REAR", "TRUCK_BODIES",
    "pan_body", "pan_joint", "tire_actuator", "tire_sensor", "wheel_site", "hydraulic_actuator",
    "axle_body", "spring_tendon", "CAB_BODY", "CAB_JOINTS", "tire_tendon", "tire_length_sensor",
    "tire_rate_sensor", "tire_progressive_actuator", "spring_rebound_actuator",
]

#: Wheel stations, in the order every per-wheel array of this project uses:
#: front-left, front-right, rear-left, rear-right.
CORNERS: tuple[str, ...] = ("fl", "fr", "rl", "rr")
FRONT: tuple[str, ...] = ("fl", "fr")
REAR: tuple[str, ...] = ("rl", "rr")

#: Bodies of the truck (pans excluded): their masses sum to the vehicle mass.
TRUCK_BODIES: tuple[str, ...] = ("chassis", "payload", "front_axle", "rear_axle")

#: The cab as its own body on its mounts, present only with ``TruckVariant.cab_mount_hz`` set
#: (otherwise the cab is part of the chassis); a truck body too, so its mass adds to
#: :data:`TRUCK_BODIES`' when it exists.
CAB_BODY: str = "cab"
#: The cab's joints on the chassis: its vertical slide (qpos in m, 0 = at rest under gravity,
#: + up) and its pitch hinge about the cab's centre of mass (rad, + nose down); only with
#: ``TruckVariant.cab_mount_hz`` set.
CAB_JOINTS: tuple[str, ...] = ("cab_z", "cab_pitch")


def _check(corner: str) -> str:
    if corner not in CORNERS:
        raise ValueError(f"corner must be one of {', '.join(CORNERS)}, got {corner!r}")
    return corner


def pan_body(corner: str) -> str:
    """Body of the wheelpan under ``corner``."""
    return f"pan_{_check(corner)}"


def pan_joint(corner: str) -> str:
    """Vertical slide joint of the wheelpan (qpos in m, 0 = mid-stroke, + up)."""
    return f"pan_{_check(corner)}_z"


def tire_actuator(corner: str) -> str:
    """The tire's force element (an actuator on a spatial tendon, N, compression positive)."""
    return f"tire_{_check(corner)}"


def tire_progressive_actuator(corner: str, step: int = 0) -> str:
    """The progressive tire's force element ``step`` (0-based) on the tire tendon (N, compression
    positive); only with ``TruckVariant.tire_progressive_ratio`` set. Step 0 is the bilinear tire's
    one element (``tire_progressive_<c>``); a spread stiffening (``TruckVariant.tire_progressive_spread_m``)
    adds steps 1 to 4 (``tire_progressive_<c>_2`` ... ``_5``)."""
    if isinstance(step, bool) or not isinstance(step, int) or step < 0:
        raise ValueError(f"step must be an int >= 0, got {step!r}")
    return f"tire_progressive_{_check(corner)}" + (f"_{step + 1}" if step else "")


def tire_tendon(corner: str) -> str:
    """The tire's spatial tendon, wheel centre to pan top (its length in m)."""
    return f"tire_{_check(corner)}"


def tire_length_sensor(corner: str) -> str:
    """Sensor of the tire tendon's length (m); only on prescribed pans (``build_spec(pans="mocap")``)."""
    return f"tire_length_{_check(corner)}"


def tire_rate_sensor(corner: str) -> str:
    """Sensor of the tire tendon's rate of change from the truck's motion alone (m/s; a mocap pan
    has no velocity in MuJoCo); only on prescribed pans (``build_spec(pans="mocap")``)."""
    return f"tire_rate_{_check(corner)}"


def tire_sensor(corner: str) -> str:
    """Sensor of the tire force on the pan (N): the tire actuator's force, or with a progressive tire
    (``TruckVariant.tire_progressive_ratio``) the total force of the tire tendon's elements."""
    return f"tire_force_{_check(corner)}"


def wheel_site(corner: str) -> str:
    """Site at the wheel centre."""
    return f"wheel_{_check(corner)}"


def hydraulic_actuator(corner: str) -> str:
    """The servo-hydraulic user actuator that :mod:`rigsim.hydraulics.bridge` adds on the pan joint."""
    return f"hyd_{_check(corner)}"


def axle_body(corner: str) -> str:
    """The axle body that carries ``corner``'s wheel."""
    return "front_axle" if _check(corner) in FRONT else "rear_axle"


def spring_tendon(corner: str) -> str:
    """The leaf spring's tendon at ``corner`` (its rate, damping and interleaf friction)."""
    return f"spring_{_check(corner)}"


def spring_rebound_actuator(corner: str) -> str:
    """The leaf spring's rebound damping element (an actuator on the spring tendon, N, acting only
    while the spring extends); only with ``TruckVariant.damper_rebound_ratio`` set."""
    return f"spring_rebound_{_check(corner)}"


# Plant features the calibrated model family lacks: a flexible frame, the engine on its mounts and
# digressive dampers (mjcf/frame.py, mjcf/engine.py, mjcf/dampers.py); each element exists only
# when its feature is applied.

#: The frame's rear half (``TruckVariant.frame_torsion_hz``): a truck body whose mass adds to
#: :data:`TRUCK_BODIES`' when it exists; it carries the rear axle, the rear hangers and the payload
#: when the payload lies behind the frame's joints. Its body frame is the chassis' (same origin and
#: axes), so the bodies and sites it carries keep their positions in the chassis frame.
FRAME_REAR_BODY: str = "frame_rear"
#: The frame's joints at mid-wheelbase, rear half on front half: its torsion hinge about x (rad,
#: + the rear half's left side up) and its vertical bending hinge about y (rad, + the rear half's
#: tail up, as ``chassis_pitch``'s + nose down), both at the rails' centre height; only with the
#: flexible frame.
FRAME_JOINTS: tuple[str, ...] = ("frame_torsion", "frame_bending")
#: The engine and gearbox as their own body on rubber mounts (``TruckVariant.engine_mount_hz``), a
#: truck body whose mass adds to :data:`TRUCK_BODIES`' when it exists.
ENGINE_BODY: str = "engine"
#: The engine's joints on the chassis: its vertical slide (m, 0 = at rest under gravity, + up) and
#: its pitch hinge about its centre of mass (rad, + nose down); only with the engine mount.
ENGINE_JOINTS: tuple[str, ...] = ("engine_z", "engine_pitch")
#: The two sides of a digressive damper's elements: the spring extending (rebound) and compressing (bump).
DAMPER_SIDES: tuple[str, ...] = ("ext", "cmp")


def spring_digressive_actuator(corner: str, side: str) -> str:
    """The leaf spring damper's digressive element on ``side``: the part of its low-speed damping that
    saturates at the knee (``"ext"``: acting only while the spring extends, ``"cmp"``: only while it
    compresses; an actuator on the spring tendon, N); only with
    ``TruckVariant.damper_digressive_knee_m_per_s`` set."""
    if side not in DAMPER_SIDES:
        raise ValueError(f"side must be one of {', '.join(DAMPER_SIDES)}, got {side!r}")
    return f"spring_digressive_{_check(corner)}_{side}"


__all__ += ["FRAME_REAR_BODY", "FRAME_JOINTS", "ENGINE_BODY", "ENGINE_JOINTS", "DAMPER_SIDES",
            "spring_digressive_actuator"]
