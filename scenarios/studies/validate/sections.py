"""The sections of ``validate.json``, each built from the routes and the runs it summarises.

Every function returns a plain nested dict (SI units in the key names: ``_hz``, ``_db``,
``_deg``, ``_m``, ``_mm``, ``_pct``, ``_N``) for one field of
:class:`rigsim.scenarios.studies.validate.result.ValidateResult`, plus, where the figures need them,
the curves it was made from.
"""

from __future__ import annotations

import math

import numpy as np

from rigsim.correction.output.transfer import bandwidth_hz, transfer_bandwidth_hz
from rigsim.hydraulics.params import ActuatorParams
from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.drive import IDENT_SEED
from rigsim.scenarios.core.plant import PlantLinearization
from rigsim.scenarios.studies.paper.table import PAPER_TABLE1  # the paper's Table 1, one home for its numbers
from rigsim.scenarios.studies.validate.routes import (ROUTE1_VARIANTS, Route3, budget_models, err_db_deg, freqresp,
                                                      linear_steps, nanmax, roots_json, tf_json)
from rigsim.scenarios.studies.validate.runs import IdentificationRun
from rigsim.scenarios.studies.validate.settings import FIT_ORDERS, STEP_AT_S, STEP_LARGE_M, STEP_SMALL_M

__all__ = ["STEP_SIZES", "route2_section", "route1_section", "budget_section", "route3_section", "steps_section",
           "friction_off_section", "table1_section"]

#: The Figure 7 steps: name -> size, m.
STEP_SIZES = {"small": STEP_SMALL_M, "large": STEP_LARGE_M}

#: Table 1 rows -> the runs they come from.
TABLE1_ROWS = (("road_test", "road"), ("rig_test", "rig"), ("linearized_model", "lin_route2_per_wheel"),
               ("linearized_model_eq4", "lin_eq4"), ("linearized_model_route2_mimo", "lin_route2_mimo"))


def _coupling(h, f_hz) -> dict:
    out = {}
    for i, c in enumerate(CORNERS):
        for j, c2 in enumerate(CORNERS):
            if i != j:
                mag = np.abs(h[:, i, j])
                k = int(np.argmax(mag))
                out[f"{c2}->{c}"] = {"max_db": float(20 * np.log10(mag[k])), "at_hz": float(f_hz[k])}
    return out


def route2_section(lin: PlantLinearization, f_bode, h2_bode) -> dict:
    """Route 2: static gains (1), -3 dB bandwidths (Hz), poles and own-path zeros (rad/s),
    cross-coupling (dB at Hz, from ``h2_bode`` at ``f_bode``), static loads (N) and tires (N/m)."""
    dc2 = np.abs(lin.frequency_response([1e-4])[0])
    f_bw = np.geomspace(0.05, 200.0, 3000)
    h2_bw = lin.frequency_response(f_bw)
    bw2 = {c: bandwidth_hz(f_bw, h2_bw[:, i, i], reference=float(dc2[i, i])) for i, c in enumerate(CORNERS)}
    coupling2 = _coupling(h2_bode, f_bode)
    worst = max(coupling2.items(), key=lambda kv: kv[1]["max_db"])
    return {
        "method": "mujoco.mjd_transitionFD (centred, eps 1e-6) of truck + pans + 4 hydraulic actuators at "
                  "static rest, leaf-spring frictionloss disabled; H = C (exp(j 2 pi f dt) I - A)^-1 B",
        "states": int(lin.a.shape[0]),
        "dc_gain": {c: float(dc2[i, i]) for i, c in enumerate(CORNERS)},
        "bandwidth_hz": bw2,
        "poles": roots_json(lin.poles()),
        "zeros": {c: roots_json(lin.siso_zeros(i)) for i, c in enumerate(CORNERS)},
        "cross_coupling_max": {"path": worst[0], **worst[1]},
        "cross_coupling": coupling2,
        "static_load_N": {c: float(lin.load_N[i]) for i, c in enumerate(CORNERS)},
        "tire_N_per_m": {c: float(lin.kt_N_per_m[i]) for i, c in enumerate(CORNERS)},
    }


