"""The tire's force elements in a truck spec: the XML's affine tire and the progressive one.

Each wheel station's tire is an affine actuator on a spatial tendon from the wheel centre to the
pan top (``truck_rig.xml``): F = kt (R0 - L) - ct dL/dt, clamped to [0, 1e7] N. A progressive tire
(``TruckVariant.tire_progressive_ratio``) adds a second affine element on the same tendon that
engages beyond an onset deflection; :mod:`mjcf.physics` sums a tendon's elements.
"""

from __future__ import annotations

import mujoco

from mjcf import names

__all__ = ["TIRE_PROGRESSIVE_ONSET_M", "set_tire", "tire_elements", "add_progressive_tire"]

#: m: the tire deflection (R0 - L) beyond which the progressive element of
#: ``TruckVariant.tire_progressive_ratio`` engages when ``tire_progressive_onset_m`` is not given:
#: 2 cm, between the static deflections of the rear duals (1.6-2.2 cm) and of the steer tires
#: (2.6-2.9 cm) on the paper's payloads, so that the dynamic deflection of every wheel crosses it.
TIRE_PROGRESSIVE_ONSET_M = 0.02


def set_tire(spec: mujoco.MjSpec, corner: str, k: float | None, c: float | None, r0: float | None) -> None:
    """Set ``corner``'s tire element: stiffness ``k`` (N/m), damping ``c`` (N s/m) and free radius
    ``r0`` (m), each None to keep the compiled spec's; the law stays kt (R0 - L) - ct dL/dt."""
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


def tire_elements(spec: mujoco.MjSpec, corner: str) -> list:
    """The force elements on ``corner``'s tire tendon: the XML's tire, then the progressive one if any."""
    extra = names.tire_progressive_actuator(corner)
    return [spec.actuator(names.tire_actuator(corner))] + [a for a in spec.actuators if a.name == extra]


def add_progressive_tire(spec: mujoco.MjSpec, corner: str, ratio: float, onset_m: float) -> None:
    """A second affine element on ``corner``'s tire tendon (see ``TruckVariant.tire_progressive_ratio``):
    F2 = k2 (R0 - onset - L) clamped to [0, 1e7] N, k2 = ratio kt, no damping; the tire force sensor
    becomes the tendon's total actuator force (``mjSENS_TENDONACTFRC``), the sum of both elements."""
    tire = spec.actuator(names.tire_actuator(corner))
    kt = -float(tire.biasprm[1])
    r0 = float(tire.biasprm[0]) / kt
    k2 = float(ratio) * kt
    tendon = names.tire_tendon(corner)
    spec.add_actuator(name=names.tire_progressive_actuator(corner), target=tendon,
                      trntype=mujoco.mjtTrn.mjTRN_TENDON, gaintype=mujoco.mjtGain.mjGAIN_FIXED,
                      gainprm=[0.0] * 10, biastype=mujoco.mjtBias.mjBIAS_AFFINE,
                      biasprm=[k2 * (r0 - float(onset_m)), -k2, 0.0] + [0.0] * 7,
                      forcelimited=mujoco.mjtLimited.mjLIMITED_TRUE, forcerange=list(tire.forcerange),
                      ctrllimited=mujoco.mjtLimited.mjLIMITED_FALSE)
    sensor = names.tire_sensor(corner)
    spec.delete(spec.sensor(sensor))
    spec.add_sensor(name=sensor, type=mujoco.mjtSensor.mjSENS_TENDONACTFRC, objtype=mujoco.mjtObj.mjOBJ_TENDON,
                    objname=tendon)
