"""A channel-timing error as the calibrated tire shows it.

A skew tau between the force and the LVDT channels (the force lagging by tau, ``F_meas(t) =
F(t - tau)``) turns the measured force's phase against the pan's by ``-omega tau``. Through the tire,
``F ~ k_t x + c_t dx/dt``, that turn is, to first order in ``omega tau``, a tire damping smaller by
``k_t tau``: 0.5 ms on a 1 MN/m tire is 500 N s/m, 0.29 of the catalogue front tire's 1.7 kN s/m. A
fit that reads the tire's damping off the record finds ``c_t - k_t tau``, and nothing in the record
tells the two apart. What does show is a tire whose fitted time constant ``c_t / k_t`` lies outside
a tire's (:data:`TIRE_TIME_CONSTANT_S`): :func:`skew_note` says so and how large a skew would explain
it. A skew within the band passes unseen; the lab's channel timing (``--force-filter``,
``--lvdt-filter``) is what removes it.
"""

from __future__ import annotations

__all__ = ["TIRE_TIME_CONSTANT_S", "tire_time_constants", "skew_note"]

#: s: the band of a truck tire's time constant c_t / k_t (its damping over its stiffness). **Estimate**:
#: a tire's damping ratio at the wheel-hop mode (~10 Hz) is a few per cent of critical (Cebon 1999,
#: ch. 2; 1-12 %), c_t / k_t = 2 zeta / omega_hop: 0.3-4 ms. The catalogue's tires (truck_rig.xml):
#: 1.7 ms on both axles.
TIRE_TIME_CONSTANT_S = (0.3e-3, 4.0e-3)


def tire_time_constants(calibration) -> dict[str, float]:
    """Each axle's fitted tire time constant c_t / k_t (s), ``{"front": ..., "rear": ...}``, from the
    calibration's fitted values and, where a value was held, its held one."""
    values = {**calibration.fixed, **dict(zip(calibration.names, calibration.fitted))}
    out = {}
    for axle in ("front", "rear"):
        c, k = values.get(f"tire_damping_{axle}_Ns_per_m"), values.get(f"tire_stiffness_{axle}_N_per_m")
        if c is not None and k:
            out[axle] = float(c) / float(k)
    return out


def skew_note(calibration) -> str:
    """One sentence where a fitted tire's time constant lies outside :data:`TIRE_TIME_CONSTANT_S`
    (the sign of a skew between the force and the LVDT channels), naming the axle and the skew that
    would explain it; "" where every axle's lies inside (or without a calibration)."""
    if calibration is None:
        return ""
    lo, hi = TIRE_TIME_CONSTANT_S
    for axle, tc in tire_time_constants(calibration).items():
        if lo <= tc <= hi:
            continue
        skew = (lo - tc) if tc < lo else (tc - hi)
        late, early = ("force", "LVDT") if tc < lo else ("LVDT", "force")
        return (f"note: the {axle} tires' fitted damping is {1e3 * tc:.2f} ms of their stiffness, outside a tire's "
                f"{1e3 * lo:g}-{1e3 * hi:g} ms: the {late} channel late on the {early} by {1e3 * skew:.2f} ms or more "
                "gives the same (a skew tau reads as k_t tau of tire damping); check the channels' timing "
                "(--force-filter, --lvdt-filter)")
    return ""
