"""The model correction on trucks a lab brings: other geometry and suspension, described by their spec sheets.

::

    python benchmarks/fleet_suite.py --draw development|fresh [--trucks 24] [--duration-s 30]
                                     [--seed N] [--cab auto|held|fitted] [--workers N] [--noise-N 100]
                                     [--part K/N] [--keep SCORES.jsonl]
    python benchmarks/fleet_suite.py --page DEVELOPMENT.txt FRESH.txt [--results docs/results]

Truck ``i`` of a draw (:func:`rigsim.scenarios.studies.model_suite.fleet.draw_truck`) is a spec sheet
(wheelbase 3.6-6.5 m, tracks, dual or single rear tires, leaf or air on each axle with their rates
and dampers) and a plant truck on the rig that differs from it as the mismatch suite's plants differ
from the catalogue (payload, stations, masses, rebound, cab, progressive tire) and carries structure
the model family lacks (a frame that twists and bends, an engine on rubber mounts, dampers
digressive or worn, air springs' bushings), on its own road (ISO B-D, 30-90 km/h). Per truck, in
worker processes: the road test (the reference), the rig test and the rig's identification; then
:func:`rigsim.scenarios.studies.model_suite.mismatch_score.score_plant`: the rig test through the lab's
chain as it was (each filter corner off by up to 5 %, the force delay by up to 10 %), its channels
aligned with the lab's **nominal** settings, corrected linearly by the identified T_a and by the
truck model calibrated on the record, the model starting from the spec sheet (``rigsim correct
--model TRUCK.toml`` with the spec sheet as ``[vehicle]``).

The development draw is seed 0: what the method is developed on. ``--draw fresh`` draws the seed
when it runs (unless ``--seed`` gives one) and prints it: the set the method is scored on, never
tuned on. Each run prints its table, the goals and one JSON line; ``--page`` writes
``docs/results/fleet_suite.md`` from the two runs' printed output, the draws side by side with a
95 % confidence interval over trucks (:func:`rigsim.scenarios.studies.model_suite.goals.share_interval`).
``--part K/N`` scores the draw's trucks K-1, K-1+N, K-1+2N... alone (every truck is still drawn
and checked first), so that N processes or machines share a draw; ``--page`` joins the parts of one
draw and seed, given as their outputs, into that draw's table.
Goals (:mod:`rigsim.scenarios.studies.model_suite.goals`): at least 95 % of wheels within 1 % of the road
DLC at NRMSE at most half the linear floor; no wheel more than 0.05 NRMSE above the linear
correction.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import os
import pathlib
import re
import secrets
import subprocess
import sys
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from rigsim.correction.output.pipeline import CorrectionError  # noqa: E402
from rigsim.scenarios.core.files import to_json  # noqa: E402
from rigsim.scenarios.core.lab import TYPICAL_LAB  # noqa: E402
from rigsim.scenarios.core.pool import run_jobs  # noqa: E402
from rigsim.scenarios.records.model.cab_choice import AUTO, CAB_CHOICES  # noqa: E402
from rigsim.scenarios.studies import scoring  # noqa: E402
from rigsim.scenarios.studies.model_suite.fleet import fleet_job, fleet_trucks, lacks, spec_text  # noqa: E402
from rigsim.scenarios.studies.model_suite.goals import pct, rows_and_goals, share_interval  # noqa: E402
from rigsim.scenarios.studies.model_suite.lab_mass import mass_text  # noqa: E402
from rigsim.scenarios.studies.model_suite.mismatch_score import PlantScore, score_plant  # noqa: E402
from rigsim.scenarios.studies.results_page import markdown_table, script_command, write_results_page  # noqa: E402

RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results"
DRAWS = ("development", "fresh")
#: The development draw's seed.
DEVELOPMENT_SEED = 0
#: Hz: where the linear correction refuses a truck's records at 1 kHz (its identified T_a^-1 needs a
#: finer step than 1 ms to hold to 1 % below 30 Hz, and says so), they are recorded again at this rate,
#: as a lab follows that sentence's fix.
RETRY_RATE_HZ = 2000.0
#: kg: the load cells' uncompensated mass of the fleet's lab chain (its cells' mass less its
#: compensation; every truck's chain is the typical lab's, its filter corners apart).
CHAIN_MASS_KG = TYPICAL_LAB.cell_mass_kg - TYPICAL_LAB.compensation_kg


def _score(truck, runs, args, rate_hz):
    """One truck's runs (road, rig, identification) scored as ``rigsim correct --model`` with its spec sheet."""
    spec = truck.scenario(args.duration_s, truck="spec", rate_hz=rate_hz)
    return score_plant(truck.name, truck.plant, spec, *runs, lab=truck.lab, noise_N=args.noise_N, seed=spec.seed,
                       workers=args.workers, cab=args.cab, align=TYPICAL_LAB)


