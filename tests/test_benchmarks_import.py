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
    """A script (it runs as ``__main__``) has a ``main()``; a helper module of the scripts (no
    ``__main__`` block, e.g. model_correction_tables.py) must be imported by one of them."""
    spec = importlib.util.spec_from_file_location(f"benchmark_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    if 'if __name__ == "__main__":' in path.read_text():
        assert callable(getattr(module, "main", None)), f"{path.name} has no main()"
    else:
        users = [b.name for b in BENCHMARKS if b != path and (f"import {path.stem}" in b.read_text()
                                                              or f"from {path.stem} import" in b.read_text())]
        assert users, f"{path.name} is neither a script (no __main__ block) nor imported by one"
