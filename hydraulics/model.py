"""Nonlinear equations of one servo-hydraulic actuator (reference implementation).

Merritt, *Hydraulic Control Systems* (1967): four-way spool valve with square-root orifice flow
on each metering land (ch. 5), compressible chambers ``dP/dt = beta/V (Q - A dx/dt)`` (ch. 2),
cross-piston leakage; plus a second-order spool, the analog PI position controller with
differential-pressure feedback, a smooth cavitation floor and a chamber relief.

The scalar kernels here (``*_core`` and the helpers) are written in the subset of Python numba
compiles and are registered with :func:`numba.extending.register_jitable`: executed by CPython
they are the plain-Python reference; :mod:`rigsim.hydraulics.kernels` compiles the very same source.
They read parameters from a packed vector (:func:`rigsim.hydraulics.packing.pack`); the public
functions :func:`actuator_derivatives` and :func:`actuator_force` take ``ActuatorParams``.

States (``STATE_NAMES``): spool (normalised), spool_rate (1/s), p1_MPa, p2_MPa (MPa, gauge),
integral_m_s (m s). Inputs (``INPUT_NAMES``): x_ref (m), x_a (m, 0 = mid-stroke, + up), v_a (m/s).
"""

from __future__ import annotations

import math

import numpy as np
from numba.extending import register_jitable

from .packing import (NPACK, NSTATE, P_AREA, P_BETA, P_CAVBAND, P_CAVMIN, P_CMD_LIMIT, P_CRELIEF,
                      P_DPRATED, P_FRICTION, P_KDP, P_KP, P_KSV, P_LAMINAR, P_LEAK, P_NULL,
                      P_PCAV, P_PRELIEF, P_QRATED, P_RETURN, P_SPOOL_HZ, P_SPOOL_ZETA, P_STROKE,
                      P_SUPPLY, P_TI, P_VDEAD, pack)
from .params import ActuatorParams

__all__ = ["actuator_derivatives", "actuator_force", "smooth_opening", "orifice_root",
           "soft_clip", "bulk_factor", "chamber_flows", "MPA", "MONITOR_TAU_S", "CLIP_KNEE",
           "CAVITATION_TAIL"]

#: Pa per MPa: pressures are stored in MPa inside the activation vector.
MPA = 1.0e6
#: Lag (s) with which the spool states follow the opening of a static valve (``spool_hz = inf``).
MONITOR_TAU_S = 1.0e-3
#: The command clip is linear up to this fraction of ``command_limit``.
CLIP_KNEE = 0.8
#: Below the cavitation pressure the bulk modulus falls to zero over this fraction of the
#: cavitation band (the hard pressure floor is ``p_cav - CAVITATION_TAIL * band``).
CAVITATION_TAIL = 0.01


@register_jitable
def smooth_opening(xv, width):
    """Opening of a metering land, ``(xv + sqrt(xv^2 + width^2)) / 2`` (``max(xv, 0)`` if width 0).

    Parameters
    ----------
    xv : float, 1
        Normalised spool position (positive opens this land).
    width : float, 1
        Null-region width (``null_opening``).
    """
    if width == 0.0:
        return xv if xv > 0.0 else 0.0
    r = math.sqrt(xv * xv + width * width)
    if xv >= 0.0:
        return 0.5 * (xv + r)
    return 0.5 * width * width / (r - xv)  # same value, no cancellation for xv << 0


@register_jitable
def land_openings(xv, width):
    """``(smooth_opening(xv, width), smooth_opening(-xv, width))`` with one square root."""
    if width == 0.0:
        return (xv, 0.0) if xv > 0.0 else (0.0, -xv)
    r = math.sqrt(xv * xv + width * width)
    if xv >= 0.0:
        return 0.5 * (xv + r), 0.5 * width * width / (r + xv)
    return 0.5 * width * width / (r - xv), 0.5 * (r - xv)


@register_jitable
def smooth_opening_slope(xv, width):
    """d smooth_opening / d xv (1/1)."""
    if width == 0.0:
        if xv == 0.0:
            return 0.5  # mean of both one-sided slopes (the limit of the smoothed land)
        return 1.0 if xv > 0.0 else 0.0
    return 0.5 * (1.0 + xv / math.sqrt(xv * xv + width * width))


