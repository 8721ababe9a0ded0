"""The peak memory of ``rigsim run`` after the run: the statistics work block by block, and freed
arrays go back to the system (the goal: a 600 s rig run under 400 MB, ``benchmarks/run_memory.py``).

The statistics must stay bit for bit what numpy gives on the whole record (``result.json`` is
compared byte for byte between runs): the references are numpy's own ``mean``, ``std`` and the
stress factor's formula on the whole array. Memory is measured by ``tracemalloc`` (numpy reports
its arrays to it) and, for the allocator, by the resident memory of a fresh interpreter; nothing
is timed.
"""

from __future__ import annotations

import pathlib
import platform
import subprocess
import sys
import tracemalloc

import numpy as np
import pytest

from rigsim.correction.metrics.damage import stress_factor
from rigsim.correction.metrics.dlc import BLOCK_ROWS, column_sum, dlc, force_statistics
from rigsim.scenarios.core.memory import MMAP_THRESHOLD_BYTES

ROOT = pathlib.Path(__file__).resolve().parents[3]
SCENARIO = "scenarios/data/paper/high_72kmh_3640kg.toml"


def _forces(n: int, k: int = 4, seed: int = 1) -> np.ndarray:
    """Wheel-force-like record, N: static 30 kN, 5 kN of noise."""
    return np.random.default_rng(seed).normal(3.0e4, 5.0e3, (n, k))


@pytest.mark.parametrize("shape", [(3 * BLOCK_ROWS + 17, 4), (2 * BLOCK_ROWS, 2), (BLOCK_ROWS + 1, 7), (100, 4)])
@pytest.mark.parametrize("block_rows", [1, 5, 1000, BLOCK_ROWS])
def test_column_sum_is_numpys_sum_bit_for_bit(shape, block_rows):
    f = _forces(*shape)
    for fn in (None, np.sin, lambda b: np.square(b - 3.0e4)):
        expected = np.sum(f if fn is None else fn(f), axis=0)
        assert np.array_equal(column_sum(f, fn, block_rows), expected)


@pytest.mark.parametrize("f", [_forces(5000, 1)[:, 0], _forces(5000, 1), np.asfortranarray(_forces(5000)),
                               _forces(5000, 6)[:, :4]], ids=["1-D", "one column", "Fortran", "strided"])
def test_column_sum_of_other_layouts_is_numpys_sum(f):
    assert np.array_equal(column_sum(f, np.sin, 7), np.sum(np.sin(f), axis=0))


def test_block_sums_added_afterwards_are_not_bit_identical():
    """The test above can fail: summing each block on its own and then the block sums (another
    order of the same additions) differs from numpy's sum in the last bits."""
    f = _forces(3 * BLOCK_ROWS + 17)
    blocks = sum(np.sum(f[i:i + 1000], axis=0) for i in range(0, f.shape[0], 1000))
    assert not np.array_equal(blocks, np.sum(f, axis=0))


def test_force_statistics_and_stress_factor_are_numpys_on_the_whole_record():
    f = _forces(3 * BLOCK_ROWS + 17)
    stats = force_statistics(f)
    assert np.array_equal(stats["mean_force_N"], f.mean(axis=0))
    assert np.array_equal(stats["std_force_N"], f.std(axis=0))
    assert np.array_equal(stats["dlc"], f.std(axis=0) / f.mean(axis=0))
    assert np.array_equal(dlc(f), f.std(axis=0) / f.mean(axis=0))
    assert np.array_equal(dlc(f.T, axis=1), f.T.std(axis=1) / f.T.mean(axis=1))
    for n in (4.0, 2.5):
        assert np.array_equal(stress_factor(f, n=n), np.mean((np.maximum(f, 0.0) / f.mean(axis=0)) ** n, axis=0))
    one = f[:, 0].copy()
    assert stress_factor(one) == float(np.mean((np.maximum(one, 0.0) / one.mean()) ** 4.0))


def test_the_statistics_need_no_temporary_as_large_as_the_record():
    """numpy's std makes ``f - mean`` (the record's size) and the stress factor's formula three
    such arrays: the whole-record peak is 1x and 2x the record. Block by block it is the finite
    check's booleans (1/8) plus a few blocks of BLOCK_ROWS rows: here under a quarter."""
    f = _forces(16 * BLOCK_ROWS)  # 16.8 MB
    for fn in (force_statistics, stress_factor):
        tracemalloc.start()
        try:
            fn(f)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert peak < 0.25 * f.nbytes, (fn.__name__, peak, f.nbytes)
    tracemalloc.start()
    try:
        f.std(axis=0)
        whole = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert whole >= f.nbytes  # the measurement sees numpy's temporaries


# A freed 20 MiB array raises glibc's mmap threshold above 10 MiB: a 10 MiB array then comes
# from the heap, and freed below a live 2 MiB one it stays resident. Prints the MiB given back.
PROBE = """
import numpy as np
def rss_mib():
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmRSS")) / 1024
big = np.ones(20 * 2**20 // 8); del big
a = np.ones(10 * 2**20 // 8)
b = np.ones(2 * 2**20 // 8)
before = rss_mib()
del a
print(before - rss_mib())
"""


def _given_back_mib(setup: str) -> float:
    proc = subprocess.run([sys.executable, "-c", setup + PROBE], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return float(proc.stdout.strip().splitlines()[-1])


glibc = pytest.mark.skipif(not (sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"),
                           reason="glibc's malloc and /proc/self/status needed")


@glibc
def test_without_the_setting_a_freed_array_stays_resident():
    """The probe can fail: glibc's default keeps the freed 10 MiB."""
    assert _given_back_mib("") < 2.0


@glibc
def test_return_freed_arrays_gives_a_freed_array_back():
    assert MMAP_THRESHOLD_BYTES < 10 * 2**20
    assert _given_back_mib("from rigsim.scenarios.core.memory import return_freed_arrays\n"
                           "assert return_freed_arrays()\n") > 8.0


@glibc
def test_rigsim_run_gives_freed_arrays_back(tmp_path):
    """The run command sets it for its process (before its record and statistics)."""
    setup = ("import contextlib, io\nfrom rigsim.scenarios.cli.main import main\n"
             "with contextlib.redirect_stdout(io.StringIO()):\n"
             f"    assert main(['run', {SCENARIO!r}, '--mode', 'rig', '--duration-s', '0.5', "
             f"'--out', {str(tmp_path / 'run')!r}, '--quiet']) == 0\n")
    assert _given_back_mib(setup) > 8.0
