"""rigsim.scenarios.scipy_import: scipy.signal imported without SciPy re-parsing its docstrings.

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

ROOT = pathlib.Path(__file__).resolve().parents[2]

PROBE = r"""
import json, sys
import rigsim.scenarios  # installs the hook
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
    assert fast["parser"] == "rigsim.scenarios.scipy_import._KeepDoc"
    for name, doc in fast["docs"].items():
        # SciPy's version is the same text, re-flowed by its parser, plus a note; compare words
        words = doc.split()
        assert words, name
        assert " ".join(words[:12]) in " ".join(full["docs"][name].split()), name


STATS_PROBE = r"""
import json, sys
import numpy as np
import rigsim.scenarios  # installs the hook
import scipy.signal as s
deferred = "scipy.stats" not in sys.modules
x = np.sin(np.linspace(0.0, 20.0, 500)) + 0.1 * np.cos(np.linspace(0.0, 130.0, 500))
peaks = s.find_peaks_cwt(x, np.arange(1, 10)).tolist()  # the one use of scipy.stats in scipy.signal
import scipy.stats
print(json.dumps({"deferred": deferred, "peaks": peaks, "real": scipy.stats.__name__ == "scipy.stats"
                  and hasattr(scipy.stats, "norm"), "loaded_after": "scipy.stats" in sys.modules}))
"""


def test_scipy_stats_waits_until_something_uses_it():
    """Importing scipy.signal through rigsim does not import scipy.stats (a run never uses it);
    find_peaks_cwt, the one function of scipy.signal that needs it, gives SciPy's own result
    (the reference: the same call in a process without the hook), and ``import scipy.stats``
    afterwards is SciPy's real module."""
    e = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    e.pop("RIGSIM_SCIPY_DOCS", None)

    def probe(**env):
        out = subprocess.run([sys.executable, "-c", STATS_PROBE], env={**e, **env}, capture_output=True,
                             text=True, check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])

    fast, plain = probe(), probe(RIGSIM_SCIPY_DOCS="1")
    assert fast["deferred"] and not plain["deferred"]
    assert fast["peaks"] == plain["peaks"] and len(fast["peaks"]) > 2
    assert fast["real"] and fast["loaded_after"]
