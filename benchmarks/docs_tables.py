"""The tables of docs/validation.md, written from the studies' own result files.

::

    python benchmarks/docs_tables.py [--paper out/paper] [--validate out/validate]
                                     [--iterate DIR ...] [--out docs/results]

Reads the output folder of a finished ``rigsim paper --out DIR`` (its ``paper.json``), of a
finished ``rigsim validate --out DIR`` (its ``validate.json``) and of finished ``rigsim iterate
CASE.toml --target displacement|force --out DIR`` runs (their ``iteration.json``) and writes

* ``paper_table2.md``: the Table 2 analogue, DLC (mean of the four wheels) of the road, the rig,
  the rig corrected by the paper's method and by this project's, the road through the same
  low-pass, and the NRMSE, each case beside the paper's published values
  (:data:`rigsim.scenarios.studies.paper.table.PAPER_TABLE2`);
* ``validate_table1.md``: the Table 1 analogue, DLC of the road test, the rig test and the
  linearized models, beside the paper's;
* ``iterate_comparison.md``: input correction against output correction, per case the DLC error of
  the rig with the original drive, with the drive iterated to each target, and of the output
  correction, with the rig runs each costs (one ``--iterate`` folder per case and target).

Each file ends in the line saying how it was measured (:mod:`rigsim.scenarios.studies.results_page`):
the command (with the duration and noise read from the results), the date of the result file,
and the rigsim version, platform, CPU count and Python of the machine running this script: run
it where the study ran. A folder that is not given, or has no result file, is skipped with one
line on stderr.
"""

from __future__ import annotations

import argparse
import datetime
import json
import pathlib
import re
import sys

from rigsim.scenarios.studies.paper.table import PAPER_TABLE1, PAPER_TABLE2
from rigsim.scenarios.studies.results_page import write_results_page

ROOT = pathlib.Path(__file__).resolve().parents[1]
#: What writes the files (their first line says so).
SCRIPT = "python benchmarks/docs_tables.py --paper DIR --validate DIR"
#: What writes the simulated DYNTRAC's tables.
DYNTRAC_SCRIPT = "python benchmarks/docs_tables.py --paper-dyntrac DIR --validate-dyntrac DIR"
#: What writes the iteration's table.
ITERATE_SCRIPT = "python benchmarks/docs_tables.py --iterate DIR ..."

TABLE2_HEADER = ("case", "road DLC (paper)", "rig DLC (paper)", "corrected, paper's method (paper)",
                 "its ceiling: road through T_F", "corrected, this project", "road through the same low-pass", "NRMSE")
#: The model correction's columns (``rigsim paper --model``), appended when the result has them.
MODEL_HEADER = ("corrected, truck model (vs road)", "its NRMSE")
DAMAGE_HEADER = ("case", "stress factor n = 4: road", "rig", "corrected", "DEL m = 5: road", "rig", "corrected")
ITERATE_HEADER = ("case", "rig, original drive", "iterated drive, displacement target", "iterated drive, force target",
                  "output-corrected")
TABLE1_HEADER = ("", "road test", "rig test (nonlinear multibody)", "linearized model (route 2 T_a per wheel)",
                 "eq. 4 T_a", "route 2 whole linear plant")


def case_label(name: str) -> str:
    """``paper-medium-72kmh-6360kg`` -> ``medium, 72 km/h, 6360 kg``; any other name as it is."""
    m = re.fullmatch(r"paper-(\w+)-(\d+)kmh-(\d+)kg", name)
    return f"{m[1]}, {m[2]} km/h, {m[3]} kg" if m else name


def _date_of(path: pathlib.Path) -> datetime.date:
    return datetime.date.fromtimestamp(path.stat().st_mtime)


def _with_paper(value: float, paper: float | None) -> str:
    return f"{value:.4f}" if paper is None else f"{value:.4f} ({paper:.4f})"


def _over(value: float, ceiling: float) -> str:
    """``^`` after a corrected DLC above its ceiling (an over-correction)."""
    return "^" if value > ceiling else ""


