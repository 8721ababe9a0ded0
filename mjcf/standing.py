"""Whether a described truck can stand on the rig: a rest found, every tire loaded, every spring in its
travel, the rest stable.

A truck built from a spec sheet (:mod:`rigsim.mjcf.description`) may be one no rig could hold: a payload
behind the rear axle of a short truck lifts the steer tires, springs too soft for the load close on
their bump stops, a spring that never reaches its load finds no rest, air springs too soft for a
high payload hold a rest the truck leans away from. :func:`check_stands` solves
the truck's rest on rigid pans at mid-stroke (:func:`rigsim.mjcf.physics.static_equilibrium`) and refuses
such a truck in one sentence naming the field to change, before anything runs.
"""

from __future__ import annotations

import mujoco
import numpy as np

from rigsim.mjcf import names
from rigsim.mjcf.description import lever_loads

__all__ = ["MIN_TIRE_SHARE", "MIN_GAP_M", "MAX_GAP_M", "MAX_GROWTH_PER_S", "check_stands", "truck_layout"]

#: A tire carrying less than this share of the truck's weight at rest (1) is lifted: a wheel so light
#: leaves its pan at the first bump of any road (a steer tire carries 20-30 % of a truck's weight).
MIN_TIRE_SHARE = 0.02
#: m: the hanger-to-seat gap at rest below which a spring sits on its bump stop (0.3 m at the design
#: ride height; truck suspensions travel 0.08-0.12 m in bump before the stop, **estimate**: 0.3 - 0.25).
MIN_GAP_M = 0.05
#: m: the gap above which a spring hangs in rebound, off its seat (0.3 m + 0.25 m, as :data:`MIN_GAP_M`).
MAX_GAP_M = 0.55
#: 1/s: a real eigenvalue of the truck at rest (dry friction off) above this is a rest it leaves, the
#: truck leaning over on its springs; below it, the finite differences' noise about neutral states
#: (the bound :meth:`rigsim.scenarios.core.rig.Rig.check_stable` takes for the rig's loop too).
MAX_GROWTH_PER_S = 1e-3


def check_stands(variant) -> None:
    """Refuse a truck (:class:`rigsim.mjcf.variant.TruckVariant`) that cannot stand on the rig's pans at mid-stroke.

    Raises
    ------
    ValueError
        One sentence naming the field to change: no rest, a tire lifted, a spring on its stops.
    """
    from rigsim.mjcf.build import build_model
    from rigsim.mjcf.physics import EquilibriumError, RigIndex, static_equilibrium, tire_forces

    model = build_model(variant, pans="fixed")
    data = mujoco.MjData(model)
    _check_loads(model, _lever_loads(model))  # a lifted axle first: Newton finds no rest without one
    try:
        static_equilibrium(model, data)
    except EquilibriumError:
        raise ValueError("vehicle: the described truck finds no rest on the rig's pans (a tire off its pan or a "
                         "spring through its travel): check vehicle.payload_kg, vehicle.payload_x_m and the spring "
                         "rates vehicle.spring_rate_front_N_per_m and vehicle.spring_rate_rear_N_per_m") from None
    _check_loads(model, tire_forces(model, data, RigIndex.of(model)))
    for corner in names.CORNERS:
        gap = float(data.ten_length[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, names.spring_tendon(corner))])
        axle = "front" if corner in names.FRONT else "rear"
        if not MIN_GAP_M <= gap <= MAX_GAP_M:
            where = "closes onto its bump stop" if gap < MIN_GAP_M else "hangs off its seat"
            raise ValueError(f"vehicle: the described truck's {corner} spring {where} at rest (hanger-to-seat gap "
                             f"{gap:.3f} m, travel {MIN_GAP_M:g} to {MAX_GAP_M:g} m): give "
                             f"vehicle.spring_rate_{axle}_N_per_m a value that carries the load, or less "
                             "vehicle.payload_kg")
    if not np.all(np.isfinite(data.qpos)):  # pragma: no cover - static_equilibrium raises first
        raise ValueError("vehicle: the described truck's rest is not finite; check its masses and rates")
    _check_upright(model, data)


