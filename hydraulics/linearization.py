"""Merritt's valve coefficients at the static operating point, and the paper's eq. 4.

Load flow and load pressure follow Merritt (ch. 5): ``QL = (Q1 - Q2) / 2`` with ``Q1`` the valve
flow into chamber 1 and ``Q2`` the valve flow into chamber 2 (so ``-Q2`` leaves it), and
``PL = P1 - P2``. The coefficients are the exact partial derivatives of this package's
nonlinear valve (smoothed null, laminar core) at the static operating point:

* ``Kq = dQL/dxv`` (the mean of the two flow paths' gains), and
* ``Kc = -dQL/dPL`` taken along ``P1 + P2 = const`` (``dP1 = dPL/2, dP2 = -dPL/2``), i.e.
  the average of both chambers' flow-pressure coefficients.

At the null, unloaded point (``load_N = 0``: xv = 0, P1 = P2 = (Ps + Pr)/2) the two chambers are
symmetric, the mean-pressure mode decouples, and the two-chamber model linearizes *exactly*
to eq. 4. Under a static load the two flow paths differ and eq. 4 (one load pressure) is an
approximation of the two-pressure linearization (see :mod:`rigsim.hydraulics.loop` for the exact one).

Eq. 4 lumps leakage into its ``Kc``: :func:`eq4_parameters` passes ``Kce = Kc + Ctp`` (valve
coefficient plus cross-piston leakage), Merritt's total flow-pressure coefficient. The formula
itself lives in ``rigsim.correction.output.eq4.eq4_coefficients_from`` (which this package may not import):
``eq4_coefficients_from(**eq4_parameters(params, kt, load))``.
"""

from __future__ import annotations

from dataclasses import dataclass

from .equilibrium import static_flows, inverse_soft_clip
from .model import (bulk_factor, land_coefficient, orifice_root, orifice_root_slope, smooth_opening,
                    smooth_opening_slope, soft_clip_slope)
from .packing import pack
from .params import ActuatorParams

__all__ = ["ValveLinearization", "linearization", "eq4_parameters"]


@dataclass(frozen=True)
class ValveLinearization:
    """Linearized valve and chamber coefficients at a static operating point.

    Attributes
    ----------
    load_N : float, N
        Static load of the operating point.
    spool : float, 1
        Static (normalised) spool position.
    p1_Pa, p2_Pa : float, Pa
        Static chamber pressures.
    kq_m3_s : float, m^3/s per unit spool
        Merritt's flow gain ``dQL/dxv``.
    kc_m3_s_Pa : float, m^3/(s Pa)
        Merritt's flow-pressure coefficient of the valve ``-dQL/dPL`` (relief flow included).
    kce_m3_s_Pa : float, m^3/(s Pa)
        ``kc_m3_s_Pa`` plus cross-piston leakage: the ``Kc`` eq. 4 needs.
    ksv : float, 1
        Effective static valve gain (``ksv`` times the slope of the command clip there).
    vf_m3 : float, m^3
        Total oil volume of both chambers at mid-stroke (the paper's Vf).
    beta_e_Pa : float, Pa
        Effective bulk modulus at the operating pressures (mean of both chambers).
    """

    load_N: float
    spool: float
    p1_Pa: float
    p2_Pa: float
    kq_m3_s: float
    kc_m3_s_Pa: float
    kce_m3_s_Pa: float
    ksv: float
    vf_m3: float
    beta_e_Pa: float


