"""Integrator and time step of the road test, chosen by measurement: Euler, RK4, implicitfast.

The road test (``Rig(scenario, hydraulic=False)``) steps in ``mujoco.rollout``: the pans are mocap
bodies, each step holds each pan at the drive's mid-step value moving at its mean velocity over
the step, and the tire force at t_k is reconstructed with the tire's law
(:func:`rigsim.mjcf.physics.tire_law`) from the tendon's length and rate sensors
(:func:`rigsim.scenarios.core.stepping.run_kinematic`). Every configuration (integrator, step) runs
through that code path: ``Rig(sc, hydraulic=False)`` with the step in ``vehicle.timestep_s``,
the integrator set on the compiled model, ``rig.run(rig.road_source(), rate_hz=1000)``.

"loop" is the road test stepped without ``mujoco.rollout``, the plainest way and the costs'
baseline: the pans on their slide joints (``build_spec(variant)``), the XML's explicit Euler at
1e-4 s, a Python loop setting the pan joints' qpos/qvel to the drive's z_k, v_k before each
``mj_step`` and reading ``actuator_force`` after it (:func:`loop_run`).
"Euler 1e-4 s" goes through rollout and is not that loop: its pans hold the mid-step values.

1. road DLC: the paper's three cases (``--dlc-s``, default 20 s after the 2 s lead-in), the DLC
   of each wheel's force (:func:`rigsim.correction.metrics.dlc.dlc`), its error (%) against Euler at 2.5e-5 s
   (the reference; goal within 0.1 %) and against RK4 at 1e-4 s (a second, higher-order
   reference); the wheel-force NRMSE (:func:`rigsim.correction.metrics.dlc.nrmse`) against each at the common
   output instants. Beside them, against the Euler reference: the raw sensor force (what MuJoCo
   applied over the step: the pan at mid-step, moving at its mean velocity; the rollout's
   sensors and controls captured in the same run), which the reconstruction replaces, and that
   force with the pan moved back to z_k only (the reconstruction also takes the drive's own
   velocity v_k instead of the mean one). A 2e-3 s step cannot give a 1 kHz output and a
   scenario refuses it (it is set on the compiled model): it records at 500 Hz, is compared at
   those instants and is not eligible.
2. stability: road runs of the 24 generalization cases (``--gen-s``, default 5 s) per candidate:
   a SimulationError or a non-finite output is a failure; a case the scenario refuses before any
   step (ScenarioError) is counted apart.
3. cost: one road run of paper case 1 (``--dlc-s``) in this process after a warm-up, median of
   ``--repeats``, rounds interleaved; the wall time of ``Rig.run`` (of the loop for "loop"),
   as a ratio to "loop".

Writes the table, the failures and the cheapest configuration passing all goals to
``docs/results/road_integrator_study.md`` (``--results``: its folder), ending in the line that
says how and where it was measured (:mod:`rigsim.scenarios.studies.results_page`), and prints that file
and one JSON line. A few minutes of CPU; ``--workers`` spreads it over cores.

Usage::

    python benchmarks/road_integrator_study.py [--workers 2] [--dlc-s 20] [--gen-s 5] [--repeats 3]
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
import types

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from rigsim.correction.metrics.dlc import dlc, nrmse  # noqa: E402
from rigsim.mjcf.build import build_spec  # noqa: E402
from rigsim.mjcf.names import CORNERS, pan_joint  # noqa: E402
from rigsim.mjcf.physics import RigIndex, static_equilibrium, tire_law  # noqa: E402
from rigsim.scenarios.core import stepping  # noqa: E402
from rigsim.scenarios.core.config import ScenarioError, load_scenario, paper_scenarios, parse_scenario  # noqa: E402
from rigsim.scenarios.core.pool import run_jobs  # noqa: E402
from rigsim.scenarios.core.rig import RIG_INTEGRATOR_NAME, RIG_TIMESTEP_S, Rig, actuator_params  # noqa: E402
from rigsim.scenarios.core.watch import SimulationError, output_schedule  # noqa: E402
from rigsim.scenarios.studies.results_page import script_command, write_results_page  # noqa: E402
from rigsim.scenarios.studies.suites import generalization_cases  # noqa: E402

INTEGRATORS = {"Euler": mujoco.mjtIntegrator.mjINT_EULER, "RK4": mujoco.mjtIntegrator.mjINT_RK4,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}

#: (integrator, time step in s); "loop": the loop of explicit Euler steps with the pan joints set.
CONFIGS = (("Euler", 2.5e-5), ("RK4", 1e-4), ("loop", 1e-4), ("Euler", 1e-4), ("RK4", 5e-4),
           ("RK4", 1e-3), ("RK4", 2e-3), ("implicitfast", 1e-3))
REFERENCE, SECOND_REFERENCE, LOOP = 0, 1, 2
REFERENCES = (REFERENCE, SECOND_REFERENCE)  # not candidates: no generalization runs
ADOPTED = CONFIGS.index((RIG_INTEGRATOR_NAME, RIG_TIMESTEP_S))
DLC_GOAL_PCT, OUTPUT_HZ = 0.1, 1000.0
GEN_CASES, GEN_BATCH = 24, 6
MAX_STEP_S = 1e-3  # the largest vehicle.timestep_s a scenario accepts (rigsim.mjcf.variant.BOUNDS)
#: Where the results file goes by default: docs/results of this repository.
RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"


def scenario_at(scenario, dt_s: float, **changes):
    """The scenario with ``vehicle.timestep_s = dt_s`` (s) and other top-level ``changes``."""
    return dataclasses.replace(scenario, vehicle=dataclasses.replace(scenario.vehicle, timestep_s=dt_s), **changes)


def paper_case(k: int, duration_s: float):
    """The paper's case ``k`` (Table 2's order) at ``duration_s`` (s)."""
    return dataclasses.replace(load_scenario(paper_scenarios()[k]), duration_s=float(duration_s))


def label(i: int) -> str:
    name, dt = CONFIGS[i]
    return f"{name} {dt:g} s" + (" (Euler, pan joints)" if i == LOOP else "")


def rate_hz(i: int) -> float:
    """The output rate (Hz): 1 kHz, or the step rate of a coarser step."""
    return min(OUTPUT_HZ, 1.0 / CONFIGS[i][1])


# ------------------------------------------------------------------------ the two ways to step
def make_rig(scenario, i: int) -> Rig:
    """The road-test rig of ``scenario`` at rollout configuration ``i``."""
    name, dt = CONFIGS[i]
    rig = Rig(scenario_at(scenario, min(dt, MAX_STEP_S)), hydraulic=False)
    rig.model.opt.integrator = INTEGRATORS[name]
    rig.model.opt.timestep = dt  # above MAX_STEP_S: set on the model, the scenario refuses it
    return rig


def loop_setup(scenario):
    """(model, index, drive) of the road test stepped in a loop: pans on slide joints limited to the
    actuator's stroke, the XML's explicit Euler at 1e-4 s, the road on that step."""
    params = actuator_params(scenario)
    variant = scenario.vehicle
    if variant.pan_mass_kg is None:
        variant = dataclasses.replace(variant, pan_mass_kg=params.pan_mass_kg)
    spec = build_spec(variant)
    for c in CORNERS:
        spec.joint(pan_joint(c)).range = [-params.half_stroke_m, params.half_stroke_m]
    model = spec.compile()
    if model.opt.integrator != INTEGRATORS["Euler"] or model.opt.timestep != CONFIGS[LOOP][1]:
        raise ValueError("the model file does not give explicit Euler at 1e-4 s: 'loop' would not be the Euler loop")
    drive = Rig(scenario_at(scenario, model.opt.timestep), hydraulic=False).road_source()
    return model, RigIndex.of(model), drive


def loop_run(model, idx, drive, rate: float) -> dict:
    """The road test stepped in a Python loop: the output instants (s), drive (m) and tire forces (N)."""
    data = mujoco.MjData(model)
    static_equilibrium(model, data, pan_z_m=drive.chunk(0, 1)[0][0])
    k0, decim, n_out = output_schedule(drive, model.opt.timestep, rate)
    t, x, force = np.empty(n_out), np.empty((n_out, 4)), np.empty((n_out, 4))
    qpos, qvel, act_force = data.qpos, data.qvel, data.actuator_force
    for k in range(0, drive.n_steps, 1000):
        z, v = drive.chunk(k, min(k + 1000, drive.n_steps))
        steps = np.arange(k, k + z.shape[0])
        out = (steps >= k0) & ((steps - k0) % decim == 0)
        row = (steps - k0) // decim
        t[row[out]], x[row[out]] = drive.times(k, k + z.shape[0])[out], z[out]
        for i in range(z.shape[0]):
            qpos[idx.pan_qpos] = z[i]
            qvel[idx.pan_dof] = v[i]
            mujoco.mj_step(model, data)
            if out[i]:
                force[row[i]] = act_force[idx.tire_actuator]
    if np.any(data.warning.number) or not np.all(np.isfinite(force)):
        raise SimulationError("the Euler loop warned or produced non-finite tire forces")
    return {"t": t, "x": x, "f": force, "raw": None}


class SensorCapture:
    """Keeps the rollout's sensor and control rows of the output steps of one road run, for the
    raw sensor force: it stands in for the ``mujoco.rollout`` module that :mod:`rigsim.scenarios.core.stepping`
    calls (installed with :meth:`installed`), counting the steps of its successive calls."""

    def __init__(self, drive, dt_s: float, rate: float) -> None:
        self.k0, self.decim, _ = output_schedule(drive, dt_s, rate)
        self.k, self.sensors, self.controls = 0, [], []

    def rollout(self, model, data, state, control, **kwargs):
        out_state, out_sensor = self.real.rollout(model, data, state, control, **kwargs)
        steps = self.k + np.arange(out_sensor.shape[1])
        keep = (steps >= self.k0) & ((steps - self.k0) % self.decim == 0)
        self.sensors.append(out_sensor[0, keep])
        self.controls.append(control[keep])
        self.k += out_sensor.shape[1]
        return out_state, out_sensor

    def installed(self, fn, *args):
        self.real = stepping.rollout
        stepping.rollout = types.SimpleNamespace(rollout=self.rollout)
        try:
            return fn(*args)
        finally:
            stepping.rollout = self.real


def road_run(sc, i: int, capture: bool = False) -> dict:
    """One road run of ``sc`` at configuration ``i``: output instants (s), drive (m), forces (N);
    with ``capture`` also the raw sensor force (the pan at mid-step, at its mean velocity) and
    that force with the pan moved back to z_k ("moved"), N."""
    if i == LOOP:
        return loop_run(*loop_setup(sc), rate_hz(i))
    rig = make_rig(sc, i)
    drive = rig.road_source()
    if not capture:
        rec = rig.run(drive, rate_hz=rate_hz(i))
        return {"t": rec.t_s, "x": rec.x_ref_m, "f": rec.tire_force_N, "raw": None}
    cap = SensorCapture(drive, rig.dt_s, rate_hz(i))
    rec = cap.installed(lambda: rig.run(drive, rate_hz=rate_hz(i)))
    model, idx = rig.model, rig.index
    sensors, controls = np.concatenate(cap.sensors), np.concatenate(cap.controls)
    if sensors.shape[0] != rec.t_s.size:
        raise RuntimeError("the captured sensor rows do not match the record (a window was replayed)")
    length, truck_rate = sensors[:, rig.tire_length_sensors], sensors[:, rig.tire_rate_sensors]
    v_mean = controls[:, idx.tire_actuator]  # the pans' mean velocity over each step, m/s
    held = controls[:, model.nu:].reshape(-1, model.nmocap, 3)[:, idx.pan_mocap, 2] - model.body_pos[idx.pan_body, 2]
    raw = sensors[:, rig.sensors]  # what MuJoCo applied: the pan at mid-step, at its mean velocity
    if not np.allclose(raw, tire_law(model, idx, length, truck_rate - v_mean), rtol=1e-9, atol=1e-6):
        raise RuntimeError("the tire sensor is not the tire law of the captured tendon state")
    moved = tire_law(model, idx, length + held - rec.x_ref_m, truck_rate - v_mean)  # the pan moved back to z_k only
    return {"t": rec.t_s, "x": rec.x_ref_m, "f": rec.tire_force_N, "raw": raw, "moved": moved}


# ------------------------------------------------------------------------ workers
def dlc_job(i: int, case: int, duration_s: float) -> dict:
    """Worker: one road run of paper case ``case`` at configuration ``i``."""
    try:
        return road_run(paper_case(case, duration_s), i, capture=i != LOOP)
    except Exception as exc:  # a failed configuration is a result, not the end of the study
        return {"error": f"{type(exc).__name__}: {exc}"}


def gen_job(i: int, docs: list, duration_s: float) -> list:
    """Worker: per generalization case, whether a road run at configuration ``i`` stays finite."""
    out = []
    for doc in docs:
        sc = parse_scenario({**doc, "duration_s": duration_s})
        row = {"case": sc.name, "ok": False}
        try:
            r = road_run(sc, i)
            row["ok"] = bool(np.all(np.isfinite(r["f"])))
            row["error"] = None if row["ok"] else "non-finite output"
        except Exception as exc:  # SimulationError, or MuJoCo's own error
            row["error"] = f"{type(exc).__name__}: {exc}"
            row["refused"] = isinstance(exc, ScenarioError)  # refused before any step, not unstable
        out.append(row)
    return out


# ------------------------------------------------------------------------ in this process
def cost(duration_s: float, repeats: int) -> dict:
    """Per configuration: the median wall time (s) of one road run of paper case 1 (the stepping:
    ``Rig.run`` or the Euler loop; the model built beforehand), rounds interleaved, after a warm-up."""
    sc = paper_case(0, duration_s)
    made = {i: loop_setup(sc) if i == LOOP else make_rig(sc, i) for i in range(len(CONFIGS))}

    def once(i: int) -> float:
        if i == LOOP:
            model, idx, drive = made[i]
            t0 = time.perf_counter()
            loop_run(model, idx, drive, rate_hz(i))
        else:
            drive = made[i].road_source()
            t0 = time.perf_counter()
            made[i].run(drive, rate_hz=rate_hz(i))
        return time.perf_counter() - t0

    for i in made:
        once(i)
    walls = {i: [] for i in made}
    for _ in range(repeats):
        for i in made:
            walls[i].append(once(i))
    return {i: float(np.median(w)) for i, w in walls.items()}


# ------------------------------------------------------------------------ comparison
def common(run: dict, ref: dict) -> tuple[np.ndarray, np.ndarray]:
    """The reference's rows at ``run``'s output instants (t_s equal), and the largest difference
    of the drive there (m)."""
    rows = np.searchsorted(ref["t"], run["t"] - 1e-9)
    if rows.max() >= ref["t"].size or not np.allclose(ref["t"][rows], run["t"], rtol=0, atol=1e-9):
        raise ValueError("the run's output instants are not among the reference's")
    return rows, float(np.max(np.abs(ref["x"][rows] - run["x"])))


def compare(run: dict, ref: dict, key: str = "f") -> dict:
    """Per-wheel DLC error (%) and NRMSE (1) of ``run[key]`` against the reference's force."""
    rows, dx = common(run, ref)
    f_ref = ref["f"][rows]
    return {"dlc_pct": 100 * (dlc(run[key]) / dlc(f_ref) - 1), "nrmse": nrmse(run[key], f_ref), "drive_m": dx}


