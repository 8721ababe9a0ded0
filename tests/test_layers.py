"""The layering of DEVELOPERS' design card, checked on the sources (ast, every import anywhere
in a module, including imports inside functions):

- correction/ imports none of mjcf, hydraulics, scenarios (it corrects real rig data on a
  machine without a simulator) and no mujoco or rerun;
- hydraulics/ may read mjcf but not scenarios or correction; only hydraulics/bridge.py
  imports mujoco;
- mjcf/ imports none of the other three;
- inside scenarios/, the floors: core imports nothing above it; records (correcting a rig's
  records: the API, the model correction, the recorded identification) imports core; review
  imports core; studies import core, records and review; only cli sits on top;
- only scenarios/review/recording.py and scenarios/review/blueprint.py import rerun;
- rigsim/ (the top package) imports none of them: errors.py (the one error class every layer
  raises) imports nothing, __init__.py loads the lab's names on first use; __main__.py is the
  command, on top of everything;
- no import circle between any two modules of the project, and no module over 420 lines;
- one home each: a concept's name (the identification settings, the one NRMSE, the lab's linear
  correction, the model correction's fallback limits, the band limit's defaults, the goals) is
  defined in one module of the package or the benchmarks, and the studies' comparison of methods
  is neither defined nor imported in scenarios/records (the lab's floor).
"""

from __future__ import annotations

import ast
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("mjcf", "hydraulics", "correction", "scenarios")
MAX_LINES = 420


def _module_name(path: pathlib.Path) -> str:
    """The installed name: the design card's folders are sub-packages of ``rigsim``."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    if parts[0] != "rigsim":
        parts.insert(0, "rigsim")
    return ".".join(parts)


def _import_targets(path: pathlib.Path) -> set[str]:
    """Full dotted names imported anywhere in the module (relative imports resolved)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    inside = path.resolve().is_relative_to(ROOT)
    name = _module_name(path) if inside else path.stem
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            for alias in node.names:  # "from pkg import module" imports pkg.module; else a name of pkg
                names.add(f"{module}.{alias.name}")
    return names


def _imports(path: pathlib.Path) -> set[str]:
    """Package names imported anywhere in the module: rigsim's sub-packages by their own name
    (``rigsim.scenarios.core.run`` is ``scenarios``), any other by its top level."""
    names = set()
    for n in filter(None, _import_targets(path)):
        parts = n.split(".")
        names.add(parts[1] if parts[0] == "rigsim" and len(parts) > 1 else parts[0])
    return names


def _modules(package: str):
    return sorted((ROOT / package).rglob("*.py"))


def _project_graph() -> dict[str, set[str]]:
    modules = {_module_name(p): p for pkg in (*PACKAGES, "rigsim") for p in _modules(pkg)}
    graph = {}
    for name, path in modules.items():
        deps = set()
        for target in _import_targets(path):
            # the longest project module that the imported name is or lies in
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if target and target != name:
                deps.add(target)
        graph[name] = deps
    return graph


def _find_circle(graph: dict[str, set[str]]) -> list[str] | None:
    done, stack = set(), []

    def visit(node):
        if node in stack:
            return stack[stack.index(node):] + [node]
        if node in done:
            return None
        stack.append(node)
        for dep in sorted(graph.get(node, ())):
            found = visit(dep)
            if found:
                return found
        stack.pop()
        done.add(node)
        return None

    for node in sorted(graph):
        found = visit(node)
        if found:
            return found
    return None


FORBIDDEN = {
    "correction": {"mjcf", "hydraulics", "scenarios", "mujoco", "rerun"},
    "hydraulics": {"scenarios", "correction", "rerun"},
    "mjcf": {"hydraulics", "correction", "scenarios", "rerun"},
    # the top package's modules: errors.py imports nothing; __init__.py loads its names on use
    "rigsim": {"mjcf", "hydraulics", "correction", "scenarios", "mujoco", "rerun", "numpy", "scipy"},
}


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_imports_respect_the_layers(package):
    for path in _modules(package):
        if path.relative_to(ROOT).as_posix() == "rigsim/__main__.py":  # python -m rigsim: the command, on top
            continue
        bad = _imports(path) & FORBIDDEN[package]
        assert not bad, f"{path.relative_to(ROOT)} imports {sorted(bad)}"


