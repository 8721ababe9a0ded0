"""Mutation score of the test suite: how many small deliberate bugs the tests catch.

::

    python benchmarks/mutation_score.py [--modules correction/metrics/dlc.py ...] [--timeout 120]

Runs cosmic-ray (``pip install cosmic-ray``; chosen because it is maintained, mutates any module
with the full set of operator, comparison, constant and boolean mutations, and runs an
arbitrary test command per mutant, so each module is checked by the tests that claim to cover
it) on a clean clone of the repository in a temporary folder, never on the working tree (it
rewrites the file it mutates). For each module of :data:`TARGETS` (or ``--modules``): the number
of mutants, killed, survived, timed out, the kill rate, and every survivor's diff. Prints a
markdown report and one JSON line. Too slow for CI (seconds per mutant); its report goes into
the closing note of a change to the tests.

A survivor is either a missing test (write it) or an equivalent mutant (explain it, e.g.
``ndim <= 0`` for ``ndim == 0``, or ``std <= 0`` for ``std == 0``: the same behaviour).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import shutil
import sqlite3
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]

#: Module -> the tests that claim to cover it (the command run against each mutant).
TARGETS = {
    "correction/metrics/dlc.py": ["tests/correction/metrics/test_dlc.py", "tests/correction/metrics/test_damage.py"],
    "correction/output/eq4.py": ["tests/correction/output/test_transfer.py", "tests/correction/output/test_correction.py"],
    "correction/metrics/rainflow_damage.py": ["tests/correction/metrics/test_rainflow_fast.py", "tests/correction/metrics/test_damage.py"],
    "hydraulics/model.py": ["tests/hydraulics/test_hydraulics_laws.py", "tests/hydraulics/test_hydraulics_model.py"],
    "scenarios/studies/scoring.py": ["tests/scenarios/studies/test_scoring.py"],
}


def _cosmic_ray(*args: str, cwd: pathlib.Path) -> subprocess.CompletedProcess:
    exe = pathlib.Path(sys.executable).with_name("cosmic-ray")
    return subprocess.run([str(exe), *args], cwd=cwd, capture_output=True, text=True)


def score_module(module: str, tests: list[str], clone: pathlib.Path, timeout_s: float) -> dict:
    cfg = clone / f"cr-{pathlib.Path(module).stem}.toml"
    session = cfg.with_suffix(".sqlite")
    command = f"{sys.executable} -m pytest -x -q -p no:cacheprovider {' '.join(tests)}"
    cfg.write_text(f'[cosmic-ray]\nmodule-path = "{module}"\ntimeout = {timeout_s}\nexcluded-modules = []\n'
                   f'test-command = "{command}"\n\n[cosmic-ray.distributor]\nname = "local"\n')
    for step in (("init", cfg.name, session.name), ("exec", cfg.name, session.name)):
        proc = _cosmic_ray(*step, cwd=clone)
        if proc.returncode != 0:
            raise SystemExit(f"cosmic-ray {step[0]} failed on {module}: {proc.stderr.strip()[-400:]}")
    report = subprocess.run([str(pathlib.Path(sys.executable).with_name("cr-report")), session.name, "--show-diff",
                             "--surviving-only"], cwd=clone, capture_output=True, text=True).stdout
    with sqlite3.connect(session) as db:
        rows = db.execute("SELECT test_outcome FROM work_results").fetchall()
    outcomes = [r[0] for r in rows]
    killed = sum(o.endswith("KILLED") for o in outcomes)
    survived = sum(o.endswith("SURVIVED") for o in outcomes)
    other = len(outcomes) - killed - survived
    return {"module": module, "tests": tests, "mutants": len(outcomes), "killed": killed, "survived": survived,
            "incompetent_or_timeout": other, "kill_rate": round(killed / max(1, killed + survived), 4),
            "survivors": [blk.strip() for blk in report.split("[job-id]")[1:]]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modules", nargs="+", default=list(TARGETS), help="modules (keys of TARGETS)")
    ap.add_argument("--timeout", type=float, default=120.0, help="s per mutant's test run")
    args = ap.parse_args(argv)
    unknown = [m for m in args.modules if m not in TARGETS]
    if unknown:
        raise SystemExit(f"--modules {' '.join(unknown)}: not in TARGETS ({', '.join(TARGETS)})")
    if shutil.which("cosmic-ray", path=str(pathlib.Path(sys.executable).parent)) is None:
        raise SystemExit("cosmic-ray is not installed in this environment: pip install cosmic-ray")
    results = []
    with tempfile.TemporaryDirectory(prefix="rigsim-mutation-") as d:
        clone = pathlib.Path(d) / "repo"
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        for m in args.modules:
            r = score_module(m, TARGETS[m], clone, args.timeout)
            print(f"[{m}] {r['killed']}/{r['killed'] + r['survived']} killed", file=sys.stderr, flush=True)
            results.append(r)
    print("| module | mutants | killed | survived | other | kill rate |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for r in results:
        print(f"| {r['module']} | {r['mutants']} | {r['killed']} | {r['survived']} | {r['incompetent_or_timeout']} | "
              f"{100 * r['kill_rate']:.1f} % |")
    for r in results:
        for s in r["survivors"]:
            print(f"\n#### survivor in {r['module']}\n```\n{s}\n```")
    killed = sum(r["killed"] for r in results)
    survived = sum(r["survived"] for r in results)
    print(json.dumps({"modules": [r["module"] for r in results], "killed": killed, "survived": survived,
                      "kill_rate": round(killed / max(1, killed + survived), 4), "goal": 0.9}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
