"""The tire's force elements in a truck spec: the XML's affine tire and the progressive ones.

Each wheel station's tire is an affine actuator on a spatial tendon from the wheel centre to the
pan top (``truck_rig.xml``): F = kt (R0 - L) - ct dL/dt, clamped to [0, 1e7] N. A progressive tire
(``TruckVariant.tire_progressive_ratio``) adds a second affine element on the same tendon that
engages beyond an onset deflection (a bilinear tire, one kink: the calibrated model family's), or
with ``TruckVariant.tire_progressive_spread_m`` :data:`TIRE_PROGRESSIVE_STEPS` elements engaging one
after the other across the spread: a tire's stiffness rises smoothly over its working deflection; the
model family's bilinear tire has one kink. :mod:`rigsim.mjcf.physics` sums a tendon's elements.
"""

from __future__ import annotations

import mujoco

from rigsim.mjcf import names

__all__ = ["TIRE_PROGRESSIVE_ONSET_M", "TIRE_PROGRESSIVE_STEPS", "set_tire", "tire_elements", "progressive_onsets",
           "REAR_FIELDS", "axle_progressive", "check_progressive", "add_progressive_tire"]

#: m: the tire deflection (R0 - L) beyond which the progressive element of
#: ``TruckVariant.tire_progressive_ratio`` engages when ``tire_progressive_onset_m`` is not given:
#: 2 cm, between the static deflections of the rear duals (1.6-2.2 cm) and of the steer tires
#: (2.6-2.9 cm) on the paper's payloads, so that the dynamic deflection of every wheel crosses it.
TIRE_PROGRESSIVE_ONSET_M = 0.02
#: 1: the number of equal elements (each ratio / 5 kt) a spread progressive tire
#: (``TruckVariant.tire_progressive_spread_m`` > 0) is split into, their onsets evenly from
#: onset - spread / 2 to onset + spread / 2 (ends included): the stiffness rises in 5 equal steps
#: from kt to (1 + ratio) kt, a piecewise-linear approximation of a smooth stiffening (steps of
#: 0.5 cm over a 2 cm spread; more elements only cost actuators).
TIRE_PROGRESSIVE_STEPS = 5


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
    """The force elements on ``corner``'s tire tendon: the XML's tire, then every progressive element
    (:func:`rigsim.mjcf.names.tire_progressive_actuator`) in step order."""
    extra = [spec.actuator(names.tire_progressive_actuator(corner, k)) for k in range(TIRE_PROGRESSIVE_STEPS)]
    return [spec.actuator(names.tire_actuator(corner))] + [a for a in extra if a is not None]


def progressive_onsets(onset_m: float, spread_m: float | None) -> list[float]:
    """Onsets (m of deflection R0 - L) of the progressive elements: ``[onset_m]`` without a spread
    (None or 0 m), else :data:`TIRE_PROGRESSIVE_STEPS` evenly from onset - spread / 2 to
    onset + spread / 2, ends included."""
    if not spread_m:
        return [float(onset_m)]
    n, s = TIRE_PROGRESSIVE_STEPS, float(spread_m)
    return [float(onset_m) - 0.5 * s + k * s / (n - 1) for k in range(n)]


#: The rear tires' own field of each all-wheel stiffening field of ``TruckVariant`` (a rear field
#: left None takes the all-wheel value: :func:`axle_progressive`).
REAR_FIELDS = {"tire_progressive_ratio": "tire_progressive_ratio_rear",
               "tire_progressive_onset_m": "tire_progressive_onset_rear_m"}


def axle_progressive(variant, front: bool) -> tuple[float, float] | None:
    """The stiffening (ratio, 1; onset, m) of one axle's tires in ``variant`` (a
    :class:`rigsim.mjcf.variant.TruckVariant`), or None for linear tires. Every tire takes
    ``tire_progressive_ratio`` and ``tire_progressive_onset_m`` (default
    :data:`TIRE_PROGRESSIVE_ONSET_M`); the rear tires take ``tire_progressive_ratio_rear`` and
    ``tire_progressive_onset_rear_m`` instead where those are given."""
    if variant.tire_progressive_ratio is None:
        return None
    ratio, onset = variant.tire_progressive_ratio, variant.tire_progressive_onset_m
    if not front:
        ratio = ratio if variant.tire_progressive_ratio_rear is None else variant.tire_progressive_ratio_rear
        onset = onset if variant.tire_progressive_onset_rear_m is None else variant.tire_progressive_onset_rear_m
    return float(ratio), TIRE_PROGRESSIVE_ONSET_M if onset is None else float(onset)


