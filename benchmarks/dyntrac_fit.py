"""The simulated DYNTRAC identified from the paper: few physical unknowns fitted to Table 2.

::

    python benchmarks/dyntrac_fit.py [--duration-s 60] [--iterations 10] [--workers 2] [--check]
                                     [--out docs/results]

The paper publishes nine numbers of its rig (Table 2: the road, DYNTRAC and DYNTRAC corrected by
its eq. 4 method, DLC of three cases) but not the rig's loop gains, the roads' spectra or its
truck's suspension. This script treats them as an inverse problem. The unknowns
(:data:`UNKNOWNS`) are the position-loop gain and the differential-pressure gain of the
actuators, the road spectrum's waviness and the level of each of the paper's roughness words,
and the leaf springs' interleaf friction, each bounded by its physical range (and the source of
that range). Every evaluation runs the three paper cases (``scenarios/data/paper_dyntrac/*.toml``,
``rigsim paper --rig dyntrac``) with the values in place, on the road and on the rig (:func:`scenarios.core.run.run`), and scores the
rig's measured force (100 N load-cell noise) with the paper's method
(:func:`scenarios.studies.scoring.score_pair`, method ``paper``: eq. 4 and the 16/24 Hz T_F).

The fit is a Levenberg-Marquardt search in the logarithm of each unknown, the residual of each
number its relative error, reweighted towards the largest (the goal is every number within
+-5 %, a bound on the worst, not on the sum of squares); its Jacobian by forward differences
(one evaluation per unknown, all on the pool at once).

It starts from the values those scenarios carry, so a run on the shipped files verifies
them; ``--check`` evaluates those once and fits nothing. Prints one line per iteration, then the
table of the nine numbers (simulated, paper, error) and of the unknowns (fitted value, range,
source), with a warning for any value at a bound of its range (the data want it beyond: a sign
that something the fit lacks is being absorbed). With ``--out`` it writes both tables as
``dyntrac_fit.md`` (:mod:`scenarios.studies.results_page`).

Table 1's linearized-model column is measured by ``rigsim validate`` on the same scenario
(``benchmarks/docs_tables.py`` writes its table).
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import dataclasses
import sys
from typing import NamedTuple

import numpy as np

from scenarios.core.config import Scenario, load_scenario, paper_scenarios
from scenarios.core.rig import Rig
from scenarios.core.run import run
from scenarios.studies.paper.table import PAPER_TABLE2
from scenarios.studies.results_page import script_command, write_results_page
from scenarios.studies.scoring import NOISE_N, PAPER, score_pair

#: The worst relative error of a Table 2 number the fit accepts, 1.
GOAL = 0.05
#: Table 2's columns as (simulated key, paper key).
COLUMNS = (("road", "road"), ("rig", "rig"), ("paper", "corrected"))


class Unknown(NamedTuple):
    """One fitted value: its name, unit, physical range and the source of that range."""

    name: str
    unit: str
    lo: float
    hi: float
    source: str


#: The unknowns, in the order of the fit's vector. Each is applied to a paper scenario by
#: :func:`configured`.
UNKNOWNS = (
    Unknown("actuator.kp_per_m", "1/m", 12.0, 80.0,
            "DYNTRAC's loop gains are not published; velocity constant Ksv Kq Kp / A from 18 to 117 1/s "
            "(position bandwidth ~3-19 Hz), the upper end the loop's stability limit with 6 dB margin "
            "(hydraulics.loop)"),
    Unknown("actuator.kdp_per_Pa", "1/Pa", 0.5e-8, 4e-8,
            "differential-pressure feedback that damps the ~110 Hz oil-column mode: zeta 0.05-0.4 on the "
            "design station (hydraulics.loop); above ~5e-8 with a slow position loop the loop is unstable"),
    Unknown("road.waviness", "1", 1.5, 3.5,
            "ISO 8608 waviness w: 2 for its class lines; measured road profiles 1.5-3.5 (Andren 2006, "
            "Int. J. Vehicle Design 40)"),
    Unknown("road.gd_n0_m3 (medium)", "m^3", 8e-6, 128e-6,
            "ISO 8608 classes A-B: 'medium' by the roads' IRI is A, by the paper's DLC B "
            "(scenarios/core/roads.py)"),
    Unknown("road.gd_n0_m3 (high)", "m^3", 32e-6, 512e-6,
            "ISO 8608 classes B-C: 'high' by IRI is B, by the paper's DLC C (scenarios/core/roads.py)"),
    Unknown("vehicle.spring_friction_rear_N", "N", 400.0, 10000.0,
            "interleaf friction of a rear multi-leaf spring (the front spring half of it, as in "
            "mjcf/truck_rig.xml): friction bands of steel leaf springs from a few % to about a third of "
            "the static spring load (Fancher et al. 1980, UMTRI; Cebon 1999, Handbook of Vehicle-Road "
            "Interaction): 23.8 kN per rear spring at 3640 kg"),
)


def configured(scenario: Scenario, x: np.ndarray, duration_s: float) -> Scenario:
    """``scenario`` with the unknowns' values ``x`` (SI, :data:`UNKNOWNS`' order) in place."""
    kp, kdp, waviness, gd_medium, gd_high, friction_rear = (float(v) for v in x)
    word = _word(scenario)
    road = dataclasses.replace(scenario.road, roughness=None, waviness=waviness,
                               gd_n0_m3=gd_medium if word == "medium" else gd_high)
    actuator = {**scenario.actuator, "kp_per_m": kp, "kdp_per_Pa": kdp}
    vehicle = dataclasses.replace(scenario.vehicle, spring_friction_rear_N=friction_rear,
                                  spring_friction_front_N=friction_rear / 2.0)
    return dataclasses.replace(scenario, road=road, actuator=actuator, vehicle=vehicle, duration_s=duration_s)


def _word(scenario: Scenario) -> str:
    """The paper's roughness word of a paper case (its name says it)."""
    return "medium" if "-medium-" in scenario.name else "high"