HEADER = ("config", "road run s", "cost ratio", "worst DLC err %", "worst NRMSE", "vs RK4 1e-4: DLC % ; NRMSE",
          "raw sensor: NRMSE ; DLC %", "pan at z_k, mean velocity: NRMSE ; DLC %", "stable", "passes")


def table_rows(rows: list[dict]) -> list[list[str]]:
    """The results table's cells, one row per configuration (:data:`HEADER`)."""
    out = []
    for r in rows:
        if r["errors"]:
            acc = ["failed: " + r["errors"][0][:60], "", "", "", ""]
        else:
            acc = [f"{r['worst_dlc_pct']:.4f}", f"{r['worst_nrmse']:.2e}",
                   f"{r['worst_dlc_pct_vs_rk4']:.4f} ; {r['worst_nrmse_vs_rk4']:.2e}"]
            acc += [f"{r['worst_' + k + '_nrmse']:.2e} ; {r['worst_' + k + '_dlc_pct']:.3f}"
                    if "worst_raw_nrmse" in r else "n/a" for k in ("raw", "moved")]
        stable = "reference" if r["stable"] is None else f"{r['stable']}/{GEN_CASES}"
        stable += f" ({r['refused']} refused)" if r["refused"] else ""
        note = "" if r["output_hz"] == OUTPUT_HZ else f" ({r['output_hz']:g} Hz record)"
        out.append([f"{r['config']}{note}", f"{r['run_s']:.2f}", f"{r['cost_ratio']:.2f}", *acc, stable,
                    "yes" if r["passes"] else "no"])
    return out


