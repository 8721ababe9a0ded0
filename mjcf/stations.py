"""Each wheel station's own values, and the masses a real truck differs in: the plant's asymmetries.

The XML (``truck_rig.xml``) gives both stations of an axle the same tire and the same leaf
spring, and the model family (:mod:`rigsim.scenarios.records.model`) fits them per axle. A real truck's
left and right differ: a tire at another pressure, a spring with a broken leaf, a worn damper,
leaves that rust and rub harder. :class:`rigsim.mjcf.variant.TruckVariant`'s per-station factors
(``<quantity>_factor_<corner>``, :data:`STATION_FACTORS`) scale one station's value after its
axle's; :func:`add_rebound_damping` makes the leaf springs' dampers harder in rebound than in
bump; :func:`set_masses` sets the axles' and the chassis' masses and inertias. All plant
features: the calibrated model holds its stations equal and its masses at the catalogue's.
"""

from __future__ import annotations

import mujoco
import numpy as np

from rigsim.mjcf import names

__all__ = ["STATION_FACTORS", "station_factor_field", "apply_station_factors", "rebound_coefficients",
           "add_rebound_damping", "set_masses"]

#: Per-station factors: ``{quantity: (low, high, why)}``, each the factor (1) on the station's value
#: after its axle's (``TruckVariant.<quantity>_factor_<corner>``), inclusive bounds; estimates, the
#: reasons in mjcf/README.md ("Each wheel station's own values").
STATION_FACTORS: dict[str, tuple[float, float, str]] = {
    "tire_stiffness": (0.7, 1.3, "a tire's vertical stiffness follows its inflation pressure nearly in "
                       "proportion; 0.7-1.3 is a tire 30 % under or over its pressure, worn, or of another make"),
    "tire_damping": (0.5, 2.0, "a tire's damping is a few % of critical and varies with its construction "
                     "and temperature; a factor of 2 either way covers them"),
    "spring_rate": (0.7, 1.3, "a leaf spring's rate is made to within 5-10 %, and a broken leaf of 5-10 takes "
                    "10-20 % off it; 0.7-1.3 covers both"),
    "spring_damping": (0.3, 2.0, "a worn damper keeps a third to half of its force, a new one beside old "
                       "ones may give twice theirs"),
    "spring_friction": (0.25, 4.0, "interleaf friction depends on lubrication, wear and corrosion of the "
                        "leaves: springs of one truck differ by factors of 2-4"),
}


def station_factor_field(quantity: str, corner: str) -> str:
    """The :class:`rigsim.mjcf.variant.TruckVariant` field of one station's factor, e.g. ``tire_stiffness_factor_fl``."""
    if quantity not in STATION_FACTORS:
        raise ValueError(f"quantity must be one of {', '.join(STATION_FACTORS)}, got {quantity!r}")
    if corner not in names.CORNERS:
        raise ValueError(f"corner must be one of {', '.join(names.CORNERS)}, got {corner!r}")
    return f"{quantity}_factor_{corner}"


def apply_station_factors(spec: mujoco.MjSpec, corner: str, variant) -> None:
    """Scale ``corner``'s tire (stiffness, damping; the free radius kept) and leaf spring (rate,
    viscous damping, interleaf friction) by ``variant``'s factors for it; a factor left at None
    keeps the value. The spring's free length is kept: a softer spring sags under its load."""
    def factor(quantity: str) -> float | None:
        return getattr(variant, station_factor_field(quantity, corner))

    tire = spec.actuator(names.tire_actuator(corner))
    prm = list(tire.biasprm)  # kt R0, -kt, -ct: F = kt (R0 - L) - ct dL/dt
    if factor("tire_stiffness") is not None:
        prm[0] *= factor("tire_stiffness")
        prm[1] *= factor("tire_stiffness")
    if factor("tire_damping") is not None:
        prm[2] *= factor("tire_damping")
    tire.biasprm = prm
    spring = spec.tendon(names.spring_tendon(corner))
    for quantity, attr in (("spring_rate", "stiffness"), ("spring_damping", "damping")):
        if factor(quantity) is not None:
            value = np.array(getattr(spring, attr), dtype=float)
            value[0] *= factor(quantity)
            setattr(spring, attr, value)
    if factor("spring_friction") is not None:
        spring.frictionloss = float(spring.frictionloss) * factor("spring_friction")