def _truck_text(score) -> str:
    p = score.plant
    return f"{p['_spec']}; lacks: {p['_lacks']}" + _frame_text(score)


def _frame_text(score) -> str:
    """Where the calibration fitted the model's frame: its torsion/bending modes, Hz; its engine: mount Hz, mass kg;
    its dampers digressive: knee m/s, slope ratio, rebound ratio."""
    out = "" if score.frame_hz is None else f"; model's frame fitted {score.frame_hz[0]:.1f}/{score.frame_hz[1]:.1f} Hz"
    if score.engine is not None:
        out += f"; model's engine fitted {score.engine[1]:.0f} kg on {score.engine[0]:.1f} Hz"
    if score.damper is not None:
        out += f"; model's dampers digressive x{score.damper[1]:.2f} above {score.damper[0]:.2f} m/s" + (
            f", rebound x{score.damper[2]:.2f}" if len(score.damper) > 2 else "")
    return out


#: What a ``--keep`` file's lines must share with the run that reads them: the draw, its settings and
#: the code that scored it (:func:`code_version`).
KEPT_SETTINGS = ("draw", "seed", "trucks", "duration_s", "noise_N", "cab", "code")


#: What scores a draw: the package's sources, its dependencies' pins and this script (paths in the repository).
CODE_PATHS = ("rigsim", "mjcf", "hydraulics", "correction", "scenarios", "pyproject.toml", "benchmarks/fleet_suite.py")


def code_version(root: pathlib.Path | None = None) -> str | None:
    """The version of the code that scores a draw: a digest of :data:`CODE_PATHS` as committed (their git
    object ids at HEAD, so that a commit of docs or tests leaves it as it is), with ``+changes-`` and a
    digest of the difference where the checkout's files there differ from HEAD; None outside a git
    checkout. ``root``: the repository (default: this script's)."""
    root = pathlib.Path(__file__).resolve().parents[1] if root is None else root
    try:
        ids = subprocess.run(["git", "rev-parse", *(f"HEAD:{p}" for p in CODE_PATHS)], cwd=root, capture_output=True,
                             text=True, check=True)
        diff = subprocess.run(["git", "diff", "HEAD", "--", *CODE_PATHS], cwd=root, capture_output=True, text=True,
                              check=True)
    except (OSError, subprocess.CalledProcessError):
        return None
    digest = hashlib.sha1(ids.stdout.encode()).hexdigest()[:16]
    return digest + (f"+changes-{hashlib.sha1(diff.stdout.encode()).hexdigest()[:8]}" if diff.stdout.strip() else "")


def refused(text: str) -> SystemExit:
    """Bad input: ``text`` (one sentence naming the field and the fix) on stderr, and the exit (code 2) to
    raise before any run or write; its message is ``text``."""
    print(text, file=sys.stderr, flush=True)
    exc = SystemExit(text)
    exc.code = 2
    return exc


def read_kept(path: pathlib.Path | None) -> list[dict]:
    """The lines of a ``--keep`` file (none where it is not given or does not exist yet). A line a run
    cut short left unfinished is skipped (its truck is run again), and said on stderr."""
    if path is None or not path.exists():
        return []
    lines, cut = [], 0
    for text in path.read_text(encoding="utf-8").splitlines():
        try:
            line = json.loads(text)
        except json.JSONDecodeError:
            cut += text.strip() != ""
            continue
        if isinstance(line, dict) and "plant" in line:
            lines.append(line)
        else:
            cut += 1
    if cut:
        print(f"{path}: {cut} line(s) not a whole truck's score (a run cut while writing); those trucks run again",
              file=sys.stderr, flush=True)
    return lines


