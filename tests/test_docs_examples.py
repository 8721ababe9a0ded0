"""The Examples of the API reference run as doctests: each name the API page (docs/api/index.rst)
lists has an Examples section in its docstring, and it runs as written and prints what it shows.

They build their records in memory with numpy (no simulation, no file but in a temporary folder)
and take well under 2 s each; the option flags they need are in the examples themselves
(``# doctest: +ELLIPSIS``), so ``python -m doctest`` runs them alike."""

from __future__ import annotations

import doctest
import tempfile
import time

import pytest

from tests.test_docs import api_entries, api_object


@pytest.mark.parametrize("dotted", api_entries())
def test_the_examples_run(dotted, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # their temporary folders land here
    obj = api_object(dotted)
    tests = doctest.DocTestFinder(recurse=False).find(obj, dotted, globs={})
    examples = [t for t in tests if t.examples]
    assert examples and "\n    Examples\n    --------\n" in (obj.__doc__ or ""), f"{dotted} has no Examples"
    runner, report = doctest.DocTestRunner(optionflags=0), []
    start = time.perf_counter()
    for test in examples:
        runner.run(test, out=report.append)  # doctest swaps sys.stdout while it runs: keep the report apart
    took = time.perf_counter() - start
    result = runner.summarize(verbose=False)
    assert result.failed == 0, "".join(report)
    assert took < 20.0, f"the examples of {dotted} took {took:.1f} s: they must not simulate"
