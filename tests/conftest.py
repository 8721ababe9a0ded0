"""Fixtures shared by the tests of every package."""

from __future__ import annotations

import importlib.util
import pathlib

import pytest

#: The benchmark scripts' folder (not a package: its scripts are loaded by path).
BENCHMARKS_DIR = pathlib.Path(__file__).resolve().parents[1] / "benchmarks"


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.fixture()
def one_line():
    """``one_line(stderr) -> str``: the one line a refused command prints, asserting it is one line
    and no traceback."""
    return _one_line


def _load_benchmark(name: str):
    spec = importlib.util.spec_from_file_location(f"benchmark_{name}", BENCHMARKS_DIR / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def load_benchmark():
    """``load_benchmark(name)``: the script ``benchmarks/<name>.py`` imported as the module
    ``benchmark_<name>`` (a fresh import each call)."""
    return _load_benchmark