def kept_scores(lines: list[dict], settings: dict, path) -> dict[str, tuple[PlantScore, bool]]:
    """The trucks a ``--keep`` file's ``lines`` hold for the run of ``settings``: {name: (its score, whether
    it was recorded at :data:`RETRY_RATE_HZ`)}. Refuses (exit 2) a file that holds another draw's or
    settings' scores, before any run."""
    out = {}
    for line in lines:
        other = {k: line.get(k) for k in KEPT_SETTINGS}
        if other != {k: settings[k] for k in KEPT_SETTINGS}:
            diff = next(k for k in KEPT_SETTINGS if other[k] != settings[k])
            raise refused(f"--keep {path} holds scores of a run with {diff} {other[diff]!r}, not {settings[diff]!r}: "
                          f"give that run's settings, or another --keep file")
        out[line["plant"]["name"]] = (PlantScore.from_dict(line["plant"]), bool(line.get("retried")))
    return out


def keep(path: pathlib.Path | None, settings: dict, score: PlantScore, retried: bool) -> None:
    """Append ``score`` to the ``--keep`` file as one JSON line, flushed to disk."""
    if path is None:
        return
    line = json.loads(to_json({k: settings[k] for k in KEPT_SETTINGS} | {"retried": retried, "plant": score.to_dict()}))
    with path.open("a", encoding="utf-8") as f:
        f.write(json.dumps(line) + "\n")
        f.flush()
        os.fsync(f.fileno())


def _seed(args, lines: list[dict]) -> int:
    """The draw's seed: ``--seed``; else 0 for the development draw; else a fresh draw's ``--keep`` file's;
    else drawn now."""
    if args.seed is not None:
        return args.seed
    if args.draw == "development":
        return DEVELOPMENT_SEED
    return lines[0]["seed"] if lines else secrets.randbits(31)


def run_draw(args) -> dict:
    """Run and score one draw; its settings, summary and scores (as printed in its JSON line)."""
    lines = read_kept(args.keep)
    seed = _seed(args, lines)
    settings = {"draw": args.draw, "seed": seed, "trucks": args.trucks, "duration_s": args.duration_s,
                "noise_N": args.noise_N, "cab": args.cab, "code": code_version()}
    kept = kept_scores(lines, settings, args.keep)
    print(f"fleet suite, {args.draw} draw: seed {seed}", file=sys.stderr, flush=True)
    trucks = fleet_trucks(args.trucks, seed)  # every truck drawn and checked before any run
    part_k, part_n = args.part
    trucks = trucks[part_k - 1::part_n]
    t0 = time.perf_counter()
    for truck in trucks:
        if truck.name in kept:
            print(f"[{0:6.0f} s] {truck.name}: kept in {args.keep}", file=sys.stderr, flush=True)
    keys = [(i, k) for i in range(len(trucks)) if trucks[i].name not in kept for k in ("road", "rig", "identify")]
    jobs = [(fleet_job, (trucks[i], args.duration_s, k)) for i, k in keys]

    def said(j, _r):
        i, k = keys[j]
        print(f"[{time.perf_counter() - t0:6.0f} s] {trucks[i].name}: {k}", file=sys.stderr, flush=True)

    by = dict(zip(keys, run_jobs(jobs, workers=args.workers, on_done=said)))
    scores, at_retry_rate = [], []
    for i, truck in enumerate(trucks):
        if truck.name in kept:
            s, retried = kept[truck.name]
            scores.append(s)
            at_retry_rate += [truck.name] if retried else []
            continue
        runs = [by.pop((i, k)) for k in ("road", "rig", "identify")]
        retried = False
        try:
            s = _score(truck, runs, args, None)
        except CorrectionError as exc:  # the lab's own fix: record at a rate the correction filter holds at
            if "sampling rate" not in str(exc):
                raise
            print(f"[{time.perf_counter() - t0:6.0f} s] {truck.name}: {exc}; its records again at "
                  f"{RETRY_RATE_HZ:g} Hz", file=sys.stderr, flush=True)
            runs = run_jobs([(fleet_job, (truck, args.duration_s, k, RETRY_RATE_HZ)) for k in ("road", "rig", "identify")],
                            workers=args.workers)
            s = _score(truck, runs, args, RETRY_RATE_HZ)
            at_retry_rate.append(truck.name)
            retried = True
        s = dataclasses.replace(s, plant={**s.plant, "_spec": spec_text(truck), "_lacks": lacks(truck)})
        keep(args.keep, settings, s, retried)
        scores.append(s)
        print(f"[{time.perf_counter() - t0:6.0f} s] {s.name} ({spec_text(truck)}): {s.method}, DLC "
              f"{' '.join(pct(x) for x in s.dlc_error['delivered'])}, NRMSE/floor "
              f"{' '.join(f'{x:.2f}' for x in s.nrmse['delivered'] / s.floor)}, {s.wall_s:.0f} s"
              + (f" ({s.reason})" if s.reason else "") + _frame_text(s), file=sys.stderr, flush=True)
    head, rows, goals, numbers = rows_and_goals(scores, _truck_text)
    interval = share_interval(scores)
    print(markdown_table(head, rows))
    print(goals)
    print(f"- 95 % confidence interval of the share over trucks: {100 * interval[0]:.1f}-{100 * interval[1]:.1f} %")
    if at_retry_rate:
        print(f"- recorded at {RETRY_RATE_HZ:g} Hz where the linear correction refused 1 kHz: {', '.join(at_retry_rate)}")
    settings = settings | {"part": f"{part_k}/{part_n}", "at_retry_rate": at_retry_rate, "command": script_command(__file__)}
    out = json.loads(to_json(settings | {"summary": numbers, "interval": interval,
                                         "wall_time_s": round(time.perf_counter() - t0, 1),
                                         "plants": [s.to_dict() for s in scores]}))
    print(json.dumps(out))
    return out