def rebound_coefficients(c_Ns_per_m: float, ratio: float) -> tuple[float, float]:
    """Bump and rebound damping (N s/m) of a damper of mean coefficient ``c_Ns_per_m`` whose rebound
    coefficient is ``ratio`` times its bump one: c_b = 2 c / (1 + r), c_r = r c_b, so that
    (c_b + c_r) / 2 = c and a symmetric excitation loses the same energy per cycle."""
    bump = 2.0 * float(c_Ns_per_m) / (1.0 + float(ratio))
    return bump, float(ratio) * bump


def add_rebound_damping(spec: mujoco.MjSpec, corner: str, ratio: float) -> None:
    """Make ``corner``'s leaf-spring damper ``ratio`` times harder in rebound (the spring extending,
    dL/dt > 0) than in bump, its mean coefficient kept (:func:`rebound_coefficients`).

    The tendon's own viscous damping becomes the bump coefficient c_b; a one-sided element
    (:func:`rigsim.mjcf.names.spring_rebound_actuator`, an affine actuator on the spring tendon,
    F = -(c_r - c_b) dL/dt, its force range [-1e7, 0] N) adds the rest in rebound only."""
    spring = spec.tendon(names.spring_tendon(corner))
    damping = np.array(spring.damping, dtype=float)
    bump, rebound = rebound_coefficients(damping[0], ratio)
    damping[0] = bump
    spring.damping = damping
    spec.add_actuator(name=names.spring_rebound_actuator(corner), target=names.spring_tendon(corner),
                      trntype=mujoco.mjtTrn.mjTRN_TENDON, gaintype=mujoco.mjtGain.mjGAIN_FIXED, gainprm=[0.0] * 10,
                      biastype=mujoco.mjtBias.mjBIAS_AFFINE, biasprm=[0.0, 0.0, -(rebound - bump)] + [0.0] * 7,
                      forcelimited=mujoco.mjtLimited.mjLIMITED_TRUE, forcerange=[-1e7, 0.0],
                      ctrllimited=mujoco.mjtLimited.mjLIMITED_FALSE)


def _scale_mass(body, mass_kg: float) -> None:
    """Set ``body``'s mass, its inertia scaled with it (the same radii of gyration)."""
    scale = float(mass_kg) / float(body.mass)
    body.mass = float(mass_kg)
    body.inertia = np.asarray(body.inertia, dtype=float) * scale


def set_masses(spec: mujoco.MjSpec, variant) -> None:
    """Apply ``variant``'s axle masses (inertia scaled with each), the chassis' mass (its inertia
    kept unless given) and the chassis' roll and pitch moments of inertia (kg, kg m^2)."""
    for axle, mass in ((names.axle_body("fl"), variant.axle_mass_front_kg),
                       (names.axle_body("rl"), variant.axle_mass_rear_kg)):
        if mass is not None:
            _scale_mass(spec.body(axle), mass)
    chassis = spec.body("chassis")
    if variant.chassis_mass_kg is not None:
        chassis.mass = float(variant.chassis_mass_kg)
    inertia = np.array(chassis.inertia, dtype=float)  # principal, about the XML's axes (diaginertia)
    if variant.chassis_roll_inertia_kg_m2 is not None:
        inertia[0] = float(variant.chassis_roll_inertia_kg_m2)
    if variant.chassis_pitch_inertia_kg_m2 is not None:
        inertia[1] = float(variant.chassis_pitch_inertia_kg_m2)
    if variant.chassis_roll_inertia_kg_m2 is not None or variant.chassis_pitch_inertia_kg_m2 is not None:
        # yaw: held by the rig (no joint), kept in the XML's ratio to roll + pitch, which keeps the
        # three a body's moments (each at most the sum of the other two)
        old = np.array(chassis.inertia, dtype=float)
        inertia[2] = old[2] * (inertia[0] + inertia[1]) / (old[0] + old[1])
    chassis.inertia = inertia
