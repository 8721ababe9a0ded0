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
- no import circle between any two modules of the project, and no module over 420 lines.
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
