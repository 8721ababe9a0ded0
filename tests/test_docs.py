"""The documentation site builds with warnings as errors: a broken page, a bad cross-reference, a
docstring autodoc cannot parse or a gallery example that fails, fails the suite.

The sources (``docs/``, ``examples/`` and ``mjcf/README.md``, which the truck page includes) are
copied into ``tmp_path`` first, so the build starts from a clean state and writes nothing into the
repository (sphinx-gallery and autosummary generate files beside the sources)."""

from __future__ import annotations

import pathlib
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
GENERATED = ("_build", "auto_examples", "generated", "sg_execution_times.rst", "__pycache__")

pytest.importorskip("sphinx", reason="the docs stack is not installed (pip install -e '.[docs]')")


def test_the_site_builds_with_warnings_as_errors(tmp_path):
    shutil.copytree(ROOT / "docs", tmp_path / "docs", ignore=shutil.ignore_patterns(*GENERATED))
    shutil.copytree(ROOT / "examples", tmp_path / "examples", ignore=shutil.ignore_patterns("__pycache__"))
    (tmp_path / "mjcf").mkdir()
    shutil.copy2(ROOT / "mjcf" / "README.md", tmp_path / "mjcf" / "README.md")
    out = tmp_path / "html"
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-E", "-q", "-b", "html",
                           str(tmp_path / "docs"), str(out)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-4000:]
    for page in ("index", "getting_started", "physics", "validation", "formats", "api/index",
                 "auto_examples/index", "guide/correct"):
        assert (out / f"{page}.html").is_file(), page
