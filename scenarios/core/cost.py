"""What a run will cost before it starts: its computing time and the size of its files.

``rigsim run`` states both before a long run starts and refuses, in one sentence, a run whose
files would not fit on the output folder's disk. The figures are estimates from rates measured
with ``rigsim run`` on the project's 2-core machines (120 s and 2 s runs of the paper's high 72
km/h case, the difference per simulated second): 0.023 s (road) and 0.029 s (rig) of computing per
simulated second, 13.1-13.5 bytes per value of ``timeseries.csv`` (``%.10g``); the binary formats
hold 8 (MDF4, TDMS: float64) or 2 (RPC III: int16) bytes per value.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass

from rigsim.correction.io.atomic import size_text
from rigsim.scenarios.core.config import ScenarioError

__all__ = ["RunCost", "run_cost", "check_disk", "LONG_RUN_S", "LARGE_FILES_BYTES"]

#: Computing time per simulated second (lead-in included), s/s, by mode; rounded up.
SECONDS_PER_SIMULATED_S = {"road": 0.025, "rig": 0.03}
#: Start-up of a run whatever its length (imports, model compilation, rest state), s.
START_S = 1.0
#: Bytes per written value, by time series format.
BYTES_PER_VALUE = {"csv": 14, "mf4": 8, "tdms": 8, "rsp": 2}
#: Per-wheel signals (four columns each, after the time column) a run writes, by mode.
SIGNALS_PER_MODE = {"road": 3, "rig": 6}
#: A run estimated to take longer than this (s) or to write more than this (bytes) is announced.
LONG_RUN_S = 30.0
LARGE_FILES_BYTES = 256 * 2**20


@dataclass(frozen=True)
class RunCost:
    """The estimated cost of one run.

    Attributes
    ----------
    seconds : float, s
        Computing time, start-up included.
    file_bytes : int, bytes
        Size of the time series file (the other files are a few kB).
    rows, columns : int
        Rows and columns of the time series.
    """

    seconds: float
    file_bytes: int
    rows: int
    columns: int

    def sentence(self, what: str) -> str:
        """``"a 3600 s rig run: about 2 min of computing and 1.2 GiB of files (...)"``."""
        return (f"{what}: about {_duration(self.seconds)} of computing and {size_text(self.file_bytes)} of files "
                f"({self.rows:,} rows x {self.columns} columns)")

    @property
    def long(self) -> bool:
        """Worth announcing before it starts."""
        return self.seconds > LONG_RUN_S or self.file_bytes > LARGE_FILES_BYTES


def _duration(s: float) -> str:
    return f"{s / 3600:.2g} h" if s >= 5400 else f"{s / 60:.2g} min" if s >= 90 else f"{s:.0f} s"


def run_cost(mode: str, simulated_s: float, rows: int, fmt: str = "csv") -> RunCost:
    """Estimate a run's computing time and file size.

    Parameters
    ----------
    mode : str
        ``"road"`` or ``"rig"``.
    simulated_s : float, s
        Simulated time, lead-in included.
    rows : int
        Output samples (rows of the time series).
    fmt : str
        Time series format (:data:`BYTES_PER_VALUE`).
    """
    columns = 1 + 4 * SIGNALS_PER_MODE[mode]
    seconds = START_S + SECONDS_PER_SIMULATED_S[mode] * float(simulated_s)
    return RunCost(seconds=seconds, file_bytes=int(rows * columns * BYTES_PER_VALUE[fmt]), rows=int(rows),
                   columns=columns)


def check_disk(cost: RunCost, folder, option: str = "--out") -> None:
    """Refuse a run whose files would not fit on the disk of ``folder`` (or of its nearest existing
    parent), with a 10 % margin; one sentence naming the sizes and the fix."""
    where = os.path.abspath(os.fspath(folder))
    while not os.path.isdir(where) and os.path.dirname(where) != where:
        where = os.path.dirname(where)
    try:
        free = shutil.disk_usage(where).free
    except OSError:
        return
    if cost.file_bytes * 1.1 > free:
        raise ScenarioError(f"{option} {os.fspath(folder)}: the run would write about {size_text(cost.file_bytes)} but "
                            f"{where} has {size_text(free)} free; free some space, shorten duration_s, lower "
                            "output_rate_hz or write --format rsp")