def table2_rows(result: dict) -> list[list[str]]:
    """One row per case of ``paper.json``'s ``cases``, the paper's values in brackets; the paper's
    method's ceiling (the road force through its T_F), a corrected DLC above it marked ``^`` (the
    paper's own: above its road); the model correction's DLC and NRMSE when the result has them."""
    models = {m["case"]: m for m in result.get("model_correction") or []}
    rows = []
    for case in result["cases"]:
        paper = PAPER_TABLE2.get(case["case"]) or case.get("paper") or {}
        ceiling = case["dlc_road_lowpassed_paper"]
        mark = _over(case["dlc_corrected_paper"], ceiling)
        ref = paper.get("corrected")
        ref_text = "" if ref is None else f" ({ref:.4f}{_over(ref, paper.get('road', float('inf')))})"
        row = [case_label(case["case"]),
               _with_paper(case["dlc_road"], paper.get("road")),
               _with_paper(case["dlc_rig"], paper.get("rig")),
               f"{case['dlc_corrected_paper']:.4f}{mark}{ref_text}", f"{ceiling:.4f}",
               f"{case['dlc_corrected']:.4f}", f"{case['dlc_road_lowpassed']:.4f}",
               f"{case['nrmse_corrected']:.3f}"]
        if models:
            m = models.get(case["case"], {}).get("mean")
            row += (["-", "-"] if m is None else
                    [f"{m['dlc']:.4f} ({100 * m['dlc_error']:+.1f} %)", f"{m['nrmse']:.3f}"])
        rows.append(row)
    return rows


def _against(value: float, road: float, text: str) -> str:
    return f"{text} ({100.0 * (value / road - 1.0):+.1f} %)"


def damage_rows(result: dict) -> list[list[str]]:
    """One row per case of ``paper.json``: the stress factor (n = 4) and the damage-equivalent load
    (m = 5, kN) of road, rig and this project's correction, rig and corrected against the road."""
    rows = []
    for case in result["cases"]:
        sf = [case[f"stress_factor_{k}"] for k in ("road", "rig", "corrected")]
        dl = [case[f"del_{k}_N"] / 1e3 for k in ("road", "rig", "corrected")]
        rows.append([case_label(case["case"]), f"{sf[0]:.4f}", _against(sf[1], sf[0], f"{sf[1]:.4f}"),
                     _against(sf[2], sf[0], f"{sf[2]:.4f}"), f"{dl[0]:.2f} kN",
                     _against(dl[1], dl[0], f"{dl[1]:.2f} kN"), _against(dl[2], dl[0], f"{dl[2]:.2f} kN")])
    return rows


def paper_command(folder: pathlib.Path, result: dict) -> str:
    """The ``rigsim paper`` command of the result: its duration from the first case's road run
    (``<case>/road/result.json``: samples over rate) when the folder has it, its noise, the
    configuration (``--rig dyntrac`` when its scenarios are the fitted ones) and ``--model``."""
    command = "rigsim paper --out DIR"
    if result.get("configuration") == "dyntrac":
        command += " --rig dyntrac"
    if result.get("model_correction"):
        command += " --model"
    cases = result.get("cases") or [{}]
    run = folder / str(cases[0].get("case")) / "road" / "result.json"
    if run.is_file():
        r = json.loads(run.read_text())
        command += f" --duration-s {round((r['samples'] - 1) / r['rate_hz'], 3):g}"
    if "noise_N" in cases[0]:
        command += f" --noise-N {cases[0]['noise_N']:g}"
    return command