def shipped_values(paths) -> np.ndarray:
    """The unknowns' values the shipped paper scenarios carry (the fit's start)."""
    from hydraulics.params import ActuatorParams

    scenarios = [load_scenario(p) for p in paths]
    defaults = ActuatorParams()
    first = scenarios[0]
    gd = {_word(s): s.road.gd_n0_m3 for s in scenarios}
    friction = first.vehicle.spring_friction_rear_N
    if any(v is None for v in gd.values()) or friction is None:
        raise SystemExit("the paper scenarios must give road.gd_n0_m3 and vehicle.spring_friction_rear_N "
                         "(numbers) for the fit to start from")
    return np.array([
        first.actuator.get("kp_per_m", defaults.kp_per_m), first.actuator.get("kdp_per_Pa", defaults.kdp_per_Pa),
        first.road.waviness, gd["medium"], gd["high"],
        friction,
    ], dtype=float)


def evaluate_case(path: str, x: np.ndarray, duration_s: float) -> tuple[float, float, float]:
    """Worker: DLC of the road, the rig (measured, with noise) and the paper's method, mean of the
    wheels, of one paper case under ``x``; NaNs if the configuration cannot run (an unstable loop)."""
    from scenarios.core.config import ScenarioError

    try:
        scenario = configured(load_scenario(path), x, duration_s)
        road, rig = run(scenario, "road"), run(scenario, "rig")
    except ScenarioError:
        return (float("nan"),) * 3
    score = score_pair(road, rig, Rig(scenario), methods=(PAPER,), noise_N=NOISE_N, seed=scenario.seed)
    return (float(np.mean(score.dlc_road)), float(np.mean(score.dlc_rig)),
            float(np.mean(score.methods[PAPER.name].figures["dlc_corrected"])))


def targets(paths) -> np.ndarray:
    """Table 2's nine numbers in the order of the residuals (case by case: road, rig, corrected)."""
    names = [load_scenario(p).name for p in paths]
    return np.array([PAPER_TABLE2[n][k] for n in names for _, k in COLUMNS])


def simulate(ex, paths, xs, duration_s: float) -> list[np.ndarray]:
    """The nine simulated numbers for each vector of ``xs``, all cases of all vectors on the pool."""
    jobs = [[ex.submit(evaluate_case, str(p), x, duration_s) for p in paths] for x in xs]
    return [np.array([v for f in row for v in f.result()]) for row in jobs]


def relative_error(sim: np.ndarray, target: np.ndarray) -> np.ndarray:
    """log(sim / paper) per number; 1 (e - 1 = 172 %) where the configuration failed."""
    r = np.log(sim / target)
    return np.where(np.isfinite(r), r, 1.0)


