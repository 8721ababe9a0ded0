"""Memory of a run: refuse a run whose drive and records would not fit; give freed arrays back.

A run holds its records (one sample per output instant) and the road profile in memory; the drive
itself is made chunk by chunk. :func:`check_memory` estimates both from the measured bytes per step
and per output sample and refuses, in one sentence naming the fields to change, a run that would
take more than half of the machine's available memory, before anything is allocated.
:func:`return_freed_arrays` makes the memory of the arrays a command frees go back to the system
at once (glibc's malloc otherwise keeps much of it in the process).
"""

from __future__ import annotations


from rigsim.correction.io.atomic import available_memory_bytes, size_text
from rigsim.scenarios.core.config import ScenarioError

__all__ = ["BASE_BYTES", "BYTES_PER_STEP", "BYTES_PER_OUTPUT", "MMAP_THRESHOLD_BYTES", "available_memory_bytes",
           "check_memory", "malloc_thresholds", "return_freed_arrays"]

#: Peak memory of a road or rig run per simulation step, bytes. The drive is made chunk by chunk
#: (:class:`rigsim.scenarios.core.road_drive.RoadDrive`, on the slice of the profile each chunk reads) and
#: not held; what grows with the run's length is the road profile (0.02 m spacing) and its
#: filtering: measured (tracemalloc peak of rigsim.scenarios.core.run.run, 120 km/h, 1e-4 s, 2 s against
#: 8 s: tests/scenarios/core/test_memory.py) ~3.5 B per step; 8 with a margin.
BYTES_PER_STEP = 8
#: Memory per output sample, bytes: the records and the result's signals (~280 B measured in rig
#: mode); ``timeseries.csv`` is streamed in blocks (rigsim.scenarios.core.results.csv_parts).
BYTES_PER_OUTPUT = 512
#: What a run takes whatever its length, bytes: the rest state, the stability linearization and
#: the rollout's chunk buffers (~2.5 MB measured in rig mode), rounded up.
BASE_BYTES = 3 * 2**20


def check_memory(steps: float, outputs: float, what: str, fix: str) -> None:
    """Refuse a run whose drive and records would take more than half the available memory.

    Parameters
    ----------
    steps : float
        Simulation steps whose drive is still to be made (0 when the drive exists).
    outputs : float
        Output samples to record.
    what : str
        The run in words (``"duration_s = 60 s ... is 6.2e+05 steps"``), the start of the sentence.
    fix : str
        What to change, naming the fields.

    Raises
    ------
    ScenarioError
        One sentence: the run, its estimated memory (:data:`BYTES_PER_STEP`,
        :data:`BYTES_PER_OUTPUT`), the limit and the fix.
    """
    need = BASE_BYTES + float(steps) * BYTES_PER_STEP + float(outputs) * BYTES_PER_OUTPUT
    avail = available_memory_bytes()
    if avail is None or need <= 0.5 * avail:
        return
    raise ScenarioError(f"{what}, about {size_text(need)} of memory for the drive and records, above the limit of "
                        f"{size_text(0.5 * avail)} (half of the {size_text(avail)} available); {fix}")


#: Allocations from this size up get pages of their own, given back to the system when freed
#: (glibc's ``M_MMAP_THRESHOLD``, fixed by :func:`return_freed_arrays`; glibc starts at 128 KiB),
#: bytes. 1 MiB: the stepping's per-chunk arrays (~0.3 MB) reuse heap memory, every array of the
#: size that matters (the record's 19 MB columns, the profile's working arrays, CSV blocks) does not.
MMAP_THRESHOLD_BYTES = 2**20
# mallopt parameter numbers, glibc's malloc.h
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3


def return_freed_arrays() -> bool:
    """Make the memory of freed large arrays go back to the system at once, for the rest of the process.

    glibc's malloc gives an allocation from 128 KiB up pages of its own, unmapped when freed, but
    raises that threshold to the size of each such block freed (up to 32 MiB), and the heap's
    trim threshold to twice it. From then on arrays up to that size come from the heap, and a
    freed one stays in the process's resident memory while anything lives above it: without this
    call a 600 s rig run keeps ~45 MB of the road profile's working arrays (freed before the first
    step) that way, under its 120 MB record (``benchmarks/run_memory.py``: 420 MB peak with the
    statistics' temporaries, 360 MB without both). Setting both thresholds with ``mallopt``
    fixes them, at :data:`MMAP_THRESHOLD_BYTES` and twice it, so every array from that size up
    is unmapped when freed. Values computed are the same; the cost is the page faults of each
    new large array (measured: 0.4 s more system time in a 600 s run's 21 s of CPU).

    Returns
    -------
    bool
        Whether the thresholds were set: False where the C library has no ``mallopt`` (not glibc)
        or refused it.
    """
    return malloc_thresholds(MMAP_THRESHOLD_BYTES)


def malloc_thresholds(mmap_threshold_bytes: int) -> bool:
    """Fix glibc malloc's mmap threshold at ``mmap_threshold_bytes`` (bytes) and its trim threshold at
    twice it, for the rest of the process (``mallopt``): the one place the project sets them
    (:func:`return_freed_arrays` for memory, :func:`rigsim.scenarios.core.pool.keep_heap_memory` for
    speed). Returns whether both were set: False where the C library has no ``mallopt`` (not
    glibc) or refused it."""
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError, TypeError):  # no mallopt (macOS), no process handle (Windows)
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    # mallopt returns 1 on success; musl's stub returns 0
    ok = mallopt(_M_MMAP_THRESHOLD, int(mmap_threshold_bytes)) == 1
    return bool(mallopt(_M_TRIM_THRESHOLD, 2 * int(mmap_threshold_bytes)) == 1 and ok)