def route1_section(r1: list, f_cmp, h2_cmp, f_bode) -> tuple[dict, dict]:
    """Route 1 (every variant against route 2 at ``f_cmp``, Hz), and eq. 4's response at
    ``f_bode`` (Hz) per corner for the Bode plots."""
    out = {"flow_direction": (
        "route 1 = variant 'static_mean': Kq and Kc are the exact slopes of the valve at each station's "
        "static loaded point (P1 > P2), Kq the mean of the two chambers' flow paths, QL = (Q1 - Q2)/2, "
        "Kc including cross-piston leakage; the other variants show the effect of the choice"),
        "variants": {}, "bandwidth_hz": {}, "models": {}}
    for name, text in ROUTE1_VARIANTS.items():
        var = {"description": text, "corners": {}}
        for i, c in enumerate(CORNERS):
            tf, coeff = r1[i][name]
            db, deg = err_db_deg(freqresp(tf, f_cmp), h2_cmp[:, i, i])
            var["corners"][c] = {**{k: float(v) for k, v in coeff.items()},
                                 "bandwidth_hz": transfer_bandwidth_hz(tf),
                                 "frf_max_error_db": float(np.max(np.abs(db))),
                                 "frf_max_error_deg": float(np.max(np.abs(deg)))}
        var["frf_max_error_db"] = max(v["frf_max_error_db"] for v in var["corners"].values())
        var["frf_max_error_deg"] = max(v["frf_max_error_deg"] for v in var["corners"].values())
        out["variants"][name] = var
    out["mid_band_gain_db"] = {}
    h1_bode = {}
    for i, c in enumerate(CORNERS):
        tf = r1[i]["static_mean"][0]
        out["bandwidth_hz"][c] = transfer_bandwidth_hz(tf)
        # Between 1/Ti and the bandwidth eq. 4 is ~ b1 s / (a1 s): the proportional loop's droop
        # under the tire-to-ground load, b1 / a1 = K / (K + Kc' kt / Ap^2).
        b1, a1 = float(np.ravel(tf.num[0][0])[0]), float(np.ravel(tf.den[0][0])[3])
        out["mid_band_gain_db"][c] = 20.0 * math.log10(b1 / a1)
        out["models"][c] = tf_json(tf)
        h1_bode[c] = freqresp(tf, f_bode)
    return out, h1_bode


def budget_section(params: ActuatorParams, lin: PlantLinearization, r1: list, f_cmp, h2_cmp) -> tuple[dict, dict]:
    """The departure budget: each step from eq. 4 to route 2 against route 2 (dB, deg), and
    the stages' responses at ``f_cmp`` (Hz) per corner for the plot."""
    budget, curves, one_pressure = {}, {}, {}
    for i, c in enumerate(CORNERS):
        stages = {"eq4": freqresp(r1[i]["static_mean"][0], f_cmp)}
        stages.update(budget_models(params, float(lin.kt_N_per_m[i]), float(lin.load_N[i]), f_cmp))
        row = {}
        for name, h in stages.items():
            db, deg = err_db_deg(h, h2_cmp[:, i, i])
            row[name] = {"max_error_db": float(np.max(np.abs(db))), "max_error_deg": float(np.max(np.abs(deg))),
                         "error_db_at_30hz": float(db[-1]), "error_deg_at_30hz": float(deg[-1])}
        budget[c] = row
        curves[c] = stages
        db, deg = err_db_deg(stages["eq4"], stages["two_chamber_static_valve"])
        one_pressure[c] = {"max_db": float(np.max(np.abs(db))), "max_deg": float(np.max(np.abs(deg)))}
    section = {
        "stages": {
            "eq4": "paper's eq. 4 (route 1)",
            "two_chamber_static_valve": "both chambers linearized separately at the loaded point, static valve, tire to ground",
            "plus_spool_dynamics": "... with the 150 Hz second-order spool (the valve of the plant); what "
                                   "remains to route 2 is the vehicle",
            "route2": "the whole plant (truck, suspension, the other three actuators), MuJoCo's Euler map",
        },
        "versus_route2": budget,
        "eq4_vs_two_chamber_static_valve": one_pressure,
    }
    return section, curves


def route3_section(r3: Route3, ident: IdentificationRun, ident_s: float) -> dict:
    """Route 3: how it was identified, the drive (m, m/s), the record (s, Hz), per-wheel errors
    against route 2, bandwidths (Hz) and the largest identified cross-coupling (dB at Hz)."""
    worst = max(r3.coupling.items(), key=lambda kv: kv[1]["max_db"])
    return {
        "method": "4 independent road-like Gaussian drives (displacement PSD flat to 1 Hz, 1/f^2 above, "
                  "0.05-60 Hz) on the nonlinear rig (leaf friction on); MIMO H1 = S_yu S_uu^-1 with "
                  "multiple coherence; stable rational fit (Sanathanan-Koerner) per wheel, weight "
                  "sqrt(coh / (1 - coh)) / |H| (relative error, trusted points first)",
        "record_s": ident_s,
        "drive_rms_m": ident.drive_rms_m,
        "drive_velocity_rms_m_s": ident.drive_velocity_rms_m_s,
        "pan_rms_m": float(np.mean(ident.record.pan_m.std(axis=0))),
        "rate_hz": r3.estimate.fs_hz,
        "nperseg": dict(r3.estimate.nperseg),
        "fit_orders": list(FIT_ORDERS),
        "seed": IDENT_SEED,
        "events": dict(ident.record.events),
        "corners": dict(r3.corners),
        "bandwidth_hz": {c: r3.corners[c]["bandwidth_hz"] for c in CORNERS},
        "cross_coupling_max": {"path": worst[0], **worst[1]},
    }


