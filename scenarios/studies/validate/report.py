"""``report.md`` of ``rigsim validate``, the lines the command prints, and writing the folder.

:func:`write_report` renders the figures (:mod:`rigsim.scenarios.studies.validate.figures`) and
``report.md`` in memory from a :class:`~rigsim.scenarios.studies.validate.result.ValidateResult`,
then writes every file atomically, ``validate.json`` (through
:func:`rigsim.scenarios.core.files.write_json`) last.
"""

from __future__ import annotations

import math
import pathlib

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.files import atomic_write_bytes, write_json
from rigsim.scenarios.studies.validate.figures import render_figures
from rigsim.scenarios.studies.validate.result import ValidateResult
from rigsim.scenarios.studies.validate.settings import GOAL_FRF_DB, GOAL_FRF_DEG, GOAL_TABLE1_PCT

__all__ = ["events_text", "summary_lines", "write_report"]


def _fmt(x, nd=4) -> str:
    if isinstance(x, float) and math.isnan(x):
        return "n/a"
    return f"{x:.{nd}f}"


def _report_md(js: dict) -> str:
    c4 = list(CORNERS)
    r1, r2, r3, t1 = js["route1"], js["route2"], js["route3"], js["table1"]
    bw = js["bandwidth_hz"]
    lines = [
        "# Validation of the linearized actuator model (paper eq. 4) against the multibody plant",
        "",
        f"Scenario `{js['scenario']}` (truck 3640 kg payload on the four-post rig), rig test "
        f"and road test {js['integrator']} at {js['timestep_s']:g} s, linearization explicit Euler at "
        f"{js['linear_timestep_s']:g} s. Table 1 runs {js['duration_s']:g} s, identification record "
        f"{js['ident_duration_s']:g} s. Every number is in [`validate.json`](validate.json); wall time "
        f"{js['wall_time_s']:.1f} s.",
        "",
        "## Three routes to T_a(s) = X_a / X_p",
        "",
        "1. **Analytic** — eq. 4 with Merritt's Kq, Kc at each station's static load and its tire kt "
        "(front 0.9 MN/m, rear 1.8 MN/m).",
        f"   {r1['flow_direction']}.",
        f"2. **Numerical** — {r2['method']} ({r2['states']} states). The actuator alone (one pan, static "
        "valve, spring to ground) linearized the same way reproduces eq. 4 to 1e-6 relative: "
        "`tests/hydraulics/test_hydraulics_mujoco.py::test_transition_fd_reproduces_eq4`.",
        f"3. **Identified** — {r3['method']}. Drive RMS {1e3 * r3['drive_rms_m']:.1f} mm, "
        f"{r3['drive_velocity_rms_m_s']:.2f} m/s; record {r3['record_s']:g} s at {r3['rate_hz']:g} Hz.",
        "",
        "| wheel | bandwidth route 1 (Hz) | route 2 (Hz) | route 3 fit (Hz) | route 3 H1 (Hz) | route 1 vs 2 max dB / deg | route 3 vs 2 max dB / deg (coh > 0.95) | min coherence to 30 Hz |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for c in c4:
        v1 = r1["variants"]["static_mean"]["corners"][c]
        v3 = r3["corners"][c]
        lines.append(f"| {c} | {_fmt(bw['route1'][c], 2)} | {_fmt(bw['route2'][c], 2)} | {_fmt(bw['route3'][c], 2)} | "
                     f"{_fmt(v3['bandwidth_h1_hz'], 2)} | {v1['frf_max_error_db']:.2f} / {v1['frf_max_error_deg']:.1f} | "
                     f"{v3['frf_max_error_db']:.2f} / {v3['frf_max_error_deg']:.1f} | {v3['coherence_min_to_30hz']:.4f} |")
    goal3 = js["goals"]["route3_within_0p5db_5deg_to_30hz"]
    lines += [
        "",
        f"**Goal: route 3 within {GOAL_FRF_DB} dB / {GOAL_FRF_DEG:g} deg of route 2 up to 30 Hz where coherence > 0.95: "
        f"{'met' if goal3 else 'NOT met'}** (max {js['frf_max_error_db']['route3']:.2f} dB, "
        f"{js['frf_max_error_deg']['route3']:.1f} deg). Route 1 (eq. 4) departs by up to "
        f"{js['frf_max_error_db']['route1']:.2f} dB and {js['frf_max_error_deg']['route1']:.1f} deg.",
        "",
        "Bode overlays (magnitude, phase, differences to route 2): "
        + ", ".join(f"[{c}](bode_{c}.png)" for c in c4)
        + ". Coherence and route 2's cross-coupling: [coherence_coupling.png](coherence_coupling.png).",
        "",
        f"Largest cross-coupling (route 2): {r2['cross_coupling_max']['path']} "
        f"{r2['cross_coupling_max']['max_db']:.1f} dB at {r2['cross_coupling_max']['at_hz']:.2f} Hz; "
        f"identified (route 3): {r3['cross_coupling_max']['path']} {r3['cross_coupling_max']['max_db']:.1f} dB at "
        f"{r3['cross_coupling_max']['at_hz']:.2f} Hz.",
        "",
        "### Poles and zeros",
        "",
        "Eq. 4 (wheel fl): poles " + _roots_md(r1["models"]["fl"]["poles"]) + "; zero "
        + _roots_md(r1["models"]["fl"]["zeros"]) + ". Rear (rl): poles " + _roots_md(r1["models"]["rl"]["poles"]) + ".",
        "",
        "Route 2 (whole plant, continuous equivalents, one per pair): " + _roots_md(r2["poles"]) + ".",
        "",
        "Route 2 zeros of wheel fl's own path (those not cancelling a pole): " + _roots_md(r2["zeros"]["fl"]) + ".",
        "",
        f"Route 3 fit (orders {r3['fit_orders'][0]}/{r3['fit_orders'][1]}), wheel fl: poles "
        + _roots_md(r3["corners"]["fl"]["fit"]["poles"]) + "; zeros " + _roots_md(r3["corners"]["fl"]["fit"]["zeros"])
        + f". The fit stays within {r3['corners']['fl']['fit_max_error_db_vs_h1']:.2f} dB / "
        f"{r3['corners']['fl']['fit_max_error_deg_vs_h1']:.1f} deg of its H1 estimate (coherent points, 0.1-30 Hz).",
        "",
        "### How Kq and Kc are taken (route 1 variants)",
        "",
        "| variant | Kq fl (m^3/s) | bandwidth fl / rl (Hz) | max error vs route 2 (dB / deg) |",
        "| --- | --- | --- | --- |",
    ]
    for name, var in r1["variants"].items():
        lines.append(f"| {name}: {var['description']} | {var['corners']['fl']['kq_m3_s']:.5g} | "
                     f"{var['corners']['fl']['bandwidth_hz']:.2f} / {var['corners']['rl']['bandwidth_hz']:.2f} | "
                     f"{var['frf_max_error_db']:.2f} / {var['frf_max_error_deg']:.1f} |")
    lines += [
        "",
        "## Where eq. 4 departs from the plant, and why",
        "",
        "Each row adds one thing eq. 4 leaves out; the numbers are the largest difference to route 2 "
        "over 0.1-30 Hz for wheel fl (rl in brackets). Plot: [departure_fl.png](departure_fl.png).",
        "",
        "| model | max dB | max deg | at 30 Hz: dB, deg |",
        "| --- | --- | --- | --- |",
    ]
    bud = js["departure_budget"]
    bfl, brl = bud["versus_route2"]["fl"], bud["versus_route2"]["rl"]
    for name, text in bud["stages"].items():
        if name == "route2":
            continue
        a, b = bud["versus_route2"]["fl"][name], bud["versus_route2"]["rl"][name]
        lines.append(f"| {text} | {a['max_error_db']:.2f} ({b['max_error_db']:.2f}) | {a['max_error_deg']:.1f} "
                     f"({b['max_error_deg']:.1f}) | {a['error_db_at_30hz']:+.2f}, {a['error_deg_at_30hz']:+.1f} |")
    lines += [
        "",
        f"* **Valve dynamics.** Eq. 4 assumes a static valve. The plant's servovalve is a 150 Hz, zeta 0.7 "
        f"second-order spool inside the position loop. Adding it to the linearized actuator cuts the phase "
        f"error against the plant from {bfl['two_chamber_static_valve']['max_error_deg']:.1f} to "
        f"{bfl['plus_spool_dynamics']['max_error_deg']:.1f} deg (fl; at 30 Hz from "
        f"{bfl['two_chamber_static_valve']['error_deg_at_30hz']:+.1f} to {bfl['plus_spool_dynamics']['error_deg_at_30hz']:+.1f} deg): "
        "the spool's lag is eq. 4's largest error above ~10 Hz, and it is a phase error mostly.",
        f"* **One load pressure.** Under the static wheel load P1 > P2, so the two chambers' flow paths differ. "
        f"Linearizing both chambers separately changes eq. 4 by at most "
        f"{bud['eq4_vs_two_chamber_static_valve']['fl']['max_db']:.1e} dB here, because Kq and Kc are "
        "taken as the mean of both paths (QL = (Q1 - Q2)/2). Taking Kq of one flow direction instead "
        "(variants table above) moves the bandwidth by up to "
        f"{_variant_spread(r1):.2f} Hz: the linear model's gain depends on where and in which direction it "
        "is linearized, which no single eq. 4 can follow on a road drive.",
        f"* **Tire to rigid ground, load dependence through kt.** In eq. 4 every metre of pan travel "
        "compresses the tire by a metre, so the load changes by kt x_a; the pressure feedback Kdp and the "
        "valve's Kc give way under it and the proportional loop droops, b1/a1 = K / (K + Kc' kt / Ap^2), "
        f"until the integrator (Ti = 1 s) removes it: eq. 4's gain between ~0.2 Hz and its bandwidth sits at "
        f"{r1['mid_band_gain_db']['fl']:+.2f} dB (fl, 0.9 MN/m) and {r1['mid_band_gain_db']['rl']:+.2f} dB "
        "(rl, 1.8 MN/m), and its step response creeps to the target over seconds (steps.png). On the rig the "
        "truck rides up with the pan, the tire is hardly compressed at low frequency, and the plant's gain "
        "stays at ~0 dB up to the body modes. The same kt sets eq. 4's bandwidth: "
        f"{bw['route1']['fl']:.2f} Hz front, {bw['route1']['rl']:.2f} Hz rear (plant: {bw['route2']['fl']:.2f} and "
        f"{bw['route2']['rl']:.2f} Hz).",
        f"* **Vehicle coupling.** Eq. 4's tire stands on rigid ground. On the rig it stands on the axle "
        "(axle hop 9-11 Hz) under the body (bounce, pitch, roll 1-2.6 Hz), and the other three actuators "
        "load each pan through the truck. What remains between the actuator with its spool and route 2 is "
        f"this coupling: up to {bfl['plus_spool_dynamics']['max_error_db']:.2f} dB and "
        f"{bfl['plus_spool_dynamics']['max_error_deg']:.1f} deg for fl ({brl['plus_spool_dynamics']['max_error_db']:.2f} dB, "
        f"{brl['plus_spool_dynamics']['max_error_deg']:.1f} deg for rl), at the body modes and around the axle hop, "
        f"plus cross-coupling up to {r2['cross_coupling_max']['max_db']:.1f} dB.",
        "* **Route 2 vs route 3.** Route 2 is linear with the leaf springs' dry friction off; route 3 is the "
        "nonlinear rig (orifice law, smoothed null, leaf friction on) at road amplitude. Their difference "
        "measures how far the real rig is from its linearization at that amplitude; see the friction-off "
        "diagnostic below.",
        "",
        "## Figure 7 analogue: step responses",
        "",
        "All four pans stepped together at t = 0.05 s from static rest. Largest difference to the nonlinear rig "
        "over 2 s, all wheels ([steps.png](steps.png)):",
        "",
        "| step | route 2 (mm, %) | eq. 4 (mm, %) | route 3 fit (mm, %) | nonlinear overshoot (%) |",
        "| --- | --- | --- | --- | --- |",
    ]
    for key in ("small", "large"):
        e = js["steps"][key]
        cells = [f"{e[m]['max_error_mm']:.4f}, {e[m]['max_error_pct']:.2f}" if m in e else "n/a"
                 for m in ("route2", "route1", "route3")]
        lines.append(f"| {1e3 * e['step_m']:g} mm | " + " | ".join(cells) + f" | {e['nonlinear_overshoot_pct']:.1f} |")
    dg = js["diagnostics_friction_off"]
    lines += [
        "",
        "Hydraulic events (spool saturation, cavitation, over-pressure; samples at each record's rate): "
        f"identification record {events_text(js['route3']['events'])}; 1 mm step "
        f"{events_text(js['steps']['small']['events'])}; 1 cm step {events_text(js['steps']['large']['events'])}; "
        f"Table 1 rig run {events_text(js['table1']['rig_events'])}.",
    ]
    lines += [
        "",
        "## Diagnostic: the same without leaf-spring friction",
        "",
        f"{dg['what'][0].upper()}{dg['what'][1:]}.",
        "",
        f"* Route 3 vs route 2 up to 30 Hz (coherence > 0.95): {dg['route3_frf_max_error_db']:.2f} dB, "
        f"{dg['route3_frf_max_error_deg']:.1f} deg without friction, against {js['frf_max_error_db']['route3']:.2f} dB, "
        f"{js['frf_max_error_deg']['route3']:.1f} deg with it. Largest route 3 errors with friction: "
        + ", ".join(f"{c} {js['route3']['corners'][c]['frf_max_error_db']:.2f} dB at "
                    f"{js['route3']['corners'][c]['frf_max_error_db_at_hz']:.2f} Hz, "
                    f"{js['route3']['corners'][c]['frf_max_error_deg']:.1f} deg at "
                    f"{js['route3']['corners'][c]['frf_max_error_deg_at_hz']:.2f} Hz" for c in c4) + ".",
        f"* Steps, route 2 vs nonlinear rig: 1 mm {dg['step_max_error_small_mm']:.4f} mm "
        f"({dg['step_max_error_small_pct']:.2f} %), 1 cm {dg['step_max_error_large_mm']:.4f} mm "
        f"({dg['step_max_error_large_pct']:.2f} %) without friction, against "
        f"{js['step_max_error_small_pct']:.2f} % and {js['step_max_error_large_pct']:.2f} % with it. "
        "Without friction the small step is nearly linear and what is left of the large one is the valve's "
        "orifice law during the fast rise; with friction the leaf springs stick, so the truck loads the pans "
        "differently from the linearized (friction-free) truck while the body settles.",
    ]
    goal1 = js["goals"]["table1_linearized_within_2pct_of_rig"]
    p = t1["paper"]
    lines += [
        "",
        "## Table 1 analogue (high roughness, 72 km/h, 3640 kg)",
        "",
        "| | road test | rig test (nonlinear multibody) | linearized model (route 2 T_a per wheel) | eq. 4 T_a | route 2 whole linear plant |",
        "| --- | --- | --- | --- | --- | --- |",
        f"| this model | {t1['road_test']:.4f} | {t1['rig_test']:.4f} | {t1['linearized_model']:.4f} "
        f"({t1['linearized_vs_rig_pct']:+.2f} %) | {t1['linearized_model_eq4']:.4f} ({t1['linearized_eq4_vs_rig_pct']:+.2f} %) | "
        f"{t1['linearized_model_route2_mimo']:.4f} ({t1['linearized_route2_mimo_vs_rig_pct']:+.2f} %) |",
        f"| paper | {p['road_test']:.4f} | {p['rig_test']:.4f} (nonlinear model {p['nonlinear_model']:.4f}) | "
        f"{p['linearized_model']:.4f} ({t1['paper_linearized_vs_rig_pct']:+.2f} %) | | |",
        "",
        f"**Goal: linearized-model DLC within {GOAL_TABLE1_PCT:g} % of the rig test's: {'met' if goal1 else 'NOT met'}.** "
        f"Road > rig: {'yes' if js['goals']['table1_road_above_rig'] else 'NO'}. {t1['notes']}",
        "",
    ]
    return "\n".join(lines)


def events_text(events) -> str:
    """A run's hydraulic events ``{event: {corner: {"samples", "first_time_s"}}}`` in words."""
    parts = []
    for name, corners in events.items():
        per = [f"{c} {e['samples']} samples from {e['first_time_s']:.3f} s" for c, e in corners.items()
               if e.get("samples")]
        if per:
            parts.append(f"{name.replace('_', ' ')}: " + ", ".join(per))
    return "; ".join(parts) if parts else "none"


def _variant_spread(r1: dict) -> float:
    bws = [v["corners"][c]["bandwidth_hz"] for v in r1["variants"].values() for c in ("fl", "rl")]
    base = [r1["variants"]["static_mean"]["corners"][c]["bandwidth_hz"] for c in ("fl", "rl")]
    return max(max(abs(x - base[0]) for x in bws[0::2]), max(abs(x - base[1]) for x in bws[1::2]))


def _roots_md(roots: list[dict]) -> str:
    if not roots:
        return "none"
    parts = []
    for r in roots:
        if r["imag_rad_s"] > 0:
            parts.append(f"{r['frequency_hz']:.2f} Hz (zeta {r['damping_ratio']:.2f})")
        else:
            parts.append(f"{r['real_rad_s']:.3g} rad/s")
    return ", ".join(parts)


def summary_lines(result: ValidateResult) -> list[str]:
    """The key numbers of ``validate.json`` as ``key = value`` lines (what the command prints)."""
    js = result.to_dict()
    out = []
    for k in ("step_max_error_small_mm", "step_max_error_small_pct", "step_max_error_large_mm",
              "step_max_error_large_pct", "step_max_error_small_pct_eq4", "step_max_error_large_pct_eq4"):
        out.append(f"{k} = {js[k]:.6g}")
    for route in ("route1", "route3"):
        out.append(f"frf_max_error_db.{route} = {js['frf_max_error_db'][route]:.6g}")
        out.append(f"frf_max_error_deg.{route} = {js['frf_max_error_deg'][route]:.6g}")
    for route in ("route1", "route2", "route3"):
        for c in CORNERS:
            out.append(f"bandwidth_hz.{route}.{c} = {js['bandwidth_hz'][route][c]:.6g}")
    for k in ("road_test", "rig_test", "linearized_model", "linearized_model_eq4",
              "linearized_model_route2_mimo", "linearized_vs_rig_pct"):
        out.append(f"table1.{k} = {js['table1'][k]:.6g}")
    for k, v in js["goals"].items():
        out.append(f"goals.{k} = {v}")
    return out


def write_report(result: ValidateResult, out_dir) -> dict[str, pathlib.Path]:
    """Render the PNGs and ``report.md`` in memory, then write every file atomically
    (``validate.json`` last, so its presence means the folder is complete); returns file name -> path."""
    out = pathlib.Path(out_dir)
    files: dict[str, bytes] = dict(render_figures(result))
    files["report.md"] = _report_md(result.to_dict()).encode("utf-8")
    paths = {}
    for name, data in files.items():
        atomic_write_bytes(out / name, data)
        paths[name] = out / name
    paths["validate.json"] = write_json(out / "validate.json", result)
    return paths