def _read_run(path: pathlib.Path) -> dict:
    if not path.is_file():
        raise refused(f"--page {path}: no such file; give the files a fleet_suite run's output was written to")
    lines = [line for line in path.read_text(encoding="utf-8").splitlines() if line.startswith("{")]
    if not lines:
        raise refused(f"--page {path}: no JSON line of a fleet_suite run in it; give the file its run printed")
    return json.loads(lines[-1])


def joined(runs: list[dict]) -> list[dict]:
    """The runs with the parts of one draw and seed (``--part``) joined into one run, in the order each
    draw first appears: its trucks in the draw's order, its interval over all of them, its commands
    joined with ``&``. Refuses parts that overlap, miss a truck or differ in their settings."""
    groups: dict = {}
    for run in runs:
        groups.setdefault((run["draw"], run["seed"]), []).append(run)
    out = []
    for (draw, seed), parts in groups.items():
        if len(parts) == 1 and parts[0].get("part", "1/1") == "1/1":
            out.append(parts[0])
            continue
        plants = sorted((p for run in parts for p in run["plants"]), key=lambda p: p["name"])
        names = [p["name"] for p in plants]
        settings = {(run["trucks"], run["duration_s"], run["noise_N"], run["cab"], run.get("code")) for run in parts}
        if len(settings) > 1 or len(set(names)) != len(names) or len(names) != parts[0]["trucks"]:
            raise refused(f"the parts of the {draw} draw (seed {seed}) do not make one draw: give each part "
                          f"once, all run with the same --trucks, --duration-s, --noise-N and --cab by the same code")
        scores = [PlantScore.from_dict(p) for p in plants]
        out.append(parts[0] | {"part": "1/1", "plants": plants, "interval": list(share_interval(scores)),
                               "at_retry_rate": sorted(n for run in parts for n in run.get("at_retry_rate") or []),
                               "wall_time_s": max(run["wall_time_s"] for run in parts),
                               "command": " & ".join(run["command"] for run in parts)})
    return out