def linearization(params: ActuatorParams, load_N: float = 0.0) -> ValveLinearization:
    """Merritt's Kq, Kc (and Kce, Ksv, Vf, beta_e) at the static point carrying ``load_N`` (N)."""
    p = params
    xv, p1, p2 = static_flows(p, float(load_N))
    prm = pack(p).tolist()
    kv = land_coefficient(prm)
    ps, pr, lam, w = p.supply_pressure_Pa, p.return_pressure_Pa, p.laminar_drop_Pa, p.null_opening
    a_pos, a_neg = smooth_opening(xv, w), smooth_opening(-xv, w)
    s_pos, s_neg = smooth_opening_slope(xv, w), smooth_opening_slope(-xv, w)
    dq1_dxv = kv * (s_pos * orifice_root(ps - p1, lam) + s_neg * orifice_root(p1 - pr, lam))
    dq2_dxv = -kv * (s_neg * orifice_root(ps - p2, lam) + s_pos * orifice_root(p2 - pr, lam))
    dq1_dp1 = -kv * (a_pos * orifice_root_slope(ps - p1, lam) + a_neg * orifice_root_slope(p1 - pr, lam))
    dq2_dp2 = -kv * (a_neg * orifice_root_slope(ps - p2, lam) + a_pos * orifice_root_slope(p2 - pr, lam))
    crel = p.relief_conductance_m3_s_Pa
    dq1_dp1 -= crel if p1 > p.relief_pressure_Pa else 0.0
    dq2_dp2 -= crel if p2 > p.relief_pressure_Pa else 0.0
    kq = 0.5 * (dq1_dxv - dq2_dxv)
    kc = -0.25 * (dq1_dp1 + dq2_dp2)
    u0 = inverse_soft_clip(xv / p.ksv, p.command_limit)
    ksv = p.ksv * soft_clip_slope(u0, p.command_limit)
    fac = 0.5 * sum(bulk_factor(pp, p.cavitation_pressure_Pa, p.cavitation_band_Pa,
                                p.cavitation_min_fraction) for pp in (p1, p2))
    return ValveLinearization(load_N=float(load_N), spool=xv, p1_Pa=p1, p2_Pa=p2, kq_m3_s=kq,
                              kc_m3_s_Pa=kc, kce_m3_s_Pa=kc + p.leakage_m3_s_Pa, ksv=ksv,
                              vf_m3=2.0 * p.mid_volume_m3, beta_e_Pa=p.bulk_modulus_Pa * fac)


def eq4_parameters(params: ActuatorParams, kt_N_per_m: float, load_N: float = 0.0,
                   mass_kg: float | None = None) -> dict[str, float]:
    """The physical parameters of the paper's eq. 4 for ``params`` linearized at ``load_N``.

    The keys are exactly the keyword arguments of ``rigsim.correction.output.eq4.eq4_coefficients_from``
    (``rigsim.correction.output.eq4.EQ4_PARAMETERS``), the one implementation of the formula::

        num, den = eq4_coefficients_from(**eq4_parameters(params, kt, load))

    (this package does not import :mod:`correction`: it only supplies the numbers).

    Parameters
    ----------
    params : ActuatorParams
    kt_N_per_m : float, N/m
        Tire stiffness, the spring from pan to ground of eq. 4's load model (passed through
        unchecked as ``tire_N_per_m``; ``eq4_coefficients_from`` requires ``>= 0``).
    load_N : float, N
        Static load of the linearization point (0: valve null, Merritt's usual choice; the
        linearization is then exact for this package's symmetric actuator).
    mass_kg : float, kg, optional
        Moving mass mp (default ``params.pan_mass_kg``, pan plus piston).

    Returns
    -------
    dict[str, float]
        ``ksv`` (1, effective static valve gain at the operating point), ``kq_m3_s`` (m^3/s per
        unit spool, Merritt's Kq), ``kc_m3_s_Pa`` (m^3/(s Pa), Kce = valve Kc plus cross-piston
        leakage), ``kp_per_m`` (1/m), ``kdp_per_Pa`` (1/Pa), ``piston_area_m2`` (m^2),
        ``fluid_volume_m3`` (m^3, Vf of both chambers at mid-stroke), ``bulk_modulus_Pa`` (Pa,
        effective at the operating pressures), ``mass_kg`` (kg), ``damping_N_s_m`` (N s/m),
        ``tire_N_per_m`` (N/m) and ``ti_s`` (s, may be ``math.inf`` for P only).
    """
    p = params
    lin = linearization(p, load_N)
    return {
        "ksv": float(lin.ksv),
        "kq_m3_s": float(lin.kq_m3_s),
        "kc_m3_s_Pa": float(lin.kce_m3_s_Pa),
        "kp_per_m": float(p.kp_per_m),
        "kdp_per_Pa": float(p.kdp_per_Pa),
        "piston_area_m2": float(p.piston_area_m2),
        "fluid_volume_m3": float(lin.vf_m3),
        "bulk_modulus_Pa": float(lin.beta_e_Pa),
        "mass_kg": float(p.pan_mass_kg if mass_kg is None else mass_kg),
        "damping_N_s_m": float(p.friction_N_s_m),
        "tire_N_per_m": float(kt_N_per_m),
        "ti_s": float(p.ti_s),
    }
