"""rigsim.scenarios.studies.results_page and benchmarks/docs_tables.py: a table of measured results as a
Markdown file the documentation includes.

Expected values: the table and the configuration line the helper is given (the version, platform,
CPU count and Python of this interpreter), and the rows of a small fake ``paper.json`` /
``validate.json`` built with the keys the real ones have (``rigsim paper`` / ``rigsim validate``).
"""

from __future__ import annotations

import datetime
import json
import os
import pathlib
import platform
import subprocess
import sys

import pytest

from rigsim.scenarios.studies.paper.table import PAPER_TABLE2
from rigsim.scenarios.studies.results_page import (
    configuration_line,
    markdown_table,
    script_command,
    write_output_page,
    write_results_page,
)

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture()
def docs_tables(load_benchmark):
    return load_benchmark("docs_tables")


def test_the_helper_writes_title_table_and_configuration_line(tmp_path):
    path = write_results_page(tmp_path / "results", "demo", "A demo table", ("case", "DLC"),
                              [["a", "0.1000"], ["b", "0.2000"]], "rigsim demo --out DIR",
                              date=datetime.date(2026, 1, 2), note="DLC = std/mean.")
    assert path == tmp_path / "results" / "demo.md"
    text = path.read_text()
    lines = text.splitlines()
    assert "**A demo table**" in lines
    assert "| case | DLC |\n| --- | --- |\n| a | 0.1000 |\n| b | 0.2000 |\n" in text
    assert "DLC = std/mean." in lines
    cpus = os.cpu_count()
    assert lines[-1] == (f"Measured by `rigsim demo --out DIR` on 2026-01-02, rigsim {_version()}, "
                         f"{platform.system()} {platform.machine()}, {cpus} CPU{'s' if cpus != 1 else ''}, "
                         f"Python {platform.python_version()}.")
    assert not list((tmp_path / "results").glob("*.tmp*")), "no temporary file left behind"


def test_the_helper_writes_a_command_and_its_output(tmp_path):
    """Each command after ``$ `` (its further lines after ``> ``, as a terminal shows a
    here-document), the output verbatim (trailing blank lines dropped), in one text block; an
    output holding a fence gets a longer one."""
    path = write_output_page(tmp_path, "demo_out", ["rigsim demo", "python - <<'EOF'\n...\nEOF"],
                             "line 1\n  line 2\n\n", "python benchmarks/demo.py", date=datetime.date(2026, 1, 2))
    text = path.read_text()
    assert text.startswith("<!-- written by `python benchmarks/demo.py`: do not edit by hand -->\n\n")
    assert "```text\n$ rigsim demo\n$ python - <<'EOF'\n> ...\n> EOF\nline 1\n  line 2\n```\n" in text
    assert text.splitlines()[-1].startswith("Measured by `python benchmarks/demo.py` on 2026-01-02, rigsim ")
    fenced = write_output_page(tmp_path, "fenced", ["cat x.md"], "```\nx\n```", "c", title="T").read_text()
    assert "**T**" in fenced and "````text\n$ cat x.md\n```\nx\n```\n````\n" in fenced


def _version():
    from importlib.metadata import version

    return version("rigsim")


def test_configuration_line_defaults_to_today():
    assert f" on {datetime.date.today().isoformat()}, rigsim " in configuration_line("x")


def test_script_command_names_the_script_and_its_arguments():
    assert script_command("/any/where/benchmarks/generalization.py", ["--cases", "4"]) == \
        "python benchmarks/generalization.py --cases 4"
    assert script_command(pathlib.Path("benchmarks/step_rate.py"), []) == "python benchmarks/step_rate.py"
    assert script_command("benchmarks/x.py", ["--only", "gen01 gen02"]) == "python benchmarks/x.py --only 'gen01 gen02'"
    # where the page goes is not what was measured
    assert script_command("benchmarks/x.py", ["--results", "/tmp/r", "--n", "2", "--results=/tmp/s"]) == \
        "python benchmarks/x.py --n 2"


