"""Every script in benchmarks/ imports and has a ``main()``: a refactor that renames what a
benchmark uses breaks it here, not months later when someone runs it. Importing runs no
benchmark (each runs from ``main()``).

The benchmarks are scripts on top of the installed package, never a second library: none edits
``sys.path`` (or a child's ``PYTHONPATH``) to find the project, none imports another benchmark
(what two of them share lives in the package), and none uses a private name of the package
(``from x import _y``, ``import x._y``, ``module._y``). The checks read the sources (ast).
"""

from __future__ import annotations

import ast
import pathlib

import pytest

BENCHMARKS = sorted((pathlib.Path(__file__).resolve().parents[1] / "benchmarks").glob("*.py"))
#: The project's packages: a private name of one of them is not a benchmark's to use.
PACKAGES = ("rigsim",)


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def offences(source: str, benchmarks: set[str]) -> list[str]:
    """What in one benchmark's ``source`` breaks the rules above (``benchmarks``: the scripts'
    module names), one line each; empty when nothing does."""
    out = []
    if "sys.path" in source or "PYTHONPATH" in source:
        out.append("edits sys.path or PYTHONPATH to find the project: import the installed package")
    tree = ast.parse(source)
    project = set(PACKAGES) | benchmarks
    bound = set()  # names bound to a module or object of the project by an import
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                top = a.name.split(".")[0]
                if top in benchmarks:
                    out.append(f"imports the benchmark {a.name}")
                if top in project and any(_private(part) for part in a.name.split(".")):
                    out.append(f"imports the private module {a.name}")
                if top in project:
                    bound.add(a.asname or top)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            top = node.module.split(".")[0]
            if top in benchmarks:
                out.append(f"imports from the benchmark {node.module}")
            if top not in project:
                continue
            if any(_private(part) for part in node.module.split(".")):
                out.append(f"imports from the private module {node.module}")
            for a in node.names:
                if _private(a.name):
                    out.append(f"imports the private name {node.module}.{a.name}")
                bound.add(a.asname or a.name)
        elif isinstance(node, ast.ImportFrom) and node.level:
            out.append("a relative import: benchmarks/ is no package")
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in bound \
                and _private(node.attr):
            out.append(f"uses the private name {node.value.id}.{node.attr}")
    return out


@pytest.mark.parametrize("path", BENCHMARKS, ids=lambda p: p.stem)
def test_benchmark_imports_and_has_a_main(path, load_benchmark):
    """Every file of benchmarks/ is a script: it imports (with the package installed, nothing else
    on the path) and has a ``main()`` that its ``__main__`` block runs."""
    module = load_benchmark(path.stem)
    assert 'if __name__ == "__main__":' in path.read_text(), f"{path.name} is no script (no __main__ block)"
    assert callable(getattr(module, "main", None)), f"{path.name} has no main()"


@pytest.mark.parametrize("path", BENCHMARKS, ids=lambda p: p.stem)
def test_benchmark_uses_only_the_public_package(path):
    found = offences(path.read_text(encoding="utf-8"), {p.stem for p in BENCHMARKS})
    assert not found, f"{path.name}: " + "; ".join(found)


def test_the_benchmark_checker_can_fail():
    """Each rule refuses what it is there for, and a clean script passes."""
    names = {"generalization", "step_rate"}
    clean = ("import sys\nimport numpy as np\nfrom rigsim.scenarios.studies.suites import generalization_cases\n"
             "from rigsim.scenarios.studies.paper import compute\nnp._NoValue\nsys._getframe\ncompute.run_job\n"
             "compute.__name__\n")
    assert offences(clean, names) == []
    bad = {
        "import pathlib, sys\nsys.path.insert(0, str(pathlib.Path(__file__).parent))\n": "sys.path",
        'env = {"PYTHONPATH": "."}\n': "PYTHONPATH",
        "from generalization import case_documents\n": "benchmark generalization",
        "import step_rate as sr\n": "benchmark step_rate",
        "from rigsim.scenarios.studies.paper.compute import _run_job\n": "private name rigsim.scenarios.studies.paper.compute._run_job",
        "from rigsim.scenarios.studies.paper import compute\ncompute._case_job()\n": "private name compute._case_job",
        "import rigsim.scenarios.studies.paper.compute as c\nc._scenario\n": "private name c._scenario",
        "import rigsim.scenarios.core._private\n": "private module rigsim.scenarios.core._private",
        "from . import helpers\n": "relative import",
    }
    for source, what in bad.items():
        found = offences(source, names)
        assert any(what in f for f in found), (source, found)