def notes(rows: list[dict], best: dict | None) -> str:
    """The text under the table: the goals and columns, the failures, the cheapest passing configuration."""
    lines = [f"Goals: road DLC within {DLC_GOAL_PCT:g} % of {label(REFERENCE)} on every wheel of the three cases; "
             f"{GEN_CASES}/{GEN_CASES} cases stable; a {OUTPUT_HZ:g} Hz record. Worst: over wheels and cases; "
             "NRMSE at the common output instants; raw sensor: the force MuJoCo applied (the pan at mid-step, "
             "at its mean velocity over the step), and that force with the pan moved back to z_k only, both "
             f"against {label(REFERENCE)}'s reconstructed force (pan at z_k, at the drive's velocity v_k); "
             "refused: the scenario is refused before any step (ScenarioError). Largest difference of the drive "
             f"at the common instants: {max(r.get('drive_difference_m', 0.0) for r in rows):.2g} m."]
    failures = [f"- {r['config']}: {what}" for r in rows for what in r["unstable_cases"][:3] + r["errors"][:1]]
    if failures:
        lines.append("\n".join(failures))
    lines.append(f"Cheapest passing: {best['config'] if best else 'none'}"
                 + (f" (cost ratio {best['cost_ratio']:.2f} of {label(LOOP)})" if best else "")
                 + f"; adopted (rigsim.scenarios.core.rig): {label(ADOPTED)}.")
    return "\n\n".join(lines)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--dlc-s", type=float, default=20.0, help="duration of each paper-case run, s")
    ap.add_argument("--gen-s", type=float, default=5.0, help="duration of each generalization run, s")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--results", type=pathlib.Path, default=RESULTS,
                    help="folder of the results file road_integrator_study.md (default docs/results)")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    n = len(CONFIGS)
    docs = generalization_cases(GEN_CASES, args.gen_s)
    jobs, where = [], []
    for i in range(n):  # the references (the longest jobs) first
        for c in range(3):
            jobs.append((dlc_job, (i, c, args.dlc_s)))
            where.append(("dlc", i, c))
    for i in range(n):
        if i not in REFERENCES:
            for b in range(0, GEN_CASES, GEN_BATCH):
                jobs.append((gen_job, (i, docs[b:b + GEN_BATCH], args.gen_s)))
                where.append(("gen", i, b))
    results = run_jobs(jobs, workers=args.workers,
                       on_done=lambda k, _: print(f"  done {where[k][0]} {label(where[k][1])}", file=sys.stderr))
    runs = {(i, c): r for (kind, i, c), r in zip(where, results) if kind == "dlc"}
    gens = {i: [] for i in range(n) if i not in REFERENCES}
    for (kind, i, _), r in zip(where, results):
        if kind == "gen":
            gens[i].extend(r)
    print(f"  pool phase {time.perf_counter() - t_start:.0f} s; timing in this process ...", file=sys.stderr)
    costs = cost(args.dlc_s, args.repeats)

    rows = []
    for i in range(n):
        row = {"config": label(i), "integrator": CONFIGS[i][0], "step_s": CONFIGS[i][1], "output_hz": rate_hz(i)}
        row["errors"] = [e for e in (runs[(i, c)].get("error") for c in range(3)) if e]
        row["errors"] += [f"reference {label(ref)} failed" for ref in REFERENCES
                          if any("error" in runs[(ref, c)] for c in range(3))]
        if not row["errors"]:
            for key, ref in (("", REFERENCE), ("_vs_rk4", SECOND_REFERENCE)):
                cmp = [compare(runs[(i, c)], runs[(ref, c)]) for c in range(3)]
                row["dlc_error_pct" + key] = [x["dlc_pct"].tolist() for x in cmp]
                row["worst_dlc_pct" + key] = float(np.max(np.abs(row["dlc_error_pct" + key])))
                row["nrmse" + key] = [x["nrmse"].tolist() for x in cmp]
                row["worst_nrmse" + key] = float(np.max(row["nrmse" + key]))
                row["drive_difference_m" + key] = max(x["drive_m"] for x in cmp)
            for key in ("raw", "moved") if i != LOOP else ():
                part = [compare(runs[(i, c)], runs[(REFERENCE, c)], key) for c in range(3)]
                row[key + "_nrmse"] = [x["nrmse"].tolist() for x in part]
                row["worst_" + key + "_nrmse"] = float(np.max(row[key + "_nrmse"]))
                row["worst_" + key + "_dlc_pct"] = float(np.max([np.abs(x["dlc_pct"]) for x in part]))
        g = gens.get(i)
        row["stable"] = None if g is None else int(sum(r["ok"] for r in g))
        row["unstable_cases"] = [] if g is None else [f"{r['case']}: {r['error']}" for r in g if not r["ok"]]
        row["refused"] = None if g is None else int(sum(bool(r.get("refused")) for r in g))
        row.update(run_s=costs[i], cost_ratio=costs[i] / costs[LOOP])
        row["passes"] = bool(not row["errors"] and row["worst_dlc_pct"] <= DLC_GOAL_PCT
                             and row["stable"] == GEN_CASES and row["output_hz"] == OUTPUT_HZ)
        rows.append(row)

    candidates = [r for i, r in enumerate(rows) if r["passes"] and i not in REFERENCES]
    best = min(candidates, key=lambda r: r["cost_ratio"]) if candidates else None
    title = (f"Road-test integrator study: against {label(REFERENCE)} and {label(SECOND_REFERENCE)}; paper cases "
             f"{args.dlc_s:g} s each (+2 s lead-in), {GEN_CASES} generalization cases of {args.gen_s:g} s; "
             f"cost: median of {args.repeats}, ratio to {label(LOOP)}")
    page = write_results_page(args.results, "road_integrator_study", title, HEADER, table_rows(rows),
                              script_command(__file__, argv), note=notes(rows, best))
    print(page.read_text(encoding="utf-8"))
    summary = {"reference": label(REFERENCE), "second_reference": label(SECOND_REFERENCE), "loop": label(LOOP),
               "adopted": label(ADOPTED), "cheapest_passing": best["config"] if best else None,
               "dlc_s": args.dlc_s, "gen_s": args.gen_s, "repeats": args.repeats,
               "wall_s": round(time.perf_counter() - t_start, 1), "configs": rows}
    print(json.dumps(summary, default=float))
    return summary


if __name__ == "__main__":
    main()
