"""The paper's eq. 4: the linearized DYNTRAC actuator ``T_a(s) = X_a(s) / X_p(s)`` from its parameters.

With ``Ke = Kp / Ap`` and ``Kc' = Kc + Kdp Ksv Kq`` the paper prints::

    T_a(s) = (b1 s + b0) / (a4 s^4 + a3 s^3 + a2 s^2 + a1 s + a0)

    b0 = b1 = a0 = Ksv Kq Ke
    a1 = a0 + Kc' kt / Ap^2
    a2 = Kc' bp / Ap^2 + Vf kt / (4 beta_e Ap^2) + 1
    a3 = Kc' mp / Ap^2 + Vf bp / (4 beta_e Ap^2)
    a4 = Vf mp / (4 beta_e Ap^2)

``b0 = b1`` is the PI position controller ``Kp (1 + 1 / (Ti s))`` with ``Ti = 1 s``; this module
keeps ``Ti`` as an optional parameter (``b1 = K``, ``b0 = a0 = K / Ti``, ``a1 = K + Kc' kt / Ap^2``),
which reproduces the printed formulas exactly at the default ``Ti = 1 s``. The polynomials are
scaled as in the paper (the "1" of ``a2`` is the piston term), so ``a_n`` has units s^(n-2) with s
in rad/s, and ``T_a(0) = b0 / a0 = 1``: at steady state the pan follows its drive.

This is the one implementation of the formula in this project's correction toolkit; it imports
only numpy so that real rig data can be corrected without a simulator.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["EQ4_PARAMETERS", "eq4_coefficients_from"]

#: Names (with units) of the physical parameters of eq. 4, as keyword arguments of
#: :func:`eq4_coefficients_from` and keys of an actuator file's ``[parameters]`` table.
EQ4_PARAMETERS: dict[str, str] = {
    "ksv": "1, static gain of the servovalve (normalised command -> normalised spool)",
    "kq_m3_s": "m^3/s per unit spool, flow gain Kq of the linearized valve",
    "kc_m3_s_Pa": "m^3/(s Pa), flow-pressure coefficient Kc (valve plus leakage)",
    "kp_per_m": "1/m, proportional gain Kp of the position controller",
    "kdp_per_Pa": "1/Pa, differential-pressure feedback gain Kdp",
    "piston_area_m2": "m^2, piston area Ap",
    "fluid_volume_m3": "m^3, total oil volume of both chambers Vf",
    "bulk_modulus_Pa": "Pa, effective bulk modulus beta_e",
    "mass_kg": "kg, moving mass of piston and wheelpan mp",
    "damping_N_s_m": "N s/m, viscous friction bp",
    "tire_N_per_m": "N/m, tire stiffness kt (the load of eq. 4)",
    "ti_s": "s, integral time Ti of the PI position controller (optional, default 1 s as printed)",
}


def eq4_coefficients_from(*, ksv: float, kq_m3_s: float, kc_m3_s_Pa: float, kp_per_m: float,
                          kdp_per_Pa: float, piston_area_m2: float, fluid_volume_m3: float,
                          bulk_modulus_Pa: float, mass_kg: float, damping_N_s_m: float,
                          tire_N_per_m: float, ti_s: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Numerator and denominator of eq. 4 (descending powers of s) from physical parameters.

    Parameters
    ----------
    ksv : float, 1
        Static gain of the servovalve ``Ksv`` (> 0).
    kq_m3_s : float, m^3/s per unit spool
        Flow gain ``Kq`` of the linearized valve (> 0).
    kc_m3_s_Pa : float, m^3/(s Pa)
        Flow-pressure coefficient ``Kc`` (>= 0; valve plus cross-piston leakage).
    kp_per_m : float, 1/m
        Proportional gain ``Kp`` of the position controller (> 0).
    kdp_per_Pa : float, 1/Pa
        Differential-pressure feedback gain ``Kdp`` (>= 0).
    piston_area_m2 : float, m^2
        Piston area ``Ap`` (> 0).
    fluid_volume_m3 : float, m^3
        Total oil volume of both chambers ``Vf`` (> 0).
    bulk_modulus_Pa : float, Pa
        Effective bulk modulus ``beta_e`` (> 0).
    mass_kg : float, kg
        Moving mass of piston and wheelpan ``mp`` (> 0).
    damping_N_s_m : float, N s/m
        Viscous friction ``bp`` (>= 0).
    tire_N_per_m : float, N/m
        Tire stiffness ``kt`` (>= 0), the spring from pan to ground of eq. 4's load model.
    ti_s : float, s, optional
        Integral time ``Ti`` of the PI position controller (> 0, may be ``math.inf`` for a P-only
        controller, which gives ``b0 = a0 = 0``); default 1 s, the paper's ``b0 = b1 = a0``.

    Returns
    -------
    num : numpy.ndarray, shape (2,)
        ``[b1, b0]`` (units s and 1 with s in rad/s).
    den : numpy.ndarray, shape (5,)
        ``[a4, a3, a2, a1, a0]`` (units s^2, s, 1, 1/s, 1/s^2 times the common scale).

    Raises
    ------
    ValueError
        If a parameter is not a finite real number or out of its range; the message names it.
    """
    values = dict(ksv=ksv, kq_m3_s=kq_m3_s, kc_m3_s_Pa=kc_m3_s_Pa, kp_per_m=kp_per_m,
                  kdp_per_Pa=kdp_per_Pa, piston_area_m2=piston_area_m2,
                  fluid_volume_m3=fluid_volume_m3, bulk_modulus_Pa=bulk_modulus_Pa, mass_kg=mass_kg,
                  damping_N_s_m=damping_N_s_m, tire_N_per_m=tire_N_per_m, ti_s=ti_s)
    for name, value in values.items():
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise ValueError(f"eq. 4 parameter {name} must be a real number, got {value!r}")
        if math.isnan(value) or (math.isinf(value) and name != "ti_s"):
            raise ValueError(f"eq. 4 parameter {name} must be finite, got {value!r}")
    positive = ("ksv", "kq_m3_s", "kp_per_m", "piston_area_m2", "fluid_volume_m3", "bulk_modulus_Pa",
                "mass_kg", "ti_s")
    for name in positive:
        if not values[name] > 0:
            raise ValueError(f"eq. 4 parameter {name} must be > 0, got {values[name]!r}")
    for name in ("kc_m3_s_Pa", "kdp_per_Pa", "damping_N_s_m", "tire_N_per_m"):
        if not values[name] >= 0:
            raise ValueError(f"eq. 4 parameter {name} must be >= 0, got {values[name]!r}")

    ap2 = float(piston_area_m2) ** 2
    k = float(ksv) * float(kq_m3_s) * float(kp_per_m) / float(piston_area_m2)  # Ksv Kq Ke
    inv_ti = 0.0 if math.isinf(ti_s) else 1.0 / float(ti_s)
    kc_total = float(kc_m3_s_Pa) + float(kdp_per_Pa) * float(ksv) * float(kq_m3_s)  # Kc + Kdp Ksv Kq
    compliance = float(fluid_volume_m3) / (4.0 * float(bulk_modulus_Pa) * ap2)  # Vf / (4 beta Ap^2)
    bp, kt, mp = float(damping_N_s_m), float(tire_N_per_m), float(mass_kg)
    a0 = k * inv_ti
    a1 = k + kc_total * kt / ap2
    a2 = kc_total * bp / ap2 + compliance * kt + 1.0
    a3 = kc_total * mp / ap2 + compliance * bp
    a4 = compliance * mp
    return np.array([k, k * inv_ti]), np.array([a4, a3, a2, a1, a0])
