"""The three routes to the actuator transfer function ``T_a = X_a / X_p`` and their comparison.

* Route 1, analytic: the paper's eq. 4 per wheel station (:func:`route1_models`, several ways
  of taking Merritt's Kq, :data:`ROUTE1_VARIANTS`), and the ladder from eq. 4 to the plant
  (:func:`budget_models`);
* route 2, numerical: :meth:`rigsim.scenarios.core.rig.Rig.linearize` (evaluated elsewhere through
  :class:`rigsim.scenarios.core.plant.PlantLinearization`);
* route 3, identified: the MIMO H1 estimate of a rig record (:func:`identify`), a stable
  rational fit per wheel and its comparison with route 2 (:func:`route3`).

Also the helpers every comparison uses: :func:`err_db_deg`, :func:`freqresp`,
:func:`tf_json`, :func:`roots_json`, :func:`nanmax`, and the linear models' step responses
(:func:`linear_steps`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import control
import numpy as np

from rigsim.correction.identification.identify import fit_rational, h1_estimate
from rigsim.correction.output.transfer import (apply_transfer_function, bandwidth_hz, describe_roots, eq4_transfer_function,
                                 frequency_response_hz, state_space_frequency_response, transfer_bandwidth_hz)
from rigsim.hydraulics.linearization import linearization
from rigsim.hydraulics.loop import loop_matrices
from rigsim.hydraulics.model import land_coefficient, orifice_root
from rigsim.hydraulics.packing import pack
from rigsim.hydraulics.params import ActuatorParams
from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.drive import IDENT_SKIP_S, step_drive
from rigsim.scenarios.core.plant import PlantLinearization
from rigsim.scenarios.core.rig import RigRecord
from rigsim.scenarios.studies.validate.settings import (BODE_RANGE_HZ, COHERENCE_MIN, COMPARE_MAX_HZ, FIT_ORDERS,
                                                        STEP_AT_S)

__all__ = ["ROUTE1_VARIANTS", "H1Estimate", "Route3", "err_db_deg", "freqresp", "nanmax", "roots_json", "tf_json",
           "flow_gains", "route1_models", "budget_models", "identify", "route3", "linear_steps"]


# --------------------------------------------------------------------------------------------
# Helpers.
def err_db_deg(h, ref) -> tuple[np.ndarray, np.ndarray]:
    """Magnitude (dB) and phase (deg) of ``h / ref``: how far a response is from a reference."""
    r = np.asarray(h) / np.asarray(ref)
    return 20.0 * np.log10(np.abs(r)), np.degrees(np.angle(r))


def freqresp(tf, f_hz) -> np.ndarray:
    """Complex response of a python-control system at ``f_hz`` (Hz)."""
    return frequency_response_hz(tf, f_hz)


def nanmax(values) -> float:
    """Largest of ``values`` ignoring NaN; NaN when all are NaN."""
    v = [x for x in values if not math.isnan(x)]
    return max(v) if v else math.nan


def roots_json(r) -> list[dict]:
    """Roots (rad/s) as :func:`rigsim.correction.output.transfer.describe_roots` dicts rounded to 6 digits."""
    return [{k: round(v, 6) for k, v in d.items()} for d in describe_roots(r)]


def tf_json(tf: control.TransferFunction) -> dict:
    """Coefficients (highest power of s first, s in rad/s), poles and zeros of a SISO system."""
    return {"num": [float(x) for x in np.ravel(tf.num[0][0])],
            "den": [float(x) for x in np.ravel(tf.den[0][0])],
            "poles": roots_json(tf.poles()), "zeros": roots_json(tf.zeros())}


# --------------------------------------------------------------------------------------------
# Route 1: the paper's eq. 4.
def flow_gains(params: ActuatorParams, load_N: float) -> dict[str, float]:
    """Merritt's Kq (m^3/s per unit spool) at the static point under ``load_N`` (N), per flow direction.

    ``QL = (Q1 - Q2) / 2``. Extending (spool > 0): supply -> chamber 1 across ``Ps - P1``,
    chamber 2 -> return across ``P2 - Pr``; retracting: across ``P1 - Pr`` and ``Ps - P2``.
    """
    lin = linearization(params, load_N)
    kv = land_coefficient(pack(params).tolist())
    ps, pr, lam = params.supply_pressure_Pa, params.return_pressure_Pa, params.laminar_drop_Pa
    p1, p2 = lin.p1_Pa, lin.p2_Pa
    ext = 0.5 * kv * (orifice_root(ps - p1, lam) + orifice_root(p2 - pr, lam))
    ret = 0.5 * kv * (orifice_root(p1 - pr, lam) + orifice_root(ps - p2, lam))
    return {"static_mean": lin.kq_m3_s, "extending": ext, "retracting": ret, "mean_of_directions": 0.5 * (ext + ret)}


#: Route 1 variants: how Kq and Kc are taken (the first is the one reported as route 1).
ROUTE1_VARIANTS = {
    "static_mean": "Kq, Kc = exact slopes of the valve at the static loaded point, Kq the mean of both "
                   "chambers' flow paths (rigsim.hydraulics.linearization; at rest the spool sits in the smoothed "
                   "null region, so all four metering lands contribute)",
    "null": "Kq, Kc at the unloaded valve null (load 0, P1 = P2): Merritt's textbook point",
    "extending": "Kq of the extending direction (supply to the loaded chamber 1 across Ps - P1, chamber 2 to return)",
    "retracting": "Kq of the retracting direction (chamber 1 to return across P1 - Pr, supply to chamber 2)",
}


def route1_models(params: ActuatorParams, kt_N_per_m: float, load_N: float
                  ) -> dict[str, tuple[control.TransferFunction, dict]]:
    """Eq. 4 for one wheel station, for each way of taking Merritt's coefficients.

    Parameters
    ----------
    params : ActuatorParams
    kt_N_per_m : float, N/m
        The station's tire stiffness.
    load_N : float, N
        Static actuator load (tire force plus pan weight).

    Returns
    -------
    dict
        ``variant -> (TransferFunction, coefficients)`` for the keys of :data:`ROUTE1_VARIANTS`;
        the coefficients dict holds ``ksv`` (1), ``kq_m3_s`` (m^3/s), ``kc_m3_s_Pa`` (m^3/(s Pa))
        and ``load_N`` (N) used.
    """
    lin = linearization(params, load_N)
    lin0 = linearization(params, 0.0)
    kq = flow_gains(params, load_N)
    out = {}
    for name in ROUTE1_VARIANTS:
        ln = lin0 if name == "null" else lin
        coeff = {"ksv": ln.ksv, "kq_m3_s": ln.kq_m3_s if name in ("null", "static_mean") else kq[name],
                 "kc_m3_s_Pa": ln.kce_m3_s_Pa, "load_N": ln.load_N}
        tf = eq4_transfer_function(
            ksv=coeff["ksv"], kq_m3_s=coeff["kq_m3_s"], kc_m3_s_Pa=coeff["kc_m3_s_Pa"],
            kp_per_m=params.kp_per_m, kdp_per_Pa=params.kdp_per_Pa,
            piston_area_m2=params.piston_area_m2, fluid_volume_m3=ln.vf_m3,
            bulk_modulus_Pa=ln.beta_e_Pa, mass_kg=params.pan_mass_kg,
            damping_N_s_m=params.friction_N_s_m, tire_N_per_m=float(kt_N_per_m), ti_s=params.ti_s)
        out[name] = (tf, coeff)
    return out


def budget_models(params: ActuatorParams, kt: float, load: float, f_hz) -> dict[str, np.ndarray]:
    """FRFs (complex, at ``f_hz``, Hz) of the steps from eq. 4 to the plant: which assumption of
    eq. 4 costs what, for a station of tire stiffness ``kt`` (N/m) under ``load`` (N).

    (A free unsprung mass on the tire without its suspension is not a step of this ladder: it
    puts an undamped anti-resonance at sqrt(kt / m_u) that the real axle, held by its leaf
    spring and damper, does not have. The rest, route 2 minus the last step, is the vehicle.)
    """
    static_valve = params.replace(spool_hz=math.inf)
    out = {}
    for name, (p, mass) in {"two_chamber_static_valve": (static_valve, math.inf),
                            "plus_spool_dynamics": (params, math.inf)}.items():
        a, b, c, _ = loop_matrices(p, kt, mass, load_N=load)
        out[name] = state_space_frequency_response(a, b, c, f_hz)[:, 0, 0]
    return out


# --------------------------------------------------------------------------------------------
# Route 3: identified on the nonlinear rig.
@dataclass(frozen=True)
class H1Estimate:
    """MIMO H1 estimate of a rig record.

    Attributes
    ----------
    f_hz : numpy.ndarray, Hz, (nf,)
    h : numpy.ndarray, complex, m/m, (nf, 4, 4)
        ``x_a / x_ref`` [output, input] in corner order.
    coherence : numpy.ndarray, 1, (nf, 4)
        Multiple coherence of each output.
    nperseg : Mapping[str, int]
        Welch segment lengths (samples): "high" above 1 Hz, "low" below when spliced.
    fs_hz : float, Hz
        Sampling rate of the record.
    """

    f_hz: np.ndarray
    h: np.ndarray
    coherence: np.ndarray
    nperseg: Mapping
    fs_hz: float


def identify(record: RigRecord, *, skip_s: float = IDENT_SKIP_S) -> H1Estimate:
    """Route 3's non-parametric part: MIMO H1 and multiple coherence of a rig record, after
    dropping its first ``skip_s`` (s).

    Two Welch resolutions are spliced: 4 s segments (0.25 Hz, many averages) from 1 Hz up,
    16 s segments (0.0625 Hz) below 1 Hz when the record holds at least four of them.
    """
    dt = float(record.t_s[1] - record.t_s[0])
    fs = 1.0 / dt
    k0 = int(round(skip_s / dt))
    u = record.x_ref_m[k0:]
    y = record.pan_m[k0:]
    n = u.shape[0]
    short = min(int(round(4.0 * fs)), n // 4)
    f, h, coh = h1_estimate(u, y, fs, short)
    used = {"high": short}
    long_ = int(round(16.0 * fs))
    if n >= 4 * long_:
        fl, hl, cl = h1_estimate(u, y, fs, long_)
        lo = (fl > 0) & (fl < 1.0)
        hi = f >= 1.0
        f = np.concatenate([fl[lo], f[hi]])
        h = np.concatenate([hl[lo], h[hi]])
        coh = np.concatenate([cl[lo], coh[hi]])
        used["low"] = long_
    else:
        keep = f > 0
        f, h, coh = f[keep], h[keep], coh[keep]
    return H1Estimate(f_hz=f, h=h, coherence=coh, nperseg=used, fs_hz=fs)


@dataclass(frozen=True)
class Route3:
    """Route 3 of one rig record against route 2.

    Attributes
    ----------
    corners : Mapping[str, dict]
        Per wheel: largest errors of the H1 estimate against route 2 (dB, deg, where coherence
        > :data:`COHERENCE_MIN`, 0.1 Hz to :data:`COMPARE_MAX_HZ`) and their frequencies (Hz),
        points compared, least coherence (1), low-frequency gain (1), bandwidths (Hz) of the H1
        estimate and of the fit, the fit (:func:`tf_json`) and its errors (dB, deg) against H1
        and route 2.
    estimate : H1Estimate
    fits : list of control.TransferFunction
        The rational fit of each wheel's own path, corner order.
    coupling : Mapping[str, dict]
        Per path "in->out": the largest identified cross-coupling (dB) and its frequency (Hz).
    """

    corners: Mapping
    estimate: H1Estimate
    fits: list
    coupling: Mapping


def route3(record: RigRecord, lin: PlantLinearization, f_cmp, h2_cmp) -> Route3:
    """H1 estimate, per-wheel fits and their comparison with route 2 (``h2_cmp`` at ``f_cmp``, Hz)."""
    est = identify(record)
    f3, h3, coh3 = est.f_hz, est.h, est.coherence
    h2_at3 = lin.frequency_response(f3)
    fits, out = [], {}
    sel = (f3 >= BODE_RANGE_HZ[0]) & (f3 <= COMPARE_MAX_HZ)
    for i, c in enumerate(CORNERS):
        hii = h3[:, i, i]
        ci = coh3[:, i]
        good = sel & (ci > COHERENCE_MIN) & np.isfinite(hii)
        db, deg = err_db_deg(hii, h2_at3[:, i, i])
        w = np.clip(np.nan_to_num(ci), 0.0, 0.999999)
        # sqrt(coh / (1 - coh)) ~ 1 / relative standard deviation of H1; / |H|: relative error.
        w = np.sqrt(w / (1.0 - w)) / np.maximum(np.abs(np.nan_to_num(hii)), 1e-12)
        fit = fit_rational(f3, hii, FIT_ORDERS[0], FIT_ORDERS[1], weight=w, f_max=BODE_RANGE_HZ[1],
                           f_min=BODE_RANGE_HZ[0])
        fits.append(fit)
        fdb, fdeg = err_db_deg(freqresp(fit, f3), hii)
        gdb, gdeg = err_db_deg(freqresp(fit, f_cmp), h2_cmp[:, i, i])
        low = (f3 >= BODE_RANGE_HZ[0]) & (f3 <= 1.0) & np.isfinite(hii)
        fin = np.isfinite(hii)
        k_db = int(np.argmax(np.where(good, np.abs(db), -1.0)))
        k_deg = int(np.argmax(np.where(good, np.abs(deg), -1.0)))
        any_good = bool(np.any(good))
        out[c] = {
            "frf_max_error_db": float(abs(db[k_db])) if any_good else math.nan,
            "frf_max_error_db_at_hz": float(f3[k_db]) if any_good else math.nan,
            "frf_max_error_deg": float(abs(deg[k_deg])) if any_good else math.nan,
            "frf_max_error_deg_at_hz": float(f3[k_deg]) if any_good else math.nan,
            "points_compared": int(np.sum(good)),
            "points_in_range": int(np.sum(sel)),
            "coherence_min_to_30hz": float(np.nanmin(ci[sel])),
            "low_frequency_gain": float(np.mean(np.abs(hii[low]))) if np.any(low) else math.nan,
            "bandwidth_h1_hz": bandwidth_hz(f3[fin], hii[fin], reference=1.0),
            "bandwidth_hz": transfer_bandwidth_hz(fit),
            "fit": tf_json(fit),
            "fit_max_error_db_vs_h1": float(np.max(np.abs(fdb[good]))) if any_good else math.nan,
            "fit_max_error_deg_vs_h1": float(np.max(np.abs(fdeg[good]))) if any_good else math.nan,
            "fit_max_error_db_vs_route2": float(np.max(np.abs(gdb))),
            "fit_max_error_deg_vs_route2": float(np.max(np.abs(gdeg))),
        }
    coupling = {}
    for i, c in enumerate(CORNERS):
        for j, c2 in enumerate(CORNERS):
            if i != j:
                ok = (f3 >= BODE_RANGE_HZ[0]) & (f3 <= BODE_RANGE_HZ[1]) & np.isfinite(h3[:, i, j])
                mag = np.abs(h3[ok, i, j])
                k = int(np.argmax(mag))
                coupling[f"{c2}->{c}"] = {"max_db": float(20 * np.log10(mag[k])), "at_hz": float(f3[ok][k])}
    return Route3(corners=out, estimate=est, fits=fits, coupling=coupling)


# --------------------------------------------------------------------------------------------
# Step responses of the linear models (Figure 7).
def linear_steps(lin: PlantLinearization, eq4: list, fits: list, size_m: float, t_s) -> dict[str, np.ndarray]:
    """Pan displacement (m), (len(t_s), 4), of each linear model after a step of ``size_m`` (m)
    on all four drives at :data:`STEP_AT_S`, computed at ``lin.dt_s`` and read at the instants
    ``t_s`` (s, on that grid: the nonlinear record's): "route2" (the whole plant, all inputs)
    and, when given, "route1" (``eq4``, eq. 4 per wheel) and "route3" (``fits``)."""
    t = np.asarray(t_s, dtype=float)
    rows = np.rint(t / lin.dt_s).astype(int)
    if np.any(np.abs(rows * lin.dt_s - t) > 1e-6 * lin.dt_s + 1e-12) or np.any(rows < 0):
        raise ValueError(f"the step record's instants are not on the linear model's {lin.dt_s:g} s grid")
    u = step_drive(rows[-1] * lin.dt_s, lin.dt_s, size_m, STEP_AT_S).z_m
    out = {"route2": lin.simulate(u, diagonal=False)[:, :4]}
    if eq4:
        out["route1"] = np.column_stack([apply_transfer_function(tf, u[:, i], lin.dt_s) for i, tf in enumerate(eq4)])
    if fits:
        out["route3"] = np.column_stack([apply_transfer_function(tf, u[:, i], lin.dt_s) for i, tf in enumerate(fits)])
    return {name: y[rows] for name, y in out.items()}