#: scenarios' floors: what each sub-package may import of the others.
SCENARIO_FLOORS = {
    "rigsim.scenarios.core": set(),
    "rigsim.scenarios.records": {"rigsim.scenarios.core"},
    "rigsim.scenarios.review": {"rigsim.scenarios.core"},
    "rigsim.scenarios.studies": {"rigsim.scenarios.core", "rigsim.scenarios.records", "rigsim.scenarios.review"},
    "rigsim.scenarios.cli": {"rigsim.scenarios.core", "rigsim.scenarios.records", "rigsim.scenarios.review", "rigsim.scenarios.studies"},
}


def test_scenarios_floors():
    graph = _project_graph()
    for module, deps in graph.items():
        floor = next((f for f in SCENARIO_FLOORS if module == f or module.startswith(f + ".")), None)
        if floor is None:
            continue
        for dep in deps:
            other = next((f for f in SCENARIO_FLOORS if dep == f or dep.startswith(f + ".")), None)
            if other is not None and other != floor:
                assert other in SCENARIO_FLOORS[floor], f"{module} ({floor}) imports {dep} ({other})"


def test_no_import_circle_in_the_project():
    circle = _find_circle(_project_graph())
    assert circle is None, "import circle: " + " -> ".join(circle)


def test_the_circle_finder_can_fail():
    assert _find_circle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _find_circle({"a": {"b"}, "b": set()}) is None


def test_no_module_is_too_large():
    big = {str(p.relative_to(ROOT)): n for pkg in PACKAGES for p in _modules(pkg)
           if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert not big, f"modules over {MAX_LINES} lines: {big}"


def test_no_private_names_imported_across_modules():
    """A name that starts with "_" is its module's own: no other module imports it."""
    offenders = []
    for pkg in PACKAGES:
        for path in _modules(pkg):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.ImportFrom):
                    offenders += [f"{path.relative_to(ROOT)}: {a.name}" for a in node.names
                                  if a.name.startswith("_") and a.name != "__version__"]
    assert not offenders, offenders


def test_the_floors_checker_can_fail(monkeypatch):
    """A record module that imported a study would be refused."""
    graph = {"rigsim.scenarios.records.api": {"rigsim.scenarios.studies.scoring"}, "rigsim.scenarios.studies.scoring": set()}
    monkeypatch.setattr(sys.modules[__name__], "_project_graph", lambda: graph)
    with pytest.raises(AssertionError, match=r"rigsim.scenarios.records.api \(rigsim.scenarios.records\) imports"):
        test_scenarios_floors()


def test_only_the_bridge_imports_mujoco_in_hydraulics():
    users = {p.name for p in _modules("hydraulics") if "mujoco" in _imports(p)}
    assert users == {"bridge.py"}


def test_only_the_recording_modules_import_rerun():
    users = {str(p.relative_to(ROOT)) for package in PACKAGES for p in _modules(package) if "rerun" in _imports(p)}
    assert users == {"scenarios/review/recording.py", "scenarios/review/blueprint.py"}


def test_the_checker_sees_imports_inside_functions(tmp_path):
    """The check can fail: a function-level import is found."""
    p = tmp_path / "m.py"
    p.write_text("def f():\n    from rigsim.scenarios.core.run import run\n    import rerun as rr\n")
    assert _imports(p) == {"scenarios", "rerun"}