def write_table2(folder: pathlib.Path, out: pathlib.Path, name: str = "paper_table2",
                 title: str = "Table 2 analogue: DLC of the paper's cases", script: str = SCRIPT) -> pathlib.Path:
    """``out/<name>.md`` from ``folder/paper.json``."""
    source = folder / "paper.json"
    result = json.loads(source.read_text())
    note = ("DLC = std/mean of the wheel force, mean of the four wheels; the paper's Table 2 in brackets. "
            "Road and rig over the whole record, every corrected figure on the samples where its filters "
            "have settled. The paper's method (eq. 4 under its 16/24 Hz T_F) can give back at most the road "
            "force through T_F, its ceiling; ^ marks a value above it (the paper's own: above its road), an "
            "over-correction. NRMSE = rms(corrected - road through the low-pass) / std(road through the "
            "low-pass).")
    header = TABLE2_HEADER + (MODEL_HEADER if result.get("model_correction") else ())
    return write_results_page(out, name, title, header, table2_rows(result), paper_command(folder, result),
                              _date_of(source), note, script)


def write_table2_dyntrac(folder: pathlib.Path, out: pathlib.Path) -> pathlib.Path:
    """``out/paper_table2_dyntrac.md`` from a ``rigsim paper --rig dyntrac [--model]`` folder."""
    return write_table2(folder, out, "paper_table2_dyntrac",
                        "Table 2 analogue on the simulated DYNTRAC (the rig, roads and leaf friction fitted to the paper)",
                        DYNTRAC_SCRIPT)


#: The markers around README.md's Table 2 block, which :func:`write_readme_table` rewrites.
README_BEGIN = "<!-- table2: written by benchmarks/docs_tables.py --paper DIR --readme README.md -->"
README_END = "<!-- table2 end -->"
README_HEADER = ("case", "road DLC", "rig DLC", "corrected, paper's method", "corrected, linear (identified T_a)",
                 "corrected, truck model", "NRMSE linear / model")


def readme_rows(result: dict) -> list[list[str]]:
    """README's Table 2: road, rig and the three corrections of each case, the paper's values in
    brackets, the truck model's DLC against the road and both NRMSEs ("-" without ``--model``)."""
    models = {m["case"]: m.get("mean") for m in result.get("model_correction") or []}
    rows = []
    for case in result["cases"]:
        paper = PAPER_TABLE2.get(case["case"]) or case.get("paper") or {}
        m = models.get(case["case"])
        model = "-" if m is None else f"{m['dlc']:.4f} ({100 * m['dlc_error']:+.1f} % from road)"
        nrmse = f"{case['nrmse_corrected']:.3f} / " + ("-" if m is None else f"{m['nrmse']:.3f}")
        rows.append([case_label(case["case"]), _with_paper(case["dlc_road"], paper.get("road")),
                     _with_paper(case["dlc_rig"], paper.get("rig")),
                     _with_paper(case["dlc_corrected_paper"], paper.get("corrected")),
                     f"{case['dlc_corrected']:.4f}", model, nrmse])
    return rows


def write_readme_table(folder: pathlib.Path, readme: pathlib.Path) -> pathlib.Path:
    """Rewrite the block of ``readme`` between :data:`README_BEGIN` and :data:`README_END` with the
    Table 2 of ``folder/paper.json`` and the command that measured it."""
    from rigsim.scenarios.studies.results_page import configuration_line, markdown_table, write_block

    source = folder / "paper.json"
    result = json.loads(source.read_text())
    block = (markdown_table(README_HEADER, readme_rows(result)).rstrip("\n") + "\n\n"
             + configuration_line(paper_command(folder, result), _date_of(source)) + "\n")
    return write_block(readme, README_BEGIN, README_END, block)


def write_damage(folder: pathlib.Path, out: pathlib.Path) -> pathlib.Path:
    """``out/paper_damage.md`` from ``folder/paper.json``."""
    source = folder / "paper.json"
    result = json.loads(source.read_text())
    note = ("Means of the four wheels. Stress factor E[(F/F_static)^4] of pavements' fourth-power law; "
            "damage-equivalent load of the rainflow-counted cycles (ASTM E1049-85), m = 5, one cycle per "
            "second; road, rig and corrected on the same samples (where the correction has settled), rig "
            "and corrected against the road in brackets.")
    return write_results_page(out, "paper_damage", "Damage of the paper's cases: pavements and components",
                              DAMAGE_HEADER, damage_rows(result), paper_command(folder, result), _date_of(source),
                              note, SCRIPT)


