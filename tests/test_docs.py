"""The documentation site builds with warnings as errors: a broken page, a bad cross-reference, a
docstring autodoc cannot parse or a gallery example that fails, fails the suite.

The sources (``docs/``, ``examples/`` and the ``mjcf`` package, whose README the truck page includes and whose models the gallery simulates) are
copied into ``tmp_path`` first, so the build starts from a clean state and writes nothing into the
repository (sphinx-gallery and autosummary generate files beside the sources). The API reference
lists every function and class the correction toolkit and the records API export."""

from __future__ import annotations

import importlib
import inspect
import pathlib
import pkgutil
import re
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
GENERATED = ("_build", "auto_examples", "generated", "sg_execution_times.rst", "__pycache__")


def _documented() -> set[int]:
    """The objects docs/api/index.rst lists (autosummary entries under their currentmodule), by id."""
    found, module = set(), None
    for line in (ROOT / "docs" / "api" / "index.rst").read_text().splitlines():
        if m := re.match(r"\.\. currentmodule:: (\S+)", line):
            module = importlib.import_module(m[1])
        elif (m := re.fullmatch(r"   ([A-Za-z_][\w.]*)", line)) and module is not None:
            obj = module
            for part in m[1].split("."):
                obj = getattr(obj, part, None) or importlib.import_module(f"{obj.__name__}.{part}")
            found.add(id(obj))
    return found


def test_every_public_function_and_class_has_its_reference_entry():
    """Each function and class that a module of correction/ or scenarios.records.api exports
    (``__all__``) has an entry in the API reference, under its own module or a re-export."""
    import correction

    modules = ["scenarios.records.api"] + [m.name for m in pkgutil.walk_packages(correction.__path__, "correction.")]
    documented = _documented()
    missing = set()
    for name in modules:
        module = importlib.import_module(name)
        for public in getattr(module, "__all__", ()):
            obj = getattr(module, public)
            if (inspect.isfunction(obj) or inspect.isclass(obj)) and id(obj) not in documented:
                missing.add(f"{obj.__module__}.{obj.__qualname__}")
    assert not missing, "docs/api/index.rst has no entry for " + ", ".join(sorted(missing))


def test_the_site_builds_with_warnings_as_errors(tmp_path):
    pytest.importorskip("sphinx", reason="the docs stack is not installed (pip install -e '.[docs]')")
    shutil.copytree(ROOT / "docs", tmp_path / "docs", ignore=shutil.ignore_patterns(*GENERATED))
    shutil.copytree(ROOT / "examples", tmp_path / "examples", ignore=shutil.ignore_patterns("__pycache__"))
    # The truck page includes mjcf/README.md; docs/conf.py puts the build's root first on sys.path,
    # so mjcf/ there is the package the gallery's simulations import: the whole package, its XML too.
    shutil.copytree(ROOT / "mjcf", tmp_path / "mjcf", ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp_path / "html"
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-E", "-q", "-b", "html",
                           str(tmp_path / "docs"), str(out)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-4000:]
    for page in ("index", "getting_started", "physics", "validation", "formats", "api/index",
                 "auto_examples/index", "guide/correct"):
        assert (out / f"{page}.html").is_file(), page
