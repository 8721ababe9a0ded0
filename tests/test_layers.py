"""The layering of DEVELOPERS' design card, checked on the sources (ast, every import anywhere
in a module, including imports inside functions):

- correction/ imports none of mjcf, hydraulics, scenarios (it corrects real rig data on a
  machine without a simulator) and no mujoco or rerun;
- hydraulics/ may read mjcf but not scenarios or correction; only hydraulics/bridge.py
  imports mujoco;
- mjcf/ imports none of the other three;
- only scenarios/recording.py and scenarios/blueprint.py import rerun.
"""

from __future__ import annotations

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _imports(path: pathlib.Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def _modules(package: str):
    return sorted((ROOT / package).glob("*.py"))


FORBIDDEN = {
    "correction": {"mjcf", "hydraulics", "scenarios", "mujoco", "rerun"},
    "hydraulics": {"scenarios", "correction", "rerun"},
    "mjcf": {"hydraulics", "correction", "scenarios", "rerun"},
}


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_imports_respect_the_layers(package):
    for path in _modules(package):
        bad = _imports(path) & FORBIDDEN[package]
        assert not bad, f"{path.relative_to(ROOT)} imports {sorted(bad)}"


def test_only_the_bridge_imports_mujoco_in_hydraulics():
    users = {p.name for p in _modules("hydraulics") if "mujoco" in _imports(p)}
    assert users == {"bridge.py"}


def test_only_the_recording_modules_import_rerun():
    users = {
        str(p.relative_to(ROOT))
        for package in ("mjcf", "hydraulics", "correction", "scenarios")
        for p in _modules(package)
        if "rerun" in _imports(p)
    }
    assert users == {"scenarios/recording.py", "scenarios/blueprint.py"}


def test_the_checker_sees_imports_inside_functions(tmp_path):
    """The check can fail: a function-level import is found."""
    p = tmp_path / "m.py"
    p.write_text("def f():\n    from scenarios.runner import run\n    import rerun as rr\n")
    assert _imports(p) == {"scenarios", "rerun"}