def table1_rows(result: dict) -> list[list[str]]:
    """This model's row and the paper's row of ``validate.json``'s ``table1``."""
    t = result["table1"]
    paper = {**PAPER_TABLE1, **t.get("paper", {})}
    paper_pct = 100.0 * (paper["linearized_model"] / paper["rig_test"] - 1.0)
    return [["this model", f"{t['road_test']:.4f}", f"{t['rig_test']:.4f}",
             f"{t['linearized_model']:.4f} ({t['linearized_vs_rig_pct']:+.2f} %)",
             f"{t['linearized_model_eq4']:.4f} ({t['linearized_eq4_vs_rig_pct']:+.2f} %)",
             f"{t['linearized_model_route2_mimo']:.4f} ({t['linearized_route2_mimo_vs_rig_pct']:+.2f} %)"],
            ["paper", f"{paper['road_test']:.4f}", f"{paper['rig_test']:.4f} (nonlinear model {paper['nonlinear_model']:.4f})",
             f"{paper['linearized_model']:.4f} ({paper_pct:+.2f} %)", "", ""]]


def write_table1(folder: pathlib.Path, out: pathlib.Path, name: str = "validate_table1",
                 script: str = SCRIPT, rig: str = "design") -> pathlib.Path:
    """``out/<name>.md`` from ``folder/validate.json`` of a ``rigsim validate --rig RIG`` run."""
    source = folder / "validate.json"
    result = json.loads(source.read_text())
    command = "rigsim validate --out DIR"
    if rig != "design":
        command += f" --rig {rig}"
    if "duration_s" in result:
        command += f" --duration-s {result['duration_s']:g}"
    if "ident_duration_s" in result:
        command += f" --ident-duration-s {result['ident_duration_s']:g}"
    note = ("DLC = std/mean of the tire force, mean of the four wheels; in brackets each linearized model "
            "against the rig test. The rig test is the nonlinear multibody rig: it stands for both the "
            "paper's DYNTRAC test and its nonlinear model.")
    return write_results_page(out, name,
                              "Table 1 analogue: DLC of the rig and its linearized models (high roughness, 72 km/h, 3640 kg)",
                              TABLE1_HEADER, table1_rows(result), command, _date_of(source), note, script)


def write_table1_dyntrac(folder: pathlib.Path, out: pathlib.Path) -> pathlib.Path:
    """``out/validate_table1_dyntrac.md`` from a ``rigsim validate --rig dyntrac`` folder."""
    return write_table1(folder, out, "validate_table1_dyntrac", DYNTRAC_SCRIPT, rig="dyntrac")


def _runs(n: int) -> str:
    return f"{n} rig run{'s' if n != 1 else ''}"


def iterate_rows(results: list[dict]) -> list[list[str]]:
    """One row per scenario of the ``iteration.json`` documents ``results`` (in their first order):
    the DLC error (%, mean of the four wheels) of the rig with the original drive, of each target's
    iterated drive with its rig runs, and of the output correction of the original rig run; "-"
    for a target not given."""
    by: dict[str, dict[str, dict]] = {}
    for r in results:
        by.setdefault(r["scenario"], {})[r["target"]] = r["comparison"]
    rows = []
    for name, targets in by.items():
        first = next(iter(targets.values()))
        cells = [case_label(name), f"{100 * first['rig_original_drive']['dlc_error']:+.1f} %"]
        for target in ("displacement", "force"):
            it = targets.get(target, {}).get("rig_iterated_drive")
            cells.append("-" if it is None else f"{100 * it['dlc_error']:+.1f} %, {_runs(it['rig_runs'])}")
        out = first.get("output_corrected")
        cells.append("-" if out is None else f"{100 * out['dlc_error']:+.1f} %, {_runs(out['rig_runs'])}")
        rows.append(cells)
    return rows


