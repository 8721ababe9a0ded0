"""Digressive dampers: the leaf springs' viscous dampers softer above a knee velocity
(``TruckVariant.damper_digressive_knee_m_per_s``, ``TruckVariant.damper_digressive_ratio``).

The XML gives each leaf spring a linear damper (the spring tendon's damping, N s/m). A vehicle
damper's blow-off valves open at 0.1-0.3 m/s, above which its force grows at a fraction of its
low-speed slope: a digressive damper. :func:`add_digressive_damping` lowers the spring's linear
damping to the high-speed slope and adds two one-sided saturating elements on the spring tendon
that give the rest up to the knee, one acting while the spring extends (rebound), one while it
compresses (bump) (mjcf/README.md, "Digressive dampers").

MuJoCo 4.0's compiler turns a positive velocity coefficient of an affine bias (``biasprm[2] > 0``)
into 0 (it takes a positive value for a position actuator's damping ratio, resolved against the
position gain -biasprm[1], here 0; seen compiling ``biasprm="1 0 5"`` to ``1 0 -0``): no element can
push along the motion, a negative damping beyond the knee. The elements here only resist it.
"""

from __future__ import annotations

import mujoco

from rigsim.mjcf import names
from rigsim.mjcf.features import check_field

__all__ = ["BOUNDS", "damper_slopes", "add_digressive_damping"]

#: Bounds of the digressive damper's fields: ``{field: (low, high, unit, why)}``, inclusive, SI (the
#: shape of :data:`rigsim.mjcf.variant.BOUNDS`).
BOUNDS: dict[str, tuple[float, float, str, str]] = {
    "damper_digressive_knee_m_per_s": (0.05, 0.5, "m/s", "vehicle dampers turn digressive, their blow-off "
                                       "valves opening, at 0.1-0.3 m/s (estimate); a knee below 0.05 m/s leaves "
                                       "no linear range, above 0.5 m/s a truck's suspension seldom reaches it"),
    "damper_digressive_ratio": (0.2, 1.0, "1", "a digressive damper's slope beyond its knee is a fifth to a half "
                                "of its slope below (estimate); 1 is the XML's linear damper"),
}


def damper_slopes(spec: mujoco.MjSpec, corner: str) -> tuple[float, float]:
    """The low-speed slopes of ``corner``'s leaf-spring damper as the spec has it.

    The tendon's own damping c acts on both sides; a rebound element
    (:func:`rigsim.mjcf.stations.add_rebound_damping`, its force b2 dL/dt with b2 = -(c_r - c_b) while the
    spring extends) adds -b2 to the rebound slope.

    Returns
    -------
    tuple of float, N s/m
        (rebound, bump): the slope while the spring extends and while it compresses.
    """
    c = float(spec.tendon(names.spring_tendon(corner)).damping[0])
    rebound = spec.actuator(names.spring_rebound_actuator(corner))
    return (c - float(rebound.biasprm[2]) if rebound is not None else c), c


def add_digressive_damping(spec: mujoco.MjSpec, corner: str, knee_m_per_s: float, ratio: float) -> None:
    """Make ``corner``'s leaf-spring damper digressive: slope c up to the knee velocity, ratio c beyond.

    Parameters
    ----------
    spec : mujoco.MjSpec
        A truck spec (:func:`rigsim.mjcf.build.build_spec`), edited in place. Apply after
        :func:`rigsim.mjcf.stations.add_rebound_damping` and after every change of the spring's damping
        (the per-station factors, the suspension): the two sides' slopes are read from the spec as
        it is (:func:`damper_slopes`), and a rebound element applied afterwards would split the
        lowered tendon damping as if it were the damper's mean.
    corner : str
        One of :data:`rigsim.mjcf.names.CORNERS`.
    knee_m_per_s : float, m/s
        Spring extension or compression rate |dL/dt| where the slope changes
        (``vehicle.damper_digressive_knee_m_per_s``, :data:`BOUNDS`).
    ratio : float
        Slope beyond the knee over slope below it (``vehicle.damper_digressive_ratio``).

    Notes
    -----
    With c_s the side's low-speed slope (rebound c_r while v = dL/dt > 0, bump c_b while v < 0), the
    damper's force along the tendon (N, + extending) becomes F = -c_s v for |v| <= knee and
    F = -sign(v) c_s (knee + ratio (|v| - knee)) beyond: ratio c_s |v| at every speed plus
    (1 - ratio) c_s min(|v|, knee). The tendon's damping becomes ratio c_b, a rebound element's
    slope ratio (c_r - c_b), and two affine actuators (:func:`rigsim.mjcf.names.spring_digressive_actuator`)
    add the saturating part: ``ext`` F = -(1 - ratio) c_r v clamped to [-(1 - ratio) c_r knee, 0]
    (zero while the spring compresses), ``cmp`` F = -(1 - ratio) c_b v clamped to
    [0, (1 - ratio) c_b knee]. Both elements always exist; at ratio 1 their force is zero.
    """
    if corner not in names.CORNERS:
        raise ValueError(f"corner must be one of {', '.join(names.CORNERS)}, got {corner!r}")
    knee = check_field(BOUNDS, "damper_digressive_knee_m_per_s", knee_m_per_s)
    ratio = check_field(BOUNDS, "damper_digressive_ratio", ratio)
    if spec.actuator(names.spring_digressive_actuator(corner, "ext")) is not None:
        raise ValueError(f"the {corner} damper is already digressive: add_digressive_damping applies once a corner")
    slopes = damper_slopes(spec, corner)
    spring = spec.tendon(names.spring_tendon(corner))
    damping = list(spring.damping)
    damping[0] = ratio * slopes[1]
    spring.damping = damping
    rebound = spec.actuator(names.spring_rebound_actuator(corner))
    if rebound is not None:
        bias = list(rebound.biasprm)
        bias[2] *= ratio
        rebound.biasprm = bias
    for side, slope, sign in zip(names.DAMPER_SIDES, slopes, (-1.0, 1.0)):
        cut = (1.0 - ratio) * slope  # N s/m: the saturating part's slope
        limit = cut * knee if cut * knee > 0 else 1.0  # N; with cut 0 the force is 0 in any range
        spec.add_actuator(name=names.spring_digressive_actuator(corner, side), target=names.spring_tendon(corner),
                          trntype=mujoco.mjtTrn.mjTRN_TENDON, gaintype=mujoco.mjtGain.mjGAIN_FIXED, gainprm=[0.0] * 10,
                          biastype=mujoco.mjtBias.mjBIAS_AFFINE, biasprm=[0.0, 0.0, -cut] + [0.0] * 7,
                          forcelimited=mujoco.mjtLimited.mjLIMITED_TRUE, forcerange=sorted([0.0, sign * limit]),
                          ctrllimited=mujoco.mjtLimited.mjLIMITED_FALSE)