def write_page(paths: list[pathlib.Path], results: pathlib.Path) -> pathlib.Path:
    """``fleet_suite.md``: each draw's summary side by side, then each draw's table."""
    runs = joined([_read_run(p) for p in paths])
    for run in runs:  # where a run wrote its page or kept its scores is not what it measured
        run["command"] = re.sub(r" --(results|keep)(=| )\S+", "", run["command"])
    summary_head = ["draw", "seed", "trucks", "wheels good (95 % CI over trucks)", "worst DLC error",
                    "worst NRMSE above linear", "fallbacks", "median wall s", "median CPU s"]
    summary, parts = [], []
    for run in runs:
        scores = [PlantScore.from_dict(p) for p in run["plants"]]
        head, rows, goals, numbers = rows_and_goals(scores, _truck_text)
        lo, hi = run["interval"]
        summary.append([run["draw"], run["seed"], len(scores), f"{100 * numbers['share_good']:.1f} % "
                        f"({100 * lo:.1f}-{100 * hi:.1f} %)", f"{100 * numbers['worst_dlc_error']:.2f} %",
                        f"{numbers['worst_above_linear']:+.3f}", numbers["fallbacks"], f"{numbers['median_wall_s']:.0f}",
                        f"{numbers['median_cpu_s']:.0f}"])
        retried = run.get("at_retry_rate") or []
        unsaid = any("frame_hz" not in p for p in run["plants"])  # an output without the fitted frames
        parts.append(f"**The {run['draw']} draw** (seed {run['seed']}, `{run['command']}`"
                     + ("; its output does not say which trucks' calibrations fitted the frame" if unsaid else "")
                     + ")\n\n"
                     + markdown_table(head, rows).rstrip("\n") + "\n\n" + goals
                     + ("\n" + mass if (mass := mass_text(scores, CHAIN_MASS_KG)) else "")
                     + (f"\n- recorded at {RETRY_RATE_HZ:g} Hz, where the linear correction refused the 1 kHz records "
                        f"(its T_a^-1 off by more than 1 % below 30 Hz at that step): {', '.join(retried)}" if retried else ""))
    note = ("Per truck the worse wheel, as in the mismatch suite (docs/results/mismatch_suite.md); the plant column "
            "gives the spec sheet (wheelbase, rear tires, front/rear suspension, payload) and what the plant has that "
            "its model lacks. The records pass through the lab's chain as it was (corners off by up to 5 %) and are "
            "aligned with its nominal settings. A truck's wall time depends on what else the machine ran (the draws may run "
            "side by side); its CPU time is the calibration's and correction's own, in this process and its workers.\n\n"
            + "\n\n".join(parts))
    command = " && ".join(r["command"] for r in runs)
    draws = " and ".join(dict.fromkeys(r["draw"] for r in runs))
    page = write_results_page(results, "fleet_suite", f"The model correction on trucks a lab brings: {draws} "
                              f"draw{'s' if len(runs) > 1 else ''}", summary_head, summary, command, note=note,
                              script=script_command(__file__, ["--page", *(f"{r['draw'].upper()}.txt" for r in runs)]))
    print(page.read_text(encoding="utf-8"))
    return page


def _part(text: str) -> tuple[int, int]:
    """``K/N`` (1 <= K <= N) as (K, N)."""
    try:
        k, n = (int(v) for v in text.split("/"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--part must be K/N, e.g. 1/2, got {text!r}") from None
    if not 1 <= k <= n:
        raise argparse.ArgumentTypeError(f"--part K/N needs 1 <= K <= N, got {text!r}")
    return k, n


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draw", choices=DRAWS, default=None, help="run the development draw (seed 0) or a fresh one")
    ap.add_argument("--trucks", type=int, default=24, help="how many trucks (default 24)")
    ap.add_argument("--duration-s", type=float, default=30.0, help="analysed seconds per run (default 30)")
    ap.add_argument("--seed", type=int, default=None, help="the draw's seed (default: 0, or drawn now for fresh)")
    ap.add_argument("--cab", choices=CAB_CHOICES, default=AUTO, help="the model's cab mode (default auto)")
    ap.add_argument("--noise-N", type=float, default=scoring.NOISE_N, help="white load-cell noise, N rms (default 100)")
    ap.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    ap.add_argument("--part", type=_part, default=(1, 1), metavar="K/N",
                    help="score the draw's trucks K-1, K-1+N, ... alone (default 1/1: all of them)")
    ap.add_argument("--keep", type=pathlib.Path, default=None, metavar="SCORES.jsonl",
                    help="append each truck's score to this file as it is scored; the trucks it holds are not run again")
    ap.add_argument("--page", type=pathlib.Path, nargs="+", default=None, metavar="RUN.txt",
                    help="write fleet_suite.md from runs' printed output instead of running")
    ap.add_argument("--results", type=pathlib.Path, default=RESULTS, help="folder of fleet_suite.md")
    args = ap.parse_args(argv)
    if args.page is not None:
        write_page(args.page, args.results)
        return 0
    if args.draw is None:
        ap.error("give --draw development or --draw fresh (or --page RUN.txt ...)")
    if not 1 <= args.trucks <= 200 or args.duration_s < scoring.MIN_DURATION_S or args.noise_N < 0:
        ap.error(f"--trucks must be 1-200, --duration-s >= {scoring.MIN_DURATION_S:g} s, --noise-N >= 0")
    run_draw(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
