"""Every script in benchmarks/ imports: a refactor that renames what a benchmark uses breaks it
here, not months later when someone runs it (sweep_throughput.py and startup.py once did).
Importing runs no benchmark (each runs from ``main()``)."""

from __future__ import annotations

import importlib.util
import pathlib

import pytest

BENCHMARKS = sorted((pathlib.Path(__file__).resolve().parents[1] / "benchmarks").glob("*.py"))


@pytest.mark.parametrize("path", BENCHMARKS, ids=lambda p: p.stem)
def test_benchmark_imports_and_has_a_main(path):
    spec = importlib.util.spec_from_file_location(f"benchmark_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert callable(getattr(module, "main", None)), f"{path.name} has no main()"