@register_jitable
def orifice_root(dp, laminar):
    """Signed square root of a pressure drop, with a cubic laminar core (sqrt(Pa)).

    ``sign(dp) sqrt(|dp|)`` for ``|dp| >= laminar``; below, ``dp (1.25 - 0.25 (dp/laminar)^2) /
    sqrt(laminar)``, which matches the root in value and slope at ``|dp| = laminar``.
    """
    a = abs(dp)
    if a >= laminar:
        r = math.sqrt(a)
        return r if dp >= 0.0 else -r
    z = dp / laminar
    return dp * (1.25 - 0.25 * z * z) / math.sqrt(laminar)


@register_jitable
def orifice_root_slope(dp, laminar):
    """d orifice_root / d dp (1/sqrt(Pa))."""
    a = abs(dp)
    if a >= laminar:
        return 0.5 / math.sqrt(a)
    z = dp / laminar
    return (1.25 - 0.75 * z * z) / math.sqrt(laminar)


@register_jitable
def soft_clip(u, limit):
    """Smooth saturation of the normalised command: identity up to ``CLIP_KNEE * limit``, then an
    exponential approach to ``+-limit`` (continuous value and slope)."""
    knee = CLIP_KNEE * limit
    a = abs(u)
    if a <= knee:
        return u
    span = limit - knee
    y = limit - span * math.exp(-(a - knee) / span)
    return y if u > 0.0 else -y


@register_jitable
def soft_clip_slope(u, limit):
    """d soft_clip / d u (1/1)."""
    knee = CLIP_KNEE * limit
    a = abs(u)
    if a <= knee:
        return 1.0
    return math.exp(-(a - knee) / (limit - knee))


@register_jitable
def bulk_factor(p, p_cav, band, fmin):
    """Fraction of the nominal bulk modulus at gauge pressure ``p`` (Pa).

    1 above ``p_cav + band``; a smoothstep down to ``fmin`` at the cavitation pressure
    ``p_cav``; below it a linear fall to 0 at ``p_cav - CAVITATION_TAIL * band`` (the hard floor,
    which the pressure approaches but cannot pass: a chamber pulled open fills with vapour).
    """
    z = (p - p_cav) / band
    if z >= 1.0:
        return 1.0
    if z <= 0.0:
        t = 1.0 + z / CAVITATION_TAIL
        return fmin * t if t > 0.0 else 0.0
    return fmin + (1.0 - fmin) * z * z * (3.0 - 2.0 * z)


@register_jitable
def land_coefficient(prm):
    """Flow coefficient of one metering land at rated opening, m^3/(s sqrt(Pa)): the rated flow
    passes two lands in series, each dropping half the rated valve drop."""
    return prm[P_QRATED] / math.sqrt(0.5 * prm[P_DPRATED])


@register_jitable
def chamber_flows(xv, p1, p2, prm):
    """Valve flows into chamber 1 and into chamber 2 (m^3/s) at spool ``xv`` and pressures in Pa.

    Positive ``xv`` connects supply to chamber 1 and chamber 2 to return (Merritt's four-way valve).
    """
    kv = land_coefficient(prm)
    ps = prm[P_SUPPLY]
    pr = prm[P_RETURN]
    lam = prm[P_LAMINAR]
    a_pos, a_neg = land_openings(xv, prm[P_NULL])
    q1 = kv * (a_pos * orifice_root(ps - p1, lam) - a_neg * orifice_root(p1 - pr, lam))
    q2 = kv * (a_neg * orifice_root(ps - p2, lam) - a_pos * orifice_root(p2 - pr, lam))
    return q1, q2


@register_jitable
def valve_command(xref, xa, p1, p2, integ, prm):
    """Controller output ``Kp (e + integral/Ti) - Kdp (P1 - P2)`` (normalised, before the clip)."""
    ti = prm[P_TI]
    inv_ti = 0.0 if math.isinf(ti) else 1.0 / ti
    return prm[P_KP] * ((xref - xa) + integ * inv_ti) - prm[P_KDP] * (p1 - p2)


