"""The workers' C heap keeps large blocks for reuse (rigsim.scenarios.core.pool.keep_heap_memory).

Dask's nanny starts its workers with ``MALLOC_TRIM_THRESHOLD_=65536``; glibc then serves every
block above 128 KiB with fresh mmap'ed pages, and each chunk of a run pays page faults on every
touch (a sweep case measured 23 % slower). The reference is the kernel's own count of minor page
faults (``getrusage``) over the same allocation pattern, in a subprocess started with that
variable: without the setting every 4 MiB array is faulted in again (~1024 faults each), with it
the heap hands the same pages back.
"""

from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]

SCRIPT = r"""
import ctypes, json, resource, sys
# PR_SET_THP_DISABLE (41): transparent huge pages back a 4 MiB array with 2 faults instead of 1024
# when the kernel has huge pages at hand (measured: 120 faults for 40 arrays), which hides the
# effect; the test counts 4 KiB pages.
ctypes.CDLL(None).prctl(41, 1, 0, 0, 0)
import numpy as np
from rigsim.scenarios.core.pool import keep_heap_memory

def faults(n=40):
    a = np.ones(512 * 1024)  # warm the allocator
    del a
    f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(n):
        a = np.ones(512 * 1024)  # 4 MiB, every page touched
        del a
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0

before = faults()
applied = keep_heap_memory()
after = faults()
print(json.dumps({"before": before, "after": after, "applied": applied}))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_keep_heap_memory_undoes_dasks_trim_threshold():
    env = {**os.environ, "MALLOC_TRIM_THRESHOLD_": "65536",
           "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, check=True)
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["applied"]
    assert r["before"] > 10 * 1024, r  # 40 arrays of 1024 pages, each faulted in afresh (~514 faults each here)
    assert r["after"] < r["before"] / 10, r