def fit(ex, paths, x0: np.ndarray, duration_s: float, iterations: int, say=print):
    """Levenberg-Marquardt in log space on the reweighted residuals (see the module's description).
    Returns the best vector, its simulated numbers and residuals."""
    lo = np.log([u.lo for u in UNKNOWNS])
    hi = np.log([u.hi for u in UNKNOWNS])
    target = targets(paths)
    z = np.clip(np.log(x0), lo, hi)
    sim = simulate(ex, paths, [np.exp(z)], duration_s)[0]
    r = relative_error(sim, target)
    say(f"start: worst {100 * np.max(np.abs(np.expm1(r))):.2f} %")
    lam, h = 1e-2, 0.04
    for it in range(iterations):
        if np.max(np.abs(r)) <= np.log1p(GOAL) / 4:
            break
        steps = [np.clip(z + h * e, lo, hi) for e in np.eye(z.size)]
        lengths = [float(np.max(zs - z)) for zs in steps]  # h, or less (0) at an upper bound
        sims = simulate(ex, paths, [np.exp(zs) for zs in steps], duration_s)
        J = np.array([(relative_error(sim_i, target) - r) / d if d > 0 else np.zeros_like(r)
                      for sim_i, d in zip(sims, lengths)]).T
        weight = (np.abs(r) / np.max(np.abs(r))) ** 3 + 0.05
        Jw, rw = J * weight[:, None], r * weight
        improved = False
        for _ in range(4):
            A = Jw.T @ Jw
            dz = np.linalg.solve(A + lam * np.diag(np.diag(A) + 1e-9), -Jw.T @ rw)
            zn = np.clip(z + dz, lo, hi)
            sn = simulate(ex, paths, [np.exp(zn)], duration_s)[0]
            rn = relative_error(sn, target)
            if np.max(np.abs(rn)) < np.max(np.abs(r)):
                z, sim, r, lam, improved = zn, sn, rn, lam / 3, True
                break
            lam *= 4
        say(f"iteration {it + 1}: worst {100 * np.max(np.abs(np.expm1(r))):.2f} %"
            + ("" if improved else " (no step improved it)"))
        if not improved:
            break
    return np.exp(z), sim, r


def tables(paths, x, sim) -> tuple[list, list]:
    """Rows of the two tables: the nine numbers, and the unknowns with their ranges and sources."""
    target = targets(paths)
    names = [load_scenario(p).name for p in paths]
    numbers = []
    for i, name in enumerate(names):
        for j, (col, _) in enumerate(COLUMNS):
            k = 3 * i + j
            numbers.append((name, col, f"{sim[k]:.4f}", f"{target[k]:.4f}", f"{100 * (sim[k] / target[k] - 1):+.1f} %"))
    values = []
    for u, v in zip(UNKNOWNS, x):
        at_bound = "at its bound" if min(abs(np.log(v / u.lo)), abs(np.log(v / u.hi))) < 0.01 else "inside"
        values.append((u.name, f"{v:.4g} {u.unit}", f"{u.lo:.3g} ... {u.hi:.3g}", at_bound, u.source))
    return numbers, values


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration-s", type=float, default=60.0, help="record length of every case, s (the paper's 60)")
    ap.add_argument("--iterations", type=int, default=10, help="at most this many Levenberg-Marquardt iterations")
    ap.add_argument("--workers", type=int, default=2, help="worker processes")
    ap.add_argument("--check", action="store_true", help="evaluate the shipped values only, fit nothing")
    ap.add_argument("--out", default=None, help="also write dyntrac_fit.md into this folder (e.g. docs/results)")
    args = ap.parse_args(argv)
    paths = paper_scenarios("dyntrac")
    x0 = shipped_values(paths)
    say = lambda line: print(line, file=sys.stderr, flush=True)  # noqa: E731
    with cf.ProcessPoolExecutor(args.workers) as ex:
        if args.check:
            x, sim = x0, simulate(ex, paths, [x0], args.duration_s)[0]
        else:
            x, sim, _ = fit(ex, paths, x0, args.duration_s, args.iterations, say)
    numbers, values = tables(paths, x, sim)
    worst = max(abs(sim / targets(paths) - 1))
    print("case | column | simulated | paper | error")
    for row in numbers:
        print(" | ".join(row))
    print()
    print("unknown | value | range | where | source of the range")
    for row in values:
        print(" | ".join(row))
    verdict = "within" if worst <= GOAL else "NOT within"
    print(f"\nworst error {100 * worst:.2f} %: {verdict} the +-{100 * GOAL:.0f} % goal")
    for row in values:
        if row[3] != "inside":
            print(f"warning: {row[0]} is at a bound of its range: the data want it beyond, so the fit lacks something")
    if args.out:
        cmd = script_command(__file__, argv)
        write_results_page(args.out, "dyntrac_fit", "The paper's Table 2 by the simulated DYNTRAC",
                           ("case", "column", "simulated", "paper", "error"), numbers, cmd,
                           note=f"Worst error {100 * worst:.2f} % (goal +-{100 * GOAL:.0f} %).")
        write_results_page(args.out, "dyntrac_values", "The fitted values of the simulated DYNTRAC",
                           ("unknown", "value", "range", "where", "source of the range"), values, cmd)
    return 0


if __name__ == "__main__":
    sys.exit(main())