#: Each concept's name and the one module that defines it (a def, a class or an assignment, at any
#: depth of any module of the package or of benchmarks/).
ONE_HOME = {
    "IDENT_SKIP_S": "rigsim.scenarios.core.drive",
    "IDENT_MIN_S": "rigsim.scenarios.core.drive",
    "nrmse": "rigsim.correction.metrics.dlc",
    "dynamic_error": "rigsim.correction.input.convergence",
    "linear_correction": "rigsim.scenarios.records.output",
    "BAND_LOWPASS": "rigsim.correction.output.lowpass",
    "BAND_MODE": "rigsim.correction.output.lowpass",
    "DIFFERENTIAL_LIMIT": "rigsim.scenarios.records.model.fallback",
    "HYBRID_LIMIT": "rigsim.scenarios.records.model.fallback",
    "OUTLIER_RATIO": "rigsim.scenarios.records.model.fallback",
    "DLC_GOAL": "rigsim.scenarios.records.model.fallback",
    "fallback_reason": "rigsim.scenarios.records.model.fallback",
    "DLC_GOOD": "rigsim.scenarios.studies.model_suite.goals",
    "DLC_ALL": "rigsim.scenarios.studies.model_suite.goals",
    "SHARE": "rigsim.scenarios.studies.model_suite.goals",
    "FLOOR_RATIO": "rigsim.scenarios.studies.model_suite.goals",
    "ABOVE_LINEAR": "rigsim.scenarios.studies.model_suite.goals",
}
#: The studies' comparison of correction methods (scenarios/studies/scoring.py, correction_score.py).
METHOD_COMPARISON = {"Method", "PAPER", "BEST", "METHODS", "method_named", "NOISE_N", "score_correction", "band_rows"}


def _defined(path: pathlib.Path) -> set[str]:
    """Names a module defines: functions and classes at any depth, names assigned at module level
    (a dataclass's field or a function's local variable is not a home; imports are not definitions)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    names = {n.name for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))}
    todo = list(tree.body)
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            for target in node.targets if isinstance(node, ast.Assign) else [node.target]:
                names.update(n.id for n in ast.walk(target) if isinstance(n, ast.Name))
        elif isinstance(node, (ast.If, ast.Try, ast.With, ast.For)):  # module level, conditionally
            todo += [c for c in ast.iter_child_nodes(node) if isinstance(c, ast.stmt)]
            todo += [c for h in getattr(node, "handlers", ()) for c in h.body]
    return names


def _homes(names, paths) -> dict[str, list[str]]:
    """Per name, the modules (installed names; a benchmark by its file) that define it."""
    homes = {n: [] for n in names}
    for path in paths:
        inside = path.resolve().is_relative_to(ROOT / "benchmarks") or not path.resolve().is_relative_to(ROOT)
        module = f"benchmarks/{path.name}" if inside else _module_name(path)
        for n in _defined(path) & set(names):
            homes[n].append(module)
    return homes


def _sources():
    return [p for pkg in (*PACKAGES, "rigsim") for p in _modules(pkg)] + sorted((ROOT / "benchmarks").glob("*.py"))


def test_each_concept_has_one_home():
    homes = _homes(ONE_HOME, _sources())
    wrong = {n: where for n, where in homes.items() if where != [ONE_HOME[n]]}
    assert not wrong, f"defined elsewhere or more than once (expected {ONE_HOME}): {wrong}"


def _method_comparison_in(paths) -> list[str]:
    """Where the modules define or import a name of :data:`METHOD_COMPARISON`, one line each."""
    offenders = []
    for path in paths:
        named = {t.rpartition(".")[2] for t in _import_targets(path)} | _defined(path)
        offenders += [f"{path.name}: {n}" for n in sorted(named & METHOD_COMPARISON)]
    return offenders


def test_the_lab_floor_holds_none_of_the_studies_method_comparison():
    """scenarios/records neither defines nor imports Method, PAPER, BEST, ... (studies' code)."""
    offenders = _method_comparison_in(_modules("scenarios/records"))
    assert not offenders, offenders


def test_the_one_home_checker_can_fail(tmp_path):
    """A second nrmse, or an assigned IDENT_SKIP_S, in any module is found; a local variable is none."""
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("def nrmse(x, r):\n    IDENT_SKIP_S = 1\n    return 0\n")
    b.write_text("import numpy\nIDENT_SKIP_S, x = 3.0, 1\nfrom rigsim.correction.metrics.dlc import nrmse\n")
    assert _homes({"nrmse", "IDENT_SKIP_S"}, [a, b]) == {"nrmse": ["benchmarks/a.py"], "IDENT_SKIP_S": ["benchmarks/b.py"]}
    c = tmp_path / "c.py"
    c.write_text("def f():\n    from rigsim.scenarios.studies.scoring import BEST\n    return BEST\n")
    assert _method_comparison_in([a, c]) == ["c.py: BEST"]
