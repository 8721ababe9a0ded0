"""Running a sweep: the unfinished cases of a grid on an executor, each kept as it finishes.

Resume is the default: a case whose file exists with the same fingerprint (same scenario and
evaluation settings) is not run again, unless it failed for a reason that is not a property of
the case (``retry`` in its file: a worker lost, an unexpected exception). A failing case (a
MuJoCo warning, a divergence, a drive beyond the stroke, an unstable rig) is recorded with its
error in one sentence and does not stop the others. Ctrl-C stops the run, keeps every finished
case and writes ``results.csv`` of them; running again resumes. Wall times go to ``timings.csv``
only, so two sweeps of the same grid write byte-identical case files and ``results.csv``.
"""

from __future__ import annotations

import concurrent.futures as cf
import pathlib
import time
from collections.abc import Callable
from dataclasses import dataclass

from rigsim.scenarios.core.progress import Progress, format_eta
from rigsim.scenarios.studies.sweep.case import evaluate_payload
from rigsim.scenarios.studies.sweep.grid import Case, SweepGrid
from rigsim.scenarios.studies.sweep.store import (CASES_DIR, collect_results, read_case_files, write_case, write_meta,
                                                  write_timings)

__all__ = ["SweepOutcome", "run_sweep", "SUMMARY_FILE", "format_eta"]

SUMMARY_FILE = "summary.png"


@dataclass(frozen=True)
class SweepOutcome:
    """What a call of :func:`run_sweep` did.

    Attributes
    ----------
    total : int
        Cases in the grid.
    skipped : int
        Finished cases found from an earlier run (resumed).
    ok, failed : int
        Cases run now that finished, that failed.
    interrupted : bool
        The run was stopped (Ctrl-C) before every case finished.
    wall_time_s : float, s
        Time from the first submission to the last result.
    results : pathlib.Path
        The results.csv written.
    """

    total: int
    skipped: int
    ok: int
    failed: int
    interrupted: bool
    wall_time_s: float
    results: pathlib.Path

    @property
    def cases_per_min(self) -> float:
        """Throughput of this run: cases run now (ok or failed) per minute of wall time, 1/min."""
        n = self.ok + self.failed
        return 60.0 * n / self.wall_time_s if self.wall_time_s > 0 else float("nan")


def _lost(case: Case, exc: BaseException) -> dict:
    """The record of a case whose worker failed (not a property of the case: retried on resume)."""
    return {"case_id": case.case_id, "status": "failed", "retry": True, "result": None,
            "error": f"the worker running it failed ({type(exc).__name__}: {' '.join(str(exc).split())})",
            "wall_time_s": None}


def run_sweep(grid: SweepGrid, out_dir, executor: cf.Executor, *, resume: bool = True, progress: bool = True,
              plot: bool = True, on_record: Callable[[str, dict], None] | None = None,
              executor_label: str = "") -> SweepOutcome:
    """Run the cases of ``grid`` that are not finished in ``out_dir`` on ``executor``.

    Parameters
    ----------
    grid : SweepGrid
    out_dir : path
        Output folder (created).
    executor : concurrent.futures.Executor
        Where the cases run (:func:`rigsim.scenarios.core.pool.local_executor`,
        :func:`rigsim.scenarios.studies.sweep.executors.dask_executor` or any executor whose workers run
        one case per process at a time). After Ctrl-C its cases not started are left to its
        owner to cancel (those two do it as the interrupt leaves their ``with`` block).
    resume : bool
        Skip cases with a matching case file (default). False runs every case again.
    progress : bool
        Show progress on stderr.
    plot : bool
        Write ``summary.png``.
    on_record : callable, optional
        ``on_record(case_id, record)`` after each case file is written (hooks, tests).
    executor_label : str
        Recorded in ``sweep.json``.

    Returns
    -------
    SweepOutcome

    Raises
    ------
    KeyboardInterrupt
        After Ctrl-C, with the :class:`SweepOutcome` as its argument: every finished case is
        kept and ``results.csv`` written first.
    """
    out = pathlib.Path(out_dir)
    (out / CASES_DIR).mkdir(parents=True, exist_ok=True)
    finished = read_case_files(grid, out) if resume else {}
    finished = {cid: rec for cid, rec in finished.items() if not rec.get("retry")}
    todo = [c for c in grid.cases if c.case_id not in finished]
    bar = Progress(len(grid.cases), len(grid.cases) - len(todo), progress)
    settings = grid.settings.as_dict()
    n_ok = n_failed = 0
    interrupted = False
    wall0 = time.perf_counter()
    timings: dict[str, float | None] = {}
    futures: dict[cf.Future, Case] = {}
    try:
        for case in todo:
            fut = executor.submit(evaluate_payload, case.case_id, dict(case.doc),
                                  str(case.source) if case.source else None, settings)
            futures[fut] = case
        for fut in cf.as_completed(futures):
            case = futures[fut]
            try:
                record = fut.result()
            except cf.CancelledError:
                continue
            except Exception as exc:  # noqa: BLE001 - a lost worker must not stop the sweep
                record = _lost(case, exc)
            write_case(out, case, record)
            timings[case.case_id] = record.get("wall_time_s")
            n_ok += record["status"] == "ok"
            n_failed += record["status"] != "ok"
            bar.update(case.case_id, record["status"] == "ok", record.get("error"), record.get("wall_time_s"))
            if on_record is not None:
                on_record(case.case_id, record)
    except KeyboardInterrupt:
        # The cases not started are left to the executor's owner, which stops it as the interrupt
        # leaves its with block (local_executor, dask_executor). Cancelling a process pool's
        # futures from this thread races the pool's manager thread: when the workers are then
        # terminated it fails every future it still holds, and one cancelled here makes it
        # raise InvalidStateError (CPython 3.11; upstream gh-107219), a traceback after the
        # command's last line.
        interrupted = True
    finally:
        bar.close()
        wall = time.perf_counter() - wall0
        results = collect_results(grid, out)
        write_timings(grid, out, timings)
        records = write_meta(grid, out, ran=n_ok + n_failed, wall_time_s=wall, interrupted=interrupted,
                             executor_label=executor_label)
        if plot and records:
            from rigsim.scenarios.studies.sweep.plot import plot_summary

            plot_summary(grid, records, out / SUMMARY_FILE)
    outcome = SweepOutcome(total=len(grid.cases), skipped=len(grid.cases) - len(todo), ok=n_ok,
                           failed=n_failed, interrupted=interrupted, wall_time_s=wall, results=results)
    if interrupted:
        raise KeyboardInterrupt(outcome)
    return outcome