def steps_section(records: dict, lin: PlantLinearization, eq4: list, fits: list) -> tuple[dict, dict]:
    """Figure 7: the nonlinear rig's steps (``records[name]``, RigRecord) against each linear
    model: largest error (mm, % of the step), when (s) and where; and the curves (m)."""
    section, curves = {}, {}
    for key, size in STEP_SIZES.items():
        rec = records[key]
        nl = rec.pan_m
        linear = linear_steps(lin, eq4, fits, size, rec.t_s)
        entry = {"step_m": size, "step_at_s": STEP_AT_S, "events": dict(rec.events),
                 "nonlinear_overshoot_pct": float(100 * (np.max(nl) - size) / size),
                 "nonlinear_final_m": {c: float(nl[-1, i]) for i, c in enumerate(CORNERS)}}
        for name, y in linear.items():
            err = np.abs(y - nl)
            k, i = np.unravel_index(int(np.argmax(err)), err.shape)
            entry[name] = {"max_error_mm": float(1e3 * err[k, i]), "max_error_pct": float(100 * err[k, i] / size),
                           "at_s": float(rec.t_s[k]), "corner": CORNERS[i]}
        section[key] = entry
        curves[key] = {"t_s": rec.t_s, "nonlinear": nl, **linear}
    return section, curves


def friction_off_section(r3: Route3, records: dict, lin: PlantLinearization) -> dict:
    """The diagnostic without leaf-spring friction: route 3 (dB, deg) and the steps (mm, %)
    against route 2, from the friction-free identification ``r3`` and step ``records``."""
    out = {
        "what": "the nonlinear rig again with the leaf springs' dry friction (frictionloss) set to 0, "
                "as in route 2's linearization: separates friction from the hydraulic nonlinearity",
        "route3_frf_max_error_db": nanmax(r3.corners[c]["frf_max_error_db"] for c in CORNERS),
        "route3_frf_max_error_deg": nanmax(r3.corners[c]["frf_max_error_deg"] for c in CORNERS),
        "route3_corners": {c: {k: r3.corners[c][k] for k in (
            "frf_max_error_db", "frf_max_error_db_at_hz", "frf_max_error_deg", "frf_max_error_deg_at_hz",
            "coherence_min_to_30hz", "bandwidth_hz")} for c in CORNERS},
    }
    for key, size in STEP_SIZES.items():
        nl = records[key].pan_m
        err = float(np.max(np.abs(linear_steps(lin, [], [], size, records[key].t_s)["route2"] - nl)))
        out[f"step_max_error_{key}_mm"] = 1e3 * err
        out[f"step_max_error_{key}_pct"] = 100 * err / size
    return out


def table1_section(runs: dict) -> dict:
    """Table 1: mean DLC (1) of the road, rig and linearized-model runs (``runs[name]``,
    ScenarioRun), their departures from the rig (%), the paper's numbers, per-wheel DLC."""
    dlc = {row: runs[name].dlc_mean for row, name in TABLE1_ROWS}
    rig = dlc["rig_test"]
    return {
        **dlc,
        "linearized_vs_rig_pct": 100.0 * (dlc["linearized_model"] - rig) / rig,
        "linearized_eq4_vs_rig_pct": 100.0 * (dlc["linearized_model_eq4"] - rig) / rig,
        "linearized_route2_mimo_vs_rig_pct": 100.0 * (dlc["linearized_model_route2_mimo"] - rig) / rig,
        "paper": dict(PAPER_TABLE1),
        "paper_linearized_vs_rig_pct": 100.0 * (PAPER_TABLE1["linearized_model"] - PAPER_TABLE1["rig_test"])
                                       / PAPER_TABLE1["rig_test"],
        "notes": ("rig_test is the nonlinear multibody rig, so it stands for both the paper's DYNTRAC test and "
                  "its nonlinear model; linearized_model: the pans follow route 2's own-path T_a of each wheel "
                  "applied to the profile (ZOH, exact discretization); _eq4: eq. 4 per wheel; _route2_mimo: "
                  "the whole linear plant with all four profiles (cross-coupling included). DLC = mean over "
                  "the four wheels of std/mean tire force."),
        "per_wheel": {row: dict(runs[name].dlc) for row, name in TABLE1_ROWS},
        "rig_events": dict(runs["rig"].events),
    }