def iterate_command(folders: list[pathlib.Path], results: list[dict]) -> str:
    """The ``rigsim iterate`` command of the runs: the duration from the first run's ``drive.csv``
    (its last time), the load-cell noise from its ``iteration.json``."""
    command = "rigsim iterate CASE.toml --target displacement|force --out DIR"
    drive = folders[0] / "drive.csv"
    if drive.is_file():
        last = drive.read_text().rstrip().rsplit("\n", 1)[-1]
        command += f" --duration-s {round(float(last.split(',')[0]), 3):g}"
    if "noise_N" in results[0]:
        command += f" --noise-N {results[0]['noise_N']:g}"
    return command


def write_iterate(folders: list[pathlib.Path], out: pathlib.Path) -> pathlib.Path:
    """``out/iterate_comparison.md`` from each ``folder/iteration.json``."""
    sources = [f / "iteration.json" for f in folders]
    results = [json.loads(s.read_text()) for s in sources]
    note = ("DLC error against the road test, mean of the four wheels, on the samples where the output correction "
            "has settled; rig forces with the load cells' noise. Rig runs: the original drive's, the "
            "identification's and one per drive update for the iteration; the output correction corrects the "
            "original drive's run (the rig's identification before the test not counted).")
    return write_results_page(out, "iterate_comparison", "Input correction against output correction",
                              ITERATE_HEADER, iterate_rows(results), iterate_command(folders, results),
                              max(_date_of(s) for s in sources), note, ITERATE_SCRIPT)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--paper", type=pathlib.Path, default=pathlib.Path("out/paper"),
                    help="output folder of rigsim paper (default out/paper)")
    ap.add_argument("--validate", type=pathlib.Path, default=pathlib.Path("out/validate"),
                    help="output folder of rigsim validate (default out/validate)")
    ap.add_argument("--paper-dyntrac", type=pathlib.Path, default=None, metavar="DIR",
                    help="output folder of rigsim paper --rig dyntrac [--model] (paper_table2_dyntrac.md)")
    ap.add_argument("--validate-dyntrac", type=pathlib.Path, default=None, metavar="DIR",
                    help="output folder of rigsim validate --rig dyntrac (validate_table1_dyntrac.md)")
    ap.add_argument("--readme", type=pathlib.Path, default=None, metavar="README.md",
                    help="also rewrite the Table 2 block of this README from --paper (a run with --model)")
    ap.add_argument("--iterate", type=pathlib.Path, nargs="+", default=[], metavar="DIR",
                    help="output folders of rigsim iterate, one per case and target (default none)")
    ap.add_argument("--out", type=pathlib.Path, default=ROOT / "docs" / "results",
                    help="folder of the written tables (default docs/results of this repository)")
    args = ap.parse_args(argv)
    written = 0
    jobs = [(args.paper, "paper.json", write_table2), (args.paper, "paper.json", write_damage),
            (args.validate, "validate.json", write_table1)]
    if args.paper_dyntrac is not None:
        jobs.append((args.paper_dyntrac, "paper.json", write_table2_dyntrac))
    if args.validate_dyntrac is not None:
        jobs.append((args.validate_dyntrac, "validate.json", write_table1_dyntrac))
    for folder, fname, write in jobs:
        if not (folder / fname).is_file():
            print(f"{folder / fname}: no such file, its table is not written", file=sys.stderr)
            continue
        print(f"wrote {write(folder, args.out)}")
        written += 1
    if args.readme is not None and (args.paper / "paper.json").is_file():
        print(f"wrote {write_readme_table(args.paper, args.readme)}")
    if args.iterate:
        missing = [str(f / "iteration.json") for f in args.iterate if not (f / "iteration.json").is_file()]
        if missing:
            print(f"{', '.join(missing)}: no such file, the iteration's table is not written", file=sys.stderr)
        else:
            print(f"wrote {write_iterate(args.iterate, args.out)}")
            written += 1
    return 0 if written else 1


if __name__ == "__main__":
    sys.exit(main())