@register_jitable
def derivatives_core(spool, rate, p1m, p2m, integ, xref, xa, va, prm, out):
    """Write the five state derivatives into ``out[0:5]`` (units of the states per second)."""
    p1 = p1m * MPA
    p2 = p2m * MPA
    cmd = prm[P_KSV] * soft_clip(valve_command(xref, xa, p1, p2, integ, prm), prm[P_CMD_LIMIT])
    f_hz = prm[P_SPOOL_HZ]
    if math.isinf(f_hz):  # static valve: the flows see the command, the states only monitor it
        xv = cmd
        out[0] = (cmd - spool) / MONITOR_TAU_S
        out[1] = -rate / MONITOR_TAU_S
    else:
        wn = 2.0 * math.pi * f_hz
        xv = spool
        out[0] = rate
        out[1] = wn * wn * (cmd - spool) - 2.0 * prm[P_SPOOL_ZETA] * wn * rate
    q1, q2 = chamber_flows(xv, p1, p2, prm)
    area = prm[P_AREA]
    half = 0.5 * prm[P_STROKE]
    vdead = prm[P_VDEAD]
    v1 = vdead + area * max(half + xa, 0.0)
    v2 = vdead + area * max(half - xa, 0.0)
    q_leak = prm[P_LEAK] * (p1 - p2)
    prel = prm[P_PRELIEF]
    crel = prm[P_CRELIEF]
    q_rel1 = crel * max(p1 - prel, 0.0)
    q_rel2 = crel * max(p2 - prel, 0.0)
    beta = prm[P_BETA]
    pcav = prm[P_PCAV]
    band = prm[P_CAVBAND]
    fmin = prm[P_CAVMIN]
    displaced = area * va
    n1 = q1 - q_leak - q_rel1 - displaced  # net oil flow into chamber 1, m^3/s
    n2 = q2 + q_leak - q_rel2 + displaced
    # A filling chamber refills its vapour at the cavitation pressure's stiffness (no floor tail):
    # so a chamber sitting on the hard floor recovers; dP/dt stays continuous (it is 0 at n = 0).
    b1 = beta * bulk_factor(p1 if n1 < 0.0 else max(p1, pcav), pcav, band, fmin)
    b2 = beta * bulk_factor(p2 if n2 < 0.0 else max(p2, pcav), pcav, band, fmin)
    out[2] = (b1 * n1) / (v1 * MPA)
    out[3] = (b2 * n2) / (v2 * MPA)
    out[4] = xref - xa


@register_jitable
def force_core(p1m, p2m, va, prm):
    """Actuator force on the pan (N, + up): ``A (P1 - P2) - b v``."""
    return prm[P_AREA] * ((p1m - p2m) * MPA) - prm[P_FRICTION] * va


# --------------------------------------------------------------------------------------------
def _as_packed(params) -> np.ndarray:
    if isinstance(params, ActuatorParams):
        return pack(params)
    prm = np.asarray(params, dtype=np.float64)
    if prm.shape != (NPACK,):
        raise ValueError(f"params must be ActuatorParams or a packed vector of length {NPACK}, "
                         f"got shape {prm.shape}")
    return prm


def actuator_derivatives(t: float, x, u, params) -> np.ndarray:
    """python-control style dynamics ``f(t, x, u, params)`` of one actuator.

    Parameters
    ----------
    t : float, s
        Time (unused: the equations are time-invariant).
    x : array_like, shape (5,)
        States in ``STATE_NAMES`` order (spool 1, spool_rate 1/s, p1 MPa, p2 MPa, integral m s).
    u : array_like, shape (3,)
        Inputs in ``INPUT_NAMES`` order: x_ref (m), x_a (m), v_a (m/s).
    params : ActuatorParams or ndarray
        Parameters, or their packed vector.

    Returns
    -------
    ndarray, shape (5,)
        ``dx/dt`` in the units of the states per second (pressures in MPa/s).
    """
    prm = _as_packed(params).tolist()  # list indexing keeps the pure-Python path fast
    xs = [float(v) for v in np.asarray(x, dtype=np.float64).ravel()]
    us = [float(v) for v in np.asarray(u, dtype=np.float64).ravel()]
    if len(xs) != NSTATE or len(us) != 3:
        raise ValueError(f"x must have {NSTATE} states and u 3 inputs, got {len(xs)} and {len(us)}")
    out = [0.0] * NSTATE
    derivatives_core(xs[0], xs[1], xs[2], xs[3], xs[4], us[0], us[1], us[2], prm, out)
    return np.array(out)


def actuator_force(x, v_a: float, params) -> float:
    """Force of the actuator on the pan, N (+ up): ``A (P1 - P2) - friction * v_a``.

    Parameters
    ----------
    x : array_like, shape (5,)
        States (``STATE_NAMES``).
    v_a : float, m/s
        Pan velocity.
    params : ActuatorParams or ndarray
    """
    prm = _as_packed(params).tolist()
    xs = np.asarray(x, dtype=np.float64).ravel()
    return float(force_core(float(xs[2]), float(xs[3]), float(v_a), prm))
