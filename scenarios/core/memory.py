"""Memory before a run: refuse a run whose drive and records would not fit.

A run holds its records (one sample per output instant) and the road profile in memory; the drive
itself is made chunk by chunk. :func:`check_memory` estimates both from the measured bytes per step
and per output sample and refuses, in one sentence naming the fields to change, a run that would
take more than half of the machine's available memory, before anything is allocated.
"""

from __future__ import annotations

import os

from scenarios.core.config import ScenarioError

__all__ = ["BASE_BYTES", "BYTES_PER_STEP", "BYTES_PER_OUTPUT", "available_memory_bytes", "check_memory"]

#: Peak memory of a road or rig run per simulation step, bytes. The drive is made chunk by chunk
#: (:class:`scenarios.core.road_drive.RoadDrive`, on the slice of the profile each chunk reads) and
#: not held; what grows with the run's length is the road profile (0.02 m spacing) and its
#: filtering: measured (tracemalloc peak of scenarios.core.run.run, 120 km/h, 1e-4 s, 2 s against
#: 8 s: tests/test_memory.py) ~3.5 B per step; 8 with a margin.
BYTES_PER_STEP = 8
#: Memory per output sample, bytes: the records and the result's signals (~280 B measured in rig
#: mode); ``timeseries.csv`` is streamed in blocks (scenarios.core.results.csv_parts).
BYTES_PER_OUTPUT = 512
#: What a run takes whatever its length, bytes: the rest state, the stability linearization and
#: the rollout's chunk buffers (~2.5 MB measured in rig mode), rounded up.
BASE_BYTES = 3 * 2**20


def available_memory_bytes() -> int | None:
    """int, bytes: the machine's available memory (psutil if installed, else the free pages of
    ``os.sysconf``); None where neither can tell."""
    try:
        import psutil
    except ImportError:
        psutil = None
    if psutil is not None:
        return int(psutil.virtual_memory().available)
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def _size(n_bytes: float) -> str:
    return f"{n_bytes / 2**30:.3g} GiB" if n_bytes >= 2**30 else f"{n_bytes / 2**20:.3g} MiB"


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
    raise ScenarioError(f"{what}, about {_size(need)} of memory for the drive and records, above the limit of "
                        f"{_size(0.5 * avail)} (half of the {_size(avail)} available); {fix}")
