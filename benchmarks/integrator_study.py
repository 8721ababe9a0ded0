"""Integrator and time step of the rig chosen by measurement: Euler, RK4 and implicitfast.

Every configuration (integrator, time step) is compared with explicit Euler at 2.5e-5 s (the
reference) on three goals (rig DLC within 0.1 %, identified FRF within 0.1 dB and 1 degree, 24 of
24 generalization cases stable), and costed:

1. rig DLC: rig-mode runs of the paper's three cases (``--dlc-s``, default 20 s each after the
   2 s lead-in), the DLC of each wheel's tire force (:func:`rigsim.correction.metrics.dlc.dlc`), its relative
   error against the reference's (%): goal within 0.1 %. The road drive is made at each step
   and is the same signal at the common instants (checked).
2. identified FRF: the identification of ``rigsim identify`` on the first paper case
   (independent random drives, 30 s analysed): the per-corner diagonal H1 estimate against the
   reference's at every frequency of its grid up to 30 Hz (3750-sample Welch segments: 0.27 Hz), max |dB| and max |deg|:
   goal 0.1 dB / 1 degree. The identification drive is drawn per time step
   (:func:`rigsim.scenarios.core.drive.identification_drive` draws its random phases on the step's
   FFT grid), so two steps see different random drives; the goal's comparison uses one drive,
   made at the reference step and decimated to each step ("same drive"). The estimates of
   :func:`rigsim.scenarios.studies.identify.compute.identify_rig` itself ("own drive") and of its fit
   are printed beside it: they contain the drive realisation, not only the integrator.
3. stability: rig-mode runs of the 24 cases of the generalization suite
   (:func:`rigsim.scenarios.studies.suites.generalization_cases`; ``--gen-s``, default 5 s each) per
   candidate: a SimulationError or a non-finite output is a failure.
4. cost: one rig run of the first paper case (``--dlc-s``) in this process after a warm-up,
   median of ``--repeats``: the wall time of ``Rig.run`` (stepping and recording), and the
   bare stepping rate (``mujoco.rollout`` in 0.5 s chunks, callbacks installed, no recording);
   both as ratios against the baseline, explicit Euler at 1e-4 s.

The integrator is set on the built model (``rig.model.opt.integrator``), the step through the
scenario's ``vehicle.timestep_s``. MuJoCo holds ``ctrl`` over a step, so a drive sampled at the
steps lags the continuous drive by h/2 (0.54 degrees at 30 Hz per 1e-4 s of step); the "mid"
configurations hold the drive's value at mid-step, t_k + h/2, instead (the road drive made at
h/2 and its odd samples taken). RK4 1e-4 s mid is a
second, higher-order reference (DLC and FRF against it printed beside). The script also checks how each integrator
advances the activations (one step from an off-equilibrium state against ``act + h act_dot``)
and what ``actearly`` changes. The table, the failures, the activations and the cheapest
configuration passing all three goals (by the wall time of the rig run) go to
``docs/results/integrator_study.md`` (``--results``: its folder), ending in the line that says how
and where it was measured (:mod:`rigsim.scenarios.studies.results_page`), and prints that file and one
JSON line. About 7 min of CPU with the defaults (3 min with ``--dlc-s 1 --gen-s 0.5 --repeats 1``:
the identification runs, 30 s each, are the fixed part); ``--workers`` spreads it over cores.

Usage::

    python benchmarks/integrator_study.py [--workers 2] [--dlc-s 20] [--gen-s 5] [--repeats 3]
                                          [--results docs/results]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import pathlib
import sys
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from mujoco import rollout  # noqa: E402

from rigsim.correction.identification.identify import h1_estimate  # noqa: E402
from rigsim.correction.metrics.dlc import dlc  # noqa: E402
from rigsim.hydraulics.bridge import hydraulic_callbacks  # noqa: E402
from rigsim.mjcf.names import CORNERS  # noqa: E402
from rigsim.scenarios.core.config import load_scenario, paper_scenarios, parse_scenario  # noqa: E402
from rigsim.scenarios.core.drive import IDENT_MIN_S, IDENT_SEED, IDENT_SKIP_S, Drive  # noqa: E402
from rigsim.scenarios.core.pool import run_jobs  # noqa: E402
from rigsim.scenarios.core.road_drive import road_drive  # noqa: E402
from rigsim.scenarios.core.rig import Rig  # noqa: E402
from rigsim.scenarios.core.watch import SimulationError  # noqa: E402
from rigsim.scenarios.studies.identify.compute import SEGMENT_S, identify_rig, matched_drive  # noqa: E402
from rigsim.scenarios.studies.results_page import script_command, write_results_page  # noqa: E402
from rigsim.scenarios.studies.suites import generalization_cases  # noqa: E402

INTEGRATORS = {"Euler": mujoco.mjtIntegrator.mjINT_EULER, "RK4": mujoco.mjtIntegrator.mjINT_RK4,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}
#: (integrator, time step in s, mid-step drive); the first is the reference. The 1 kHz output must
#: divide the step rate. "mid": each step holds the drive's value at mid-step, t_k + h/2, instead of
#: its value at t_k (MuJoCo holds ctrl over a step: a drive sampled at t_k lags by h/2).
CONFIGS = (("Euler", 2.5e-5, False), ("Euler", 5e-5, False), ("Euler", 1e-4, False), ("Euler", 2e-4, False),
           ("RK4", 1e-4, True), ("RK4", 2e-4, False), ("RK4", 5e-4, False), ("RK4", 1e-3, False),
           ("RK4", 2e-4, True), ("RK4", 5e-4, True), ("RK4", 1e-3, True),
           ("implicitfast", 1e-4, False), ("implicitfast", 2e-4, False), ("implicitfast", 5e-4, False))
REFERENCE, BASELINE, SECOND_REFERENCE = 0, 2, 4  # BASELINE: the costs' denominator
NO_STABILITY = (REFERENCE, SECOND_REFERENCE)  # references, not candidates: no generalization runs
DLC_GOAL_PCT, FRF_GOAL_DB, FRF_GOAL_DEG, FRF_MAX_HZ = 0.1, 0.1, 1.0, 30.0
GEN_CASES, GEN_BATCH = 24, 6
#: Where the results file goes by default: docs/results of this repository.
RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"


def label(i: int) -> str:
    name, dt, mid = CONFIGS[i]
    return f"{name} {dt:g} s" + (" mid" if mid else "")


def scenario_at(scenario, dt_s: float, **changes):
    """The scenario with ``vehicle.timestep_s = dt_s`` (s) and other top-level ``changes``."""
    return dataclasses.replace(scenario, vehicle=dataclasses.replace(scenario.vehicle, timestep_s=dt_s), **changes)


def make_rig(scenario, i: int) -> Rig:
    """The hydraulic rig of ``scenario`` at configuration ``i``: the step in the scenario, the
    integrator set on the compiled model (the stability check is left to the caller)."""
    name, dt, _ = CONFIGS[i]
    rig = Rig(scenario_at(scenario, dt), hydraulic=True, check_stability=False)
    rig.model.opt.integrator = INTEGRATORS[name]
    return rig


def drive_for(rig: Rig, i: int) -> Drive:
    """The scenario's road drive for configuration ``i``: sampled at the steps, or (mid-step) each
    step holding the profile's value at t_k + h/2 (the drive made at h/2, odd samples)."""
    if not CONFIGS[i][2]:
        d = rig.road_drive()
        return Drive(d.t_s, d.z_m, d.v_mps, held_m=d.z_m)  # each step holds its own sample
    half = road_drive(rig.scenario, dt_s=rig.dt_s / 2, wheelbase_m=rig.wheelbase_m, half_stroke_m=rig.half_stroke_m)
    mid = np.concatenate([half.z_m[1::2], half.z_m[-1:]])
    return Drive(half.t_s[0::2].copy(), mid, np.zeros_like(mid), held_m=mid)  # the hydraulic rig reads held_m only