def check_progressive(variant) -> None:
    """Refuse a progressive-tire field of ``variant`` that has no effect or starts the stiffening
    below 0 m of deflection (ranges are checked with the other fields).

    Raises
    ------
    ValueError
        One sentence naming the field and the fix.
    """
    for name in ("tire_progressive_onset_m", "tire_progressive_spread_m", *REAR_FIELDS.values()):
        if getattr(variant, name) is not None and variant.tire_progressive_ratio is None:
            rear = "; 0 keeps the front tires linear" if name in REAR_FIELDS.values() else ""
            raise ValueError(f"vehicle.{name} only applies to a progressive tire: set vehicle.tire_progressive_ratio "
                             f"too (without it the tire is linear{rear})")
    spread = variant.tire_progressive_spread_m
    if spread is None:
        return
    for front, field in ((True, "tire_progressive_onset_m"), (False, "tire_progressive_onset_rear_m")):
        onset = axle_progressive(variant, front)[1]
        if onset - 0.5 * spread < 0:
            raise ValueError(f"vehicle.tire_progressive_spread_m = {spread:g} m starts the stiffening below 0 m "
                             f"of deflection (onset {onset:g} m - spread / 2): lower it or raise vehicle.{field}")


def add_progressive_tire(spec: mujoco.MjSpec, corner: str, ratio: float, onset_m: float,
                         spread_m: float | None = None) -> None:
    """The progressive elements on ``corner``'s tire tendon (see ``TruckVariant.tire_progressive_ratio``).

    Without a spread (``spread_m`` None or 0 m), one element: F2 = k2 (R0 - onset - L) clamped to
    [0, 1e7] N, k2 = ratio kt, no damping (a bilinear tire, one kink). With a spread (m),
    :data:`TIRE_PROGRESSIVE_STEPS` such elements, each k2 = ratio kt / 5, at the onsets of
    :func:`progressive_onsets`: the stiffness rises in equal steps from kt to (1 + ratio) kt across
    the spread, a piecewise-linear approximation of a tire's smooth stiffening. The tire force sensor
    becomes, once, the tendon's total actuator force (``mjSENS_TENDONACTFRC``): the sum of the elements.
    """
    tire = spec.actuator(names.tire_actuator(corner))
    kt = -float(tire.biasprm[1])
    r0 = float(tire.biasprm[0]) / kt
    onsets = progressive_onsets(onset_m, spread_m)
    k2 = float(ratio) * kt / len(onsets)  # the ratio shared equally by the elements
    tendon = names.tire_tendon(corner)
    for step, onset in enumerate(onsets):
        spec.add_actuator(name=names.tire_progressive_actuator(corner, step), target=tendon,
                          trntype=mujoco.mjtTrn.mjTRN_TENDON, gaintype=mujoco.mjtGain.mjGAIN_FIXED,
                          gainprm=[0.0] * 10, biastype=mujoco.mjtBias.mjBIAS_AFFINE,
                          biasprm=[k2 * (r0 - onset), -k2, 0.0] + [0.0] * 7,
                          forcelimited=mujoco.mjtLimited.mjLIMITED_TRUE, forcerange=list(tire.forcerange),
                          ctrllimited=mujoco.mjtLimited.mjLIMITED_FALSE)
    sensor = names.tire_sensor(corner)
    spec.delete(spec.sensor(sensor))
    spec.add_sensor(name=sensor, type=mujoco.mjtSensor.mjSENS_TENDONACTFRC, objtype=mujoco.mjtObj.mjOBJ_TENDON,
                    objname=tendon)
