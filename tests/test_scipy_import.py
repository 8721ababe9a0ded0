"""scenarios.scipy_import: scipy.signal imported without SciPy re-parsing its docstrings.

The reference is SciPy itself in a fresh process without the hook (``RIGSIM_SCIPY_DOCS=1``): the
functions' docstrings keep all of their own text (only SciPy's appended array-API note is
missing) and the hook swaps nothing but the docstring parser of ``scipy._lib._array_api``.
"""

from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]

PROBE = r"""
import json, sys
import scenarios  # installs the hook
import scipy.signal as s
import scipy._lib._array_api as a
docs = {n: getattr(s, n).__doc__ for n in ("butter", "sosfiltfilt", "welch", "freqz")}
print(json.dumps({"parser": a.FunctionDoc.__module__ + "." + a.FunctionDoc.__name__, "docs": docs}))
"""


def _probe(**env) -> dict:
    e = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    e.pop("RIGSIM_SCIPY_DOCS", None)
    e.update(env)
    out = subprocess.run([sys.executable, "-c", PROBE], env=e, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_hook_keeps_every_docstring_and_changes_only_the_parser():
    fast, full = _probe(), _probe(RIGSIM_SCIPY_DOCS="1")
    if full["parser"] == fast["parser"]:  # a SciPy without the parsing decorator: nothing to do
        return
    assert fast["parser"] == "scenarios.scipy_import._KeepDoc"
    for name, doc in fast["docs"].items():
        # SciPy's version is the same text, re-flowed by its parser, plus a note; compare words
        words = doc.split()
        assert words, name
        assert " ".join(words[:12]) in " ".join(full["docs"][name].split()), name