def linear_check(rig: Rig) -> str:
    """"ok", or why :meth:`Rig.check_stable` refuses (or cannot check) under the model's integrator."""
    try:
        rig.check_stable()
        return "ok"
    except Exception as exc:  # ScenarioError (unstable) or MuJoCo's refusal (RK4)
        return f"{type(exc).__name__}: {exc}"


def paper_case(k: int, duration_s: float):
    return dataclasses.replace(load_scenario(paper_scenarios()[k]), duration_s=float(duration_s))


# ------------------------------------------------------------------------ workers
def dlc_job(i: int, case: int, duration_s: float) -> dict:
    """Worker: the DLC (1) of each wheel's tire force in a rig run of paper case ``case``."""
    sc = paper_case(case, duration_s)
    try:
        rig = make_rig(sc, i)
        rec = rig.run(drive_for(rig, i), rate_hz=sc.output_rate_hz)
        return {"dlc": dlc(rec.tire_force_N).tolist(), "z_sum": float(np.sum(rec.x_ref_m))}
    except Exception as exc:  # a failed configuration is a result, not the end of the study
        return {"error": f"{type(exc).__name__}: {exc}"}


def _diag_h1(x_ref_m, rec, rate_hz: float):
    k0 = int(round(IDENT_SKIP_S * rate_hz))
    u, y = x_ref_m[k0:], rec.pan_m[k0:]
    nperseg = int(min(round(SEGMENT_S * rate_hz), u.shape[0] // 8))
    f, h, coh = h1_estimate(u, y, rate_hz, nperseg)
    keep = (f > 0) & (f <= FRF_MAX_HZ)
    return f[keep], np.stack([h[keep, j, j] for j in range(len(CORNERS))], axis=1), coh[keep]


def frf_job(i: int) -> dict:
    """Worker: the diagonal H1 (m/m) to 30 Hz of paper case 0 at configuration ``i``, with the
    reference step's identification drive decimated ("same") and with identify_rig's ("own")."""
    sc = paper_case(0, IDENT_MIN_S)
    dt_ref, dt, mid = CONFIGS[REFERENCE][1], CONFIGS[i][1], CONFIGS[i][2]
    test = Rig(scenario_at(sc, dt_ref), hydraulic=True, check_stability=False).road_drive()
    drive, _ = matched_drive(test, IDENT_MIN_S + IDENT_SKIP_S, seed=IDENT_SEED)
    k = int(round(dt / dt_ref))
    held = drive.z_m[np.minimum(np.arange(0, drive.t_s.size, k) + (k // 2 if mid else 0), drive.t_s.size - 1)]
    u = drive.z_m[::int(round(1.0 / (sc.output_rate_hz * dt_ref)))]  # the drive at the output instants
    drive = Drive(drive.t_s[::k].copy(), held, np.zeros_like(held), held_m=held)
    out = {}
    try:
        rig = make_rig(sc, i)
        f, h, coh = _diag_h1(u, rig.run(drive, rate_hz=sc.output_rate_hz), sc.output_rate_hz)
        out["same"] = {"f": f, "h": h, "coh": coh}
        if mid:  # identify_rig makes its own drive at the steps: no mid-step variant
            return out
        ident = identify_rig(scenario_at(sc, dt), rig=rig)
        fo = ident.fits[CORNERS[0]].f_hz
        keep = fo <= FRF_MAX_HZ
        out["own"] = {"f": fo[keep], "h": np.stack([ident.fits[c].h[keep] for c in CORNERS], axis=1),
                      "fit": np.stack([ident.fits[c].frequency_response(fo[keep]) for c in CORNERS], axis=1)}
    except Exception as exc:  # a failed configuration is a result, not the end of the study
        out["error"] = f"{type(exc).__name__}: {exc}"
    return out


def gen_job(i: int, docs: list, duration_s: float) -> list:
    """Worker: per generalization case, whether a rig run at configuration ``i`` stays finite."""
    out = []
    for doc in docs:
        sc = parse_scenario({**doc, "duration_s": duration_s})
        row = {"case": sc.name, "ok": False, "linear": "n/a"}
        try:
            rig = make_rig(sc, i)
            row["linear"] = linear_check(rig)
            rec = rig.run(drive_for(rig, i), rate_hz=sc.output_rate_hz)
            finite = all(np.all(np.isfinite(a)) for a in (rec.tire_force_N, rec.pan_m, *rec.hydraulic.values()))
            row["ok"] = bool(finite)
            row["error"] = None if finite else "non-finite output"
        except Exception as exc:  # SimulationError, or MuJoCo's own error
            row["error"] = f"{type(exc).__name__}: {exc}"
        out.append(row)
    return out


# ------------------------------------------------------------------------ in this process
def activation_treatment() -> dict:
    """How one step of each integrator advances ``act``: max |act' - (act + h act_dot)| relative to
    max |h act_dot| (0: explicit Euler), and the largest change of (qvel, act) after one step
    when ``actearly`` is set on the hydraulic actuators (0: no effect)."""
    sc = paper_case(0, 1.0)
    out = {}
    for name in INTEGRATORS:
        rig = make_rig(sc, [c[:2] for c in CONFIGS].index((name, 1e-4)))
        model, h = rig.model, rig.dt_s
        base = rig.rest_state()
        base.ctrl[rig.actuators] = 2e-3  # a 2 mm step of x_ref: every state moves
        res = {}
        for early in (0, 1):
            model.actuator_actearly[rig.actuators] = early
            d = mujoco.MjData(model)
            kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
            st = np.empty(mujoco.mj_stateSize(model, kind))
            mujoco.mj_getState(model, base, st, kind)
            mujoco.mj_setState(model, d, st, kind)
            d.ctrl[:] = base.ctrl
            with hydraulic_callbacks(model):
                mujoco.mj_forward(model, d)
                act0, dot0 = d.act.copy(), d.act_dot.copy()
                mujoco.mj_step(model, d)
            res[early] = (np.concatenate([d.qvel, d.act]), d.act - (act0 + h * dot0), h * dot0)
        model.actuator_actearly[rig.actuators] = 0
        out[name] = {"act_vs_euler": float(np.max(np.abs(res[0][1])) / np.max(np.abs(res[0][2]))),
                     "actearly_change": float(np.max(np.abs(res[1][0] - res[0][0])))}
    return out


def physics_seconds(rig: Rig, drive: Drive) -> float:
    """Wall time (s) of stepping ``drive`` with ``mujoco.rollout`` in 0.5 s chunks, no recording."""
    model = rig.model
    data = rig.rest_state()
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, state, kind)
    chunk = int(round(0.5 / rig.dt_s))
    ctrl = np.zeros((drive.t_s.size, model.nu))
    ctrl[:, rig.actuators] = drive.z_m
    with hydraulic_callbacks(model):
        t0 = time.perf_counter()
        for k in range(0, drive.t_s.size, chunk):
            out_state, _ = rollout.rollout(model, data, state, ctrl[k:k + chunk])
            state = out_state[0, -1].copy()
        wall = time.perf_counter() - t0
    if not np.all(np.isfinite(state)):
        raise SimulationError("the bare stepping diverged")
    return wall


def cost(duration_s: float, repeats: int) -> dict:
    """Per configuration: median wall time (s) of ``Rig.run`` of paper case 0 and of the bare
    stepping, and the steps (1), rounds interleaved over the configurations after a warm-up."""
    sc = paper_case(0, duration_s)
    rigs = [make_rig(sc, i) for i in range(len(CONFIGS))]
    drives = [drive_for(r, i) for i, r in enumerate(rigs)]
    for r, d in zip(rigs, drives):  # warm-up: callbacks compiled/loaded, caches, the first 0.5 s
        n = int(np.searchsorted(d.t_s, 0.5))
        r.run(Drive(d.t_s[:n], d.z_m[:n], d.v_mps[:n]), rate_hz=sc.output_rate_hz)
    runs, bare = [[] for _ in rigs], [[] for _ in rigs]
    for _ in range(repeats):
        for i, (r, d) in enumerate(zip(rigs, drives)):
            try:
                t0 = time.perf_counter()
                r.run(d, rate_hz=sc.output_rate_hz)
                runs[i].append(time.perf_counter() - t0)
                bare[i].append(physics_seconds(r, d))
            except SimulationError:
                runs[i].append(float("nan"))
                bare[i].append(float("nan"))
    return {i: {"run_s": float(np.median(runs[i])), "bare_s": float(np.median(bare[i])),
                "steps": int(drives[i].t_s.size)} for i in range(len(CONFIGS))}


# ------------------------------------------------------------------------ comparison
def frf_difference(a: dict, b: dict, key: str = "h") -> tuple[float, float]:
    """Max |dB| and max |deg| between two diagonal responses on the same grid (all corners)."""
    if not np.allclose(a["f"], b["f"]):
        raise ValueError("the two H1 estimates are not on the same frequency grid")
    r = a[key] / b[key]
    return float(np.max(np.abs(20 * np.log10(np.abs(r))))), float(np.max(np.abs(np.degrees(np.angle(r)))))


HEADER = ("config", "run s", "cost ratio", "bare steps/s", "bare ratio", "worst rig DLC err %", "FRF dB / deg",
          "vs RK4 1e-4 mid: DLC % ; dB / deg", "own drive dB / deg", "its fit dB / deg", "stable", "passes")


def table_rows(rows: list[dict]) -> list[list[str]]:
    """The results table's cells, one row per configuration (:data:`HEADER`)."""
    out = []
    for r in rows:
        if r["errors"]:
            acc = ["failed: " + r["errors"][0][:60], "", "", "", ""]
        else:
            own = ([f"{r['own_frf_db']:.3f} / {r['own_frf_deg']:.2f}", f"{r['fit_db']:.3f} / {r['fit_deg']:.2f}"]
                   if "own_frf_db" in r else ["n/a", "n/a"])
            acc = [f"{r['worst_dlc_pct']:.3f}", f"{r['frf_db']:.3f} / {r['frf_deg']:.2f}",
                   f"{r['worst_dlc_pct_vs_rk4']:.3f} ; {r['frf_db_vs_rk4']:.3f} / {r['frf_deg_vs_rk4']:.2f}", *own]
        stable = "reference" if r["stable"] is None else f"{r['stable']}/{GEN_CASES}"
        out.append([r["config"], f"{r['run_s']:.2f}", f"{r['cost_ratio']:.2f}", f"{r['bare_steps_per_s']:,.0f}",
                    f"{r['bare_cost_ratio']:.2f}", *acc, stable, "yes" if r["passes"] else "no"])
    return out


def notes(rows: list[dict], acts: dict, best: dict | None, best_plain: dict | None) -> str:
    """The text under the table: the goals, the failures and refusals of the linear check, the
    activations' treatment, the cheapest passing configurations."""
    parts = ["Goals: rig DLC within 0.1 % of the reference on every wheel of the three cases; H1 (same drive) "
             "within 0.1 dB and 1 degree at every point (0.27 Hz apart) up to 30 Hz on every corner; 24/24 cases "
             "stable. Below the table: per configuration, the first generalization cases that failed and what the "
             "rig's linear stability check (Rig.check_stable at that integrator and step) said where it refused."]
    failures = [f"- {r['config']}: {what}" for r in rows
                for what in r["unstable_cases"][:3] + r["linear_check_failures"][:2]]
    if failures:
        parts.append("\n".join(failures))
    parts.append("Activations, one step from a 2 mm x_ref step at 1e-4 s: max|act' - (act + h act_dot)| / "
                 "max|h act_dot| (0 = explicit Euler on act), and the largest change of (qvel, act) with actearly "
                 "set:\n\n" + "\n".join(f"- {name}: {a['act_vs_euler']:.3g}; actearly changes {a['actearly_change']:.3g}"
                                        for name, a in acts.items()))
    for what, b in (("Cheapest passing", best), ("Cheapest passing with the drive sampled at the steps", best_plain)):
        parts.append(f"{what}: {b['config'] if b else 'none'}"
                     + (f" (cost ratio {b['cost_ratio']:.2f} of {label(BASELINE)})." if b else "."))
    return "\n\n".join(parts)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--dlc-s", type=float, default=20.0, help="duration of each paper-case run, s")
    ap.add_argument("--gen-s", type=float, default=5.0, help="duration of each generalization run, s")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--results", type=pathlib.Path, default=RESULTS,
                    help="folder of the results file integrator_study.md (default docs/results)")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    n = len(CONFIGS)
    docs = generalization_cases(GEN_CASES, args.gen_s)
    jobs, where = [], []
    for i in range(n):  # the expensive jobs first
        jobs.append((frf_job, (i,)))
        where.append(("frf", i, None))
    for i in range(n):
        for c in range(3):
            jobs.append((dlc_job, (i, c, args.dlc_s)))
            where.append(("dlc", i, c))
    for i in range(n):
        if i in NO_STABILITY:
            continue
        for b in range(0, GEN_CASES, GEN_BATCH):
            jobs.append((gen_job, (i, docs[b:b + GEN_BATCH], args.gen_s)))
            where.append(("gen", i, b))
    results = run_jobs(jobs, workers=args.workers,
                       on_done=lambda k, _: print(f"  done {where[k][0]} {label(where[k][1])}", file=sys.stderr))
    dlcs = {(i, c): r for (kind, i, c), r in zip(where, results) if kind == "dlc"}
    frfs = {i: r for (kind, i, _), r in zip(where, results) if kind == "frf"}
    gens = {i: [] for i in range(n) if i not in NO_STABILITY}
    for (kind, i, _), r in zip(where, results):
        if kind == "gen":
            gens[i].extend(r)
    t_pool = time.perf_counter() - t_start
    print(f"  pool phase {t_pool:.0f} s; timing in this process ...", file=sys.stderr)
    costs = cost(args.dlc_s, args.repeats)
    acts = activation_treatment()

    rows = []
    for i in range(n):
        row = {"config": label(i), "integrator": CONFIGS[i][0], "step_s": CONFIGS[i][1], "mid_step_drive": CONFIGS[i][2]}
        errs = [dlcs[(i, c)].get("error") for c in range(3)] + [frfs[i].get("error")]
        row["errors"] = [e for e in errs if e]
        same_drive = CONFIGS[i][2] or all(dlcs[(i, c)].get("z_sum") == dlcs[(REFERENCE, c)].get("z_sum") for c in range(3))
        if not row["errors"]:
            for key, ref in (("", REFERENCE), ("_vs_rk4", SECOND_REFERENCE)):
                e = [100 * (np.array(dlcs[(i, c)]["dlc"]) / dlcs[(ref, c)]["dlc"] - 1) for c in range(3)]
                row["dlc_error_pct" + key] = [x.tolist() for x in e]
                row["worst_dlc_pct" + key] = float(np.max(np.abs(e)))
                row["frf_db" + key], row["frf_deg" + key] = frf_difference(frfs[i]["same"], frfs[ref]["same"])
            if "own" in frfs[i]:
                row["own_frf_db"], row["own_frf_deg"] = frf_difference(frfs[i]["own"], frfs[REFERENCE]["own"])
                row["fit_db"], row["fit_deg"] = frf_difference(frfs[i]["own"], frfs[REFERENCE]["own"], "fit")
        row["drive_equal_at_common_instants"] = bool(same_drive)
        g = gens.get(i)
        row["stable"] = None if g is None else int(sum(r["ok"] for r in g))
        row["unstable_cases"] = [] if g is None else [f"{r['case']}: {r['error']}" for r in g if not r["ok"]]
        row["linear_check_failures"] = [] if g is None else sorted({r["linear"][:90] for r in g if r["linear"] != "ok"})
        c = costs[i]
        row.update(run_s=c["run_s"], bare_s=c["bare_s"], steps=c["steps"], run_steps_per_s=c["steps"] / c["run_s"],
                   bare_steps_per_s=c["steps"] / c["bare_s"], cost_ratio=c["run_s"] / costs[BASELINE]["run_s"],
                   bare_cost_ratio=c["bare_s"] / costs[BASELINE]["bare_s"])
        row["passes"] = bool(not row["errors"] and row["worst_dlc_pct"] <= DLC_GOAL_PCT and row["frf_db"] <= FRF_GOAL_DB
                             and row["frf_deg"] <= FRF_GOAL_DEG and row["stable"] == GEN_CASES)
        rows.append(row)

    candidates = [r for i, r in enumerate(rows) if r["passes"] and i not in NO_STABILITY]
    best = min(candidates, key=lambda r: r["cost_ratio"]) if candidates else None
    plain = [r for r in candidates if not r["mid_step_drive"]]
    best_plain = min(plain, key=lambda r: r["cost_ratio"]) if plain else None
    title = (f"Integrator study: against {label(REFERENCE)}; paper cases {args.dlc_s:g} s each (+2 s lead-in), "
             f"FRF of paper case 0 ({IDENT_MIN_S:g} s analysed) to {FRF_MAX_HZ:g} Hz, {GEN_CASES} generalization "
             f"cases of {args.gen_s:g} s; cost: median of {args.repeats}, ratio to {label(BASELINE)}")
    page = write_results_page(args.results, "integrator_study", title, HEADER, table_rows(rows),
                              script_command(__file__, argv), note=notes(rows, acts, best, best_plain))
    print(page.read_text(encoding="utf-8"))
    summary = {"reference": label(REFERENCE), "baseline": label(BASELINE), "cheapest_passing": best["config"] if best else None,
               "cheapest_passing_drive_at_steps": best_plain["config"] if best_plain else None,
               "dlc_s": args.dlc_s, "gen_s": args.gen_s, "activations": acts,
               "wall_s": round(time.perf_counter() - t_start, 1),
               "configs": [{k: v for k, v in r.items()} for r in rows]}
    print(json.dumps(summary, default=float))
    return summary


if __name__ == "__main__":
    main()
