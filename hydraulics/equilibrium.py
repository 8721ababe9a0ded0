"""Static equilibrium of one actuator holding its pan at mid-stroke under a load."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import root

from .model import CLIP_KNEE, MPA, chamber_flows
from .packing import pack
from .params import ActuatorParams

__all__ = ["equilibrium_activation", "inverse_soft_clip"]


def inverse_soft_clip(y: float, limit: float) -> float:
    """Inverse of :func:`rigsim.hydraulics.model.soft_clip` (normalised command for a clipped output)."""
    knee = CLIP_KNEE * limit
    a = abs(y)
    if a <= knee:
        return y
    if a >= limit:
        raise ValueError(f"a valve opening of {y:.4g} x ksv needs a command beyond the limit "
                         f"+-{limit:g}; the load cannot be held statically")
    span = limit - knee
    u = knee - span * math.log((limit - a) / span)
    return u if y > 0 else -u


def static_flows(params: ActuatorParams, load_N: float) -> tuple[float, float, float]:
    """Spool opening and chamber pressures (Pa) at which the valve supplies exactly the leakage."""
    p = params
    pl = load_N / p.piston_area_m2
    if abs(pl) >= p.supply_pressure_Pa - p.return_pressure_Pa:
        raise ValueError(f"load_N = {load_N:.6g} N needs |P1 - P2| = {abs(pl) / MPA:.4g} MPa, at or "
                         f"above supply - return ({(p.supply_pressure_Pa - p.return_pressure_Pa) / MPA:.4g}"
                         " MPa): lower the load or raise supply_pressure_Pa / piston_area_m2")
    prm = pack(p).tolist()
    q_scale = p.rated_flow_m3_s

    def residual(z):
        xv, pm = z[0], z[1] * MPA
        p1, p2 = pm + 0.5 * pl, pm - 0.5 * pl
        q1, q2 = chamber_flows(xv, p1, p2, prm)
        q_leak = p.leakage_m3_s_Pa * (p1 - p2)
        rel1 = p.relief_conductance_m3_s_Pa * max(p1 - p.relief_pressure_Pa, 0.0)
        rel2 = p.relief_conductance_m3_s_Pa * max(p2 - p.relief_pressure_Pa, 0.0)
        return [(q1 - q_leak - rel1) / q_scale, (q2 + q_leak - rel2) / q_scale]

    guess = [0.0, 0.5 * (p.supply_pressure_Pa + p.return_pressure_Pa) / MPA]
    sol = root(residual, guess, method="hybr", options={"xtol": 1e-14})
    res = np.abs(residual(sol.x))
    if not sol.success and not np.all(res < 1e-12):
        raise ValueError(f"no static flow balance found for load_N = {load_N:.6g} N "
                         f"({sol.message}); check the valve and leakage parameters")
    xv, pm = float(sol.x[0]), float(sol.x[1]) * MPA
    return xv, pm + 0.5 * pl, pm - 0.5 * pl


def equilibrium_activation(params: ActuatorParams, load_N: float) -> np.ndarray:
    """Activation vector at static rest, pan at qpos 0 carrying ``load_N``.

    ``(P1 - P2) A = load_N``; the spool sits where the valve flows balance the cross-piston
    leakage (and relief flow, if any); the integrator holds the valve command that keeps it
    there with zero position error.

    Parameters
    ----------
    params : ActuatorParams
    load_N : float, N
        Downward static load on the pan: wheel load plus pan (and piston) weight.

    Returns
    -------
    ndarray, shape (5,)
        States in ``STATE_NAMES`` order (spool, spool_rate, p1_MPa, p2_MPa, integral_m_s).
    """
    if not isinstance(params, ActuatorParams):
        raise TypeError(f"params must be ActuatorParams, got {type(params).__name__}")
    if not math.isfinite(load_N):
        raise ValueError(f"load_N must be finite, got {load_N!r}")
    p = params
    xv, p1, p2 = static_flows(p, float(load_N))
    u0 = inverse_soft_clip(xv / p.ksv, p.command_limit)
    need = u0 + p.kdp_per_Pa * (p1 - p2)  # = Kp * integral / Ti at zero error
    if math.isinf(p.ti_s):
        if abs(need) > 1e-12:
            raise ValueError("without integral action (ti_s = inf) the pan cannot rest at qpos 0 "
                             "with zero error under this load; use a finite ti_s")
        integral = 0.0
    elif p.kp_per_m == 0.0:
        raise ValueError("actuator.kp_per_m must be > 0 for a static equilibrium held by the "
                         "integrator, got 0")
    else:
        integral = p.ti_s * need / p.kp_per_m
    return np.array([xv, 0.0, p1 / MPA, p2 / MPA, integral], dtype=np.float64)