def _check_upright(model: mujoco.MjModel, data: mujoco.MjData) -> None:
    """Refuse a rest the truck leaves: a real eigenvalue of its linearization there (dry friction off)
    growing faster than :data:`MAX_GROWTH_PER_S`, named after the joint that moves most in it."""
    from rigsim.mjcf.modes import MODE_NAMES, eigen

    lam, vec = eigen(model, data)
    k = int(np.argmax(lam.real))
    if lam[k].real <= MAX_GROWTH_PER_S:
        return
    dof = int(np.argmax(np.abs(vec[:model.nv, k])))
    joint = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, int(model.dof_jntid[dof]))
    raise ValueError(f"vehicle: the described truck does not stand upright at rest: its "
                     f"{MODE_NAMES.get(joint, joint)} grows at {lam[k].real:.3g} 1/s (springs too soft for the "
                     "payload's height): stiffen vehicle.spring_rate_front_N_per_m and "
                     "vehicle.spring_rate_rear_N_per_m, or lower vehicle.payload_z_m")


def _lever_loads(model: mujoco.MjModel) -> np.ndarray:
    """Each wheel's static load (N) by the lever rule (:func:`~rigsim.mjcf.description.lever_loads`,
    across each axle's track) on the truck bodies at the design pose."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    site = {c: data.site_xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, names.wheel_site(c))]
            for c in names.CORNERS}
    g = -float(model.opt.gravity[2])
    pans = {mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, names.pan_body(c)) for c in names.CORNERS}
    bodies = [(float(model.body_mass[b]) * g, data.xipos[b]) for b in range(1, model.nbody) if b not in pans]
    return lever_loads(bodies, site["fl"][0], site["rl"][0], [float(site[c][1]) for c in names.CORNERS])


def _check_loads(model: mujoco.MjModel, loads: np.ndarray) -> None:
    """Refuse a tire that carries under :data:`MIN_TIRE_SHARE` of the weight, naming the field to change."""
    weight = float(np.sum(np.clip(loads, 0.0, None)))
    for i, corner in enumerate(names.CORNERS):
        if loads[i] < MIN_TIRE_SHARE * weight:
            axle = "front" if corner in names.FRONT else "rear"
            raise ValueError(f"vehicle: the described truck's {corner} tire carries {loads[i] / 1e3:.1f} kN of "
                             f"{weight / 1e3:.1f} kN at rest and lifts off its pan: move vehicle.payload_x_m "
                             f"(or vehicle.payload_y_m) towards the {corner} wheel or change vehicle.wheelbase_m")


def truck_layout(model: mujoco.MjModel, data: mujoco.MjData) -> dict:
    """The compiled truck's geometry at its design pose and its springs as ``data`` holds them (at rest):
    ``wheelbase_m``, ``track_front_m``, ``track_rear_m`` (m, between the wheel sites), and per corner
    (fl fr rl rr) ``spring_rate_N_per_m`` (N/m) and ``spring_gap_m`` (m, hanger to seat)."""
    design = mujoco.MjData(model)
    mujoco.mj_kinematics(model, design)

    def site(corner: str) -> np.ndarray:
        return design.site_xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, names.wheel_site(corner))]

    springs = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, names.spring_tendon(c)) for c in names.CORNERS]
    return {"wheelbase_m": float(site("fl")[0] - site("rl")[0]),
            "track_front_m": float(site("fl")[1] - site("fr")[1]),
            "track_rear_m": float(site("rl")[1] - site("rr")[1]),
            "spring_rate_N_per_m": model.tendon_stiffness[springs].astype(float),
            "spring_gap_m": data.ten_length[springs].astype(float)}