def test_a_row_of_the_wrong_width_is_refused():
    with pytest.raises(ValueError, match="row 0 has 1 cells"):
        markdown_table(("a", "b"), [["only one"]])


def test_the_helper_is_light():
    """Importing it loads no numerical or simulation package (it is no part of a hot path)."""
    code = ("import sys, rigsim.scenarios.studies.results_page; "
            "print(sorted(m for m in ('numpy', 'scipy', 'mujoco', 'matplotlib') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


CASE_KEYS = ("dlc_road", "dlc_rig", "dlc_corrected_paper", "dlc_corrected", "dlc_road_lowpassed", "nrmse_corrected",
             "dlc_road_lowpassed_paper")
#: Damage figures of a case: stress factors (1) and damage-equivalent loads (N) of road, rig, corrected.
DAMAGE = {"stress_factor_road": 1.25, "stress_factor_rig": 1.125, "stress_factor_corrected": 1.2,
          "del_road_N": 20000.0, "del_rig_N": 15000.0, "del_corrected_N": 19000.0}


def _fake_paper(folder: pathlib.Path, **extra) -> None:
    """A paper.json with rigsim paper's structure (two cases) and one case's road result.json;
    ``extra``: further top-level keys (``configuration``, ``model_correction``)."""
    cases = []
    for k, name in enumerate(("paper-medium-72kmh-6360kg", "paper-high-48kmh-3640kg")):
        case = {key: 0.1 + 0.01 * k + 0.001 * i for i, key in enumerate(CASE_KEYS)}
        case.update(case=name, noise_N=100.0, paper=dict(PAPER_TABLE2[name]), **DAMAGE)
        cases.append(case)
    folder.mkdir()
    (folder / "paper.json").write_text(json.dumps({"cases": cases, "methods": {}, "note": "", **extra}))
    run = folder / cases[0]["case"] / "road"
    run.mkdir(parents=True)
    (run / "result.json").write_text(json.dumps({"samples": 20001, "rate_hz": 1000.0}))


def _fake_validate(folder: pathlib.Path) -> None:
    folder.mkdir()
    table1 = {"road_test": 0.25, "rig_test": 0.2, "linearized_model": 0.199, "linearized_model_eq4": 0.19,
              "linearized_model_route2_mimo": 0.1995, "linearized_vs_rig_pct": -0.5,
              "linearized_eq4_vs_rig_pct": -5.0, "linearized_route2_mimo_vs_rig_pct": -0.25}
    (folder / "validate.json").write_text(json.dumps({"duration_s": 20.0, "ident_duration_s": 40.0, "table1": table1}))


def test_docs_tables_writes_the_rows_of_paper_and_validate(tmp_path, docs_tables):
    _fake_paper(tmp_path / "paper")
    _fake_validate(tmp_path / "validate")
    out = tmp_path / "results"
    assert docs_tables.main(["--paper", str(tmp_path / "paper"), "--validate", str(tmp_path / "validate"),
                                "--out", str(out)]) == 0
    table2 = (out / "paper_table2.md").read_text().splitlines()
    # The paper's own corrected 0.0994 lies above its road 0.0985 (^); 0.1794 below 0.1912.
    assert ("| medium, 72 km/h, 6360 kg | 0.1000 (0.0985) | 0.1010 (0.0854) | 0.1020 (0.0994^) | 0.1060 | 0.1030 "
            "| 0.1040 | 0.105 |") in table2
    assert ("| high, 48 km/h, 3640 kg | 0.1100 (0.1912) | 0.1110 (0.1497) | 0.1120 (0.1794) | 0.1160 | 0.1130 "
            "| 0.1140 | 0.115 |") in table2
    assert table2[-1].startswith("Measured by `rigsim paper --out DIR --duration-s 20 --noise-N 100` on ")
    # 1.125 / 1.25 - 1 = -10.0 %, 1.2 / 1.25 - 1 = -4.0 %; 15 / 20 - 1 = -25.0 %, 19 / 20 - 1 = -5.0 %
    damage = (out / "paper_damage.md").read_text().splitlines()
    assert ("| medium, 72 km/h, 6360 kg | 1.2500 | 1.1250 (-10.0 %) | 1.2000 (-4.0 %) | 20.00 kN | 15.00 kN (-25.0 %) "
            "| 19.00 kN (-5.0 %) |") in damage
    table1 = (out / "validate_table1.md").read_text().splitlines()
    assert "| this model | 0.2500 | 0.2000 | 0.1990 (-0.50 %) | 0.1900 (-5.00 %) | 0.1995 (-0.25 %) |" in table1
    assert "| paper | 0.2105 | 0.1754 (nonlinear model 0.1748) | 0.1724 (-1.71 %) |  |  |" in table1
    assert table1[-1].startswith("Measured by `rigsim validate --out DIR --duration-s 20 --ident-duration-s 40` on ")


def test_docs_tables_writes_the_dyntrac_table_with_the_model_column(tmp_path, docs_tables):
    model = [{"case": "paper-medium-72kmh-6360kg", "mean": {"dlc": 0.0979, "dlc_error": -0.0091, "nrmse": 0.048}}]
    _fake_paper(tmp_path / "paper", configuration="dyntrac", model_correction=model)
    folder = tmp_path / "paper"
    result = json.loads((folder / "paper.json").read_text())
    result["cases"][0]["dlc_corrected_paper"] = 0.2  # above its ceiling 0.106: marked
    (folder / "paper.json").write_text(json.dumps(result))
    out = tmp_path / "results"
    assert docs_tables.main(["--paper", str(tmp_path / "none"), "--validate", str(tmp_path / "none"),
                                "--paper-dyntrac", str(folder), "--out", str(out)]) == 0
    lines = (out / "paper_table2_dyntrac.md").read_text().splitlines()
    assert "| 0.2000^ (0.0994^) | 0.1060 |" in next(x for x in lines if x.startswith("| medium"))
    assert next(x for x in lines if x.startswith("| medium")).endswith("| 0.0979 (-0.9 %) | 0.048 |")
    assert next(x for x in lines if x.startswith("| high")).endswith("| - | - |")
    assert lines[-1].startswith("Measured by `rigsim paper --out DIR --rig dyntrac --model --duration-s 20 ")


def test_docs_tables_skips_a_missing_folder(tmp_path, capsys, docs_tables):
    _fake_paper(tmp_path / "paper")
    out = tmp_path / "results"
    assert docs_tables.main(["--paper", str(tmp_path / "paper"), "--validate", str(tmp_path / "none"),
                                "--out", str(out)]) == 0
    assert (out / "paper_table2.md").is_file() and not (out / "validate_table1.md").exists()
    assert "validate.json: no such file" in capsys.readouterr().err
    assert docs_tables.main(["--paper", str(tmp_path / "none"), "--validate", str(tmp_path / "none"),
                                "--out", str(out)]) == 1


def test_the_pages_files_are_the_scripts():
    """docs/validation.md includes the files docs_tables.py writes, and each ends in its
    configuration line."""
    page = (ROOT / "docs" / "validation.md").read_text()
    for name in ("paper_table2", "paper_damage", "validate_table1"):
        assert f"```{{include}} results/{name}.md" in page
        assert (ROOT / "docs" / "results" / f"{name}.md").read_text().splitlines()[-1].startswith("Measured by `rigsim ")


def _fake_iteration(folder: pathlib.Path, target: str, iterated: float, runs: int) -> None:
    """An iteration.json with rigsim iterate's keys (DLC errors, 1) and its drive.csv (20 s at 1 kHz)."""
    folder.mkdir()
    comparison = {"road": {"dlc": 0.25, "dlc_error": 0.0, "nrmse_vs_road": 0.0, "rig_runs": 0},
                  "rig_original_drive": {"dlc": 0.2, "dlc_error": -0.2, "nrmse_vs_road": 0.3, "rig_runs": 1},
                  "rig_iterated_drive": {"dlc": 0.25, "dlc_error": iterated, "nrmse_vs_road": 0.02, "rig_runs": runs},
                  "output_corrected": {"dlc": 0.245, "dlc_error": -0.02, "nrmse_vs_road": 0.1, "rig_runs": 1}}
    (folder / "iteration.json").write_text(json.dumps({"scenario": "paper-high-72kmh-3640kg", "target": target,
                                                       "comparison": comparison, "noise_N": 100.0}))
    (folder / "drive.csv").write_text("time_s,drive_fl_m\n0,0\n19.999,0.001\n20,0.002\n")


def test_docs_tables_writes_the_iteration_table(tmp_path, docs_tables):
    _fake_iteration(tmp_path / "disp", "displacement", -0.007, 6)
    _fake_iteration(tmp_path / "force", "force", 0.004, 8)
    out = tmp_path / "results"
    assert docs_tables.main(["--paper", str(tmp_path / "none"), "--validate", str(tmp_path / "none"),
                                "--iterate", str(tmp_path / "disp"), str(tmp_path / "force"), "--out", str(out)]) == 0
    lines = (out / "iterate_comparison.md").read_text().splitlines()
    assert lines[0] == "<!-- written by `python benchmarks/docs_tables.py --iterate DIR ...`: do not edit by hand -->"
    assert ("| high, 72 km/h, 3640 kg | -20.0 % | -0.7 %, 6 rig runs | +0.4 %, 8 rig runs | -2.0 %, 1 rig run |"
            in lines)
    assert lines[-1].startswith("Measured by `rigsim iterate CASE.toml --target displacement|force --out DIR "
                                "--duration-s 20 --noise-N 100` on ")


def test_every_results_file_is_included_and_every_include_exists():
    """docs/results holds only files a page includes, each saying which command writes it, and every
    include of a page names a file that is there."""
    docs = ROOT / "docs"
    pages = {p: p.read_text() for p in list(docs.glob("*.md")) + list(docs.glob("guide/*.md"))}
    included = set()
    for page, text in pages.items():
        for line in text.splitlines():
            if line.startswith("```{include}") and "results/" in line:
                target = (page.parent / line.split(maxsplit=1)[1].strip()).resolve()
                assert target.is_file(), f"{page.name} includes {target.name}, which is missing"
                included.add(target)
    for path in sorted((docs / "results").glob("*.md")):
        assert path.resolve() in included, f"no page includes docs/results/{path.name}"
        assert path.read_text().startswith("<!-- written by `"), f"{path.name} does not say what writes it"


def test_docs_tables_rewrites_the_readme_block_only(tmp_path, docs_tables):
    model = [{"case": "paper-medium-72kmh-6360kg", "mean": {"dlc": 0.0999, "dlc_error": 0.001, "nrmse": 0.009}}]
    _fake_paper(tmp_path / "paper", model_correction=model)
    mod = docs_tables
    readme = tmp_path / "README.md"
    readme.write_text(f"# x\n\nbefore\n{mod.README_BEGIN}\nold table\n{mod.README_END}\nafter\n")
    assert mod.main(["--paper", str(tmp_path / "paper"), "--validate", str(tmp_path / "none"),
                     "--readme", str(readme), "--out", str(tmp_path / "results")]) == 0
    text = readme.read_text()
    assert text.startswith("# x\n\nbefore\n") and text.endswith(f"{mod.README_END}\nafter\n")
    assert "old table" not in text
    assert ("| medium, 72 km/h, 6360 kg | 0.1000 (0.0985) | 0.1010 (0.0854) | 0.1020 (0.0994) | 0.1030 "
            "| 0.0999 (+0.1 % from road) | 0.105 / 0.009 |") in text
    assert "| high, 48 km/h, 3640 kg |" in text and text.count("| - |") == 1 and "0.115 / - |" in text  # no model row
    assert "Measured by `rigsim paper --out DIR --model --duration-s 20 --noise-N 100` on " in text
    readme.write_text("# no markers\n")
    with pytest.raises(SystemExit, match="needs one line"):
        mod.write_readme_table(tmp_path / "paper", readme)
