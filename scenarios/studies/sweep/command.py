"""``rigsim sweep``: a grid of scenarios, each run on the road and on the rig and corrected, on all
cores or on a Dask cluster, with nothing lost.

::

    rigsim sweep GRID.toml --out DIR [--scheduler tcp://HOST:PORT] [--workers N] [--no-resume]

The grid file format is in :mod:`scenarios.studies.sweep.grid`; the evaluation of one case in
:mod:`scenarios.studies.sweep.case`; the summary plot in :mod:`scenarios.studies.sweep.plot`.

Executors. The work goes through one ``concurrent.futures.Executor`` code path: by default a
local ``ProcessPoolExecutor`` with one worker per core (MuJoCo's callbacks are process-global: one
run per process at a time); with ``--scheduler`` the executor of a ``distributed.Client``
connected to an existing Dask cluster (``client.get_executor()``), whose workers must run one
task at a time (``--nthreads 1``) and import this package.

Outputs in ``DIR``:

* ``cases/<case_id>.json``: one file per finished case, written atomically as soon as it
  finishes (its values, scenario, scores or error, fingerprint);
* ``results.csv``: one row per case of the grid that has a case file, sorted by case id, collected
  from the case files (so an interrupted and resumed sweep gives the same file as an
  uninterrupted one); written after every run, also an interrupted one;
* ``summary.png``: DLC against speed per roughness and payload, correction error against each
  swept parameter;
* ``sweep.json``: the grid, the settings, counts and the executor of the last run.

Resume is the default: a case whose file exists with the same fingerprint (same scenario and
evaluation settings) is not run again, unless it failed for a reason that is not a property of
the case (``retry`` in its file: a worker lost, an unexpected exception). A failing case (a
MuJoCo warning, a divergence, a drive beyond the stroke, an unstable rig) is recorded with its
error in one sentence and does not stop the others. Ctrl-C stops the workers, keeps every
finished case and writes ``results.csv`` of them; the same command resumes.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import csv
import io
import json
import os
import pathlib
import signal
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from scenarios.core.config import ScenarioError
from scenarios.studies.sweep.case import METRIC_COLUMNS, evaluate_payload
from scenarios.studies.sweep.grid import GRID_FORMAT, Case, SweepGrid, format_value, load_grid

__all__ = ["SweepOutcome", "add_parser", "cmd_sweep", "collect_results", "dask_executor", "local_executor",
           "read_case_files", "results_columns", "run_sweep", "RESULTS_FILE", "CASES_DIR"]

RESULTS_FILE = "results.csv"
CASES_DIR = "cases"
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
        """Throughput of this run: cases run now (ok or failed) per minute of wall time."""
        n = self.ok + self.failed
        return 60.0 * n / self.wall_time_s if self.wall_time_s > 0 else float("nan")


# ---------------------------------------------------------------------------------- executors
def _ignore_sigint() -> None:
    """Pool-worker initializer: Ctrl-C is handled by the parent, which stops the workers."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _stop_process_pool(pool: cf.ProcessPoolExecutor) -> None:
    """Cancel what has not started and terminate the workers (running cases are abandoned)."""
    terminate = getattr(pool, "terminate_workers", None)  # Python >= 3.14
    if terminate is not None:
        terminate()
        return
    # Before 3.14 there is no public way to stop a running task: terminate the pool's worker
    # processes (its private process table, read before shutdown clears it), then shut down.
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        with contextlib.suppress(Exception):
            proc.terminate()


@contextlib.contextmanager
def local_executor(workers: int | None = None) -> Iterator[cf.Executor]:
    """A process pool with ``workers`` processes (default: all cores), each one case at a time.

    On an exception (Ctrl-C included) the workers are terminated before it propagates.
    """
    n = workers or os.cpu_count() or 1
    pool = cf.ProcessPoolExecutor(max_workers=n, initializer=_ignore_sigint)
    try:
        yield pool
    except BaseException:
        _stop_process_pool(pool)
        raise
    else:
        pool.shutdown(wait=True)


@contextlib.contextmanager
def dask_executor(address: str) -> Iterator[cf.Executor]:
    """The ``concurrent.futures`` executor of a Dask distributed cluster at ``address``.

    Raises
    ------
    ScenarioError
        If distributed is not installed, the scheduler cannot be reached, it has no workers, or a
        worker runs more than one thread (MuJoCo's callbacks are process-global).
    """
    try:
        import distributed
    except ImportError:
        raise ScenarioError("--scheduler needs the 'distributed' package; pip install "
                            "'dask[distributed]'") from None
    try:
        client = distributed.Client(address, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise ScenarioError(f"cannot connect to the Dask scheduler at {address}: {exc}") from None
    try:
        nthreads = client.nthreads()  # {worker address: threads}
        if not nthreads:
            try:
                client.wait_for_workers(1, timeout=30)
            except TimeoutError:
                raise ScenarioError(f"the Dask scheduler at {address} has no workers (waited 30 s)") from None
            nthreads = client.nthreads()
        threaded = {w: n for w, n in nthreads.items() if n != 1}
        if threaded:
            w, n = next(iter(threaded.items()))
            raise ScenarioError(
                f"Dask worker {w} runs {n} threads; MuJoCo's callbacks are process-global, so start the "
                "workers with one thread each (dask worker tcp://HOST:PORT --nthreads 1 --nworkers N)")
        executor = client.get_executor()
        try:
            yield executor
        except BaseException:
            executor.shutdown(wait=False)
            raise
        else:
            executor.shutdown(wait=True)
    finally:
        client.close()


# ------------------------------------------------------------------------------------ files
def _case_path(out: pathlib.Path, case_id: str) -> pathlib.Path:
    return out / CASES_DIR / f"{case_id}.json"


def read_case_files(grid: SweepGrid, out_dir) -> dict[str, dict]:
    """The case files in ``out_dir`` that belong to ``grid`` (same id and fingerprint), by case id."""
    out = pathlib.Path(out_dir)
    found = {}
    for case in grid.cases:
        path = _case_path(out, case.case_id)
        try:
            rec = json.loads(path.read_text(encoding="utf-8"))
        except (FileNotFoundError, json.JSONDecodeError, UnicodeDecodeError):
            continue
        if rec.get("fingerprint") == case.fingerprint and rec.get("format") == GRID_FORMAT:
            found[case.case_id] = rec
    return found


def results_columns(grid: SweepGrid) -> list[str]:
    """Header of ``results.csv``: case id, the swept keys, status, the scores, wall time, error."""
    return ["case_id", *grid.keys, "status", *METRIC_COLUMNS, "wall_time_s", "error"]


def _lookup(doc: dict, key: str) -> Any:
    node: Any = doc
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            return ""
        node = node[part]
    return node


def _cell(value: Any) -> str:
    if value is None:
        return ""
    return format_value(value) if isinstance(value, (float, int, bool)) else str(value)


def collect_results(grid: SweepGrid, out_dir) -> pathlib.Path:
    """Write ``DIR/results.csv`` from the case files of ``grid``, sorted by case id (atomically).

    A swept key a case does not set (an explicit case without it) shows the base's value.
    Failed cases have empty scores and their error.
    """
    from scenarios.core.results import atomic_write_text

    out = pathlib.Path(out_dir)
    records = read_case_files(grid, out)
    cases = {c.case_id: c for c in grid.cases}
    cols = results_columns(grid)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(cols)
    for cid in sorted(records):
        rec = records[cid]
        result = rec.get("result") or {}
        row = [cid]
        row += [_cell(_lookup(dict(cases[cid].doc), k)) for k in grid.keys]
        row.append(rec["status"])
        row += [_cell(result.get(k)) if rec["status"] == "ok" else "" for k in METRIC_COLUMNS]
        row.append(_cell(rec.get("wall_time_s")))
        row.append(rec.get("error") or "")
        writer.writerow(row)
    path = out / RESULTS_FILE
    atomic_write_text(path, buf.getvalue())
    return path


def _write_case(out: pathlib.Path, case: Case, record: dict) -> None:
    from scenarios.core.results import atomic_write_text

    doc = {"format": GRID_FORMAT, "case_id": case.case_id, "fingerprint": case.fingerprint,
           "values": dict(case.values), **{k: v for k, v in record.items() if k != "case_id"},
           "scenario": _plain(case.doc), "source": str(case.source) if case.source else None}
    atomic_write_text(_case_path(out, case.case_id), json.dumps(doc, indent=2, default=str) + "\n")


def _plain(doc) -> Any:
    if hasattr(doc, "items"):
        return {k: _plain(v) for k, v in doc.items()}
    return doc


# --------------------------------------------------------------------------------- progress
class _Progress:
    """Finished / failed / remaining counts and an ETA: a tqdm bar on a terminal, else one line
    per finished case on stderr."""

    def __init__(self, total: int, skipped: int, enabled: bool, stream=None):
        self.total, self.done, self.failed = total, skipped, 0
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.t0 = time.perf_counter()
        self.started = 0
        self.bar = None
        if enabled and getattr(self.stream, "isatty", lambda: False)():
            from tqdm import tqdm

            self.bar = tqdm(total=total, initial=skipped, unit="case", file=self.stream, dynamic_ncols=True,
                            bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}<{remaining}] {postfix}")
            self._postfix()

    def _postfix(self) -> None:
        self.bar.set_postfix_str(f"failed {self.failed}, remaining {self.total - self.done}")

    def update(self, case_id: str, record: dict) -> None:
        self.done += 1
        self.started += 1
        ok = record["status"] == "ok"
        self.failed += 0 if ok else 1
        if not self.enabled:
            return
        note = f"{case_id}: {'ok' if ok else 'FAILED: ' + str(record.get('error'))} ({record.get('wall_time_s', 0):.1f} s)"
        if self.bar is not None:
            self.bar.update(1)
            self._postfix()
            if not ok:
                self.bar.write(note, file=self.stream)
            return
        elapsed = time.perf_counter() - self.t0
        left = self.total - self.done
        eta = elapsed / self.started * left
        print(f"[{self.done}/{self.total} finished, {self.failed} failed, {left} remaining, ETA "
              f"{time.strftime('%H:%M:%S', time.gmtime(eta))}] {note}", file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


# ---------------------------------------------------------------------------------- running
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
        Where the cases run (:func:`local_executor`, :func:`dask_executor` or any executor whose
        workers run one case per process at a time).
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
        After Ctrl-C: every finished case is kept and ``results.csv`` written first.
    """
    from scenarios.core.results import atomic_write_text

    out = pathlib.Path(out_dir)
    (out / CASES_DIR).mkdir(parents=True, exist_ok=True)
    finished = read_case_files(grid, out) if resume else {}
    finished = {cid: rec for cid, rec in finished.items() if not rec.get("retry")}
    todo = [c for c in grid.cases if c.case_id not in finished]
    bar = _Progress(len(grid.cases), len(grid.cases) - len(todo), progress)
    settings = grid.settings.as_dict()
    n_ok = n_failed = 0
    interrupted = False
    wall0 = time.perf_counter()
    futures: dict[cf.Future, Case] = {}
    try:
        for case in todo:
            fut = executor.submit(evaluate_payload, case.case_id, _plain(case.doc),
                                  str(case.source) if case.source else None, settings)
            futures[fut] = case
        for fut in cf.as_completed(futures):
            case = futures[fut]
            try:
                record = fut.result()
            except cf.CancelledError:
                continue
            except Exception as exc:  # noqa: BLE001 - a lost worker must not stop the sweep
                record = {"case_id": case.case_id, "status": "failed", "retry": True, "result": None,
                          "error": f"the worker running it failed ({type(exc).__name__}: "
                                   f"{' '.join(str(exc).split())})", "wall_time_s": None}
            _write_case(out, case, record)
            n_ok += record["status"] == "ok"
            n_failed += record["status"] != "ok"
            bar.update(case.case_id, record)
            if on_record is not None:
                on_record(case.case_id, record)
    except KeyboardInterrupt:
        interrupted = True
        for fut in futures:
            fut.cancel()
    finally:
        bar.close()
        wall = time.perf_counter() - wall0
        results = collect_results(grid, out)
        records = read_case_files(grid, out)
        meta = {
            "grid": str(grid.source) if grid.source else None, "name": grid.name,
            "axes": {k: list(v) for k, v in grid.axes}, "settings": settings,
            "cases": len(grid.cases), "finished": len(records),
            "failed": sum(r["status"] != "ok" for r in records.values()),
            "complete": len(records) == len(grid.cases), "executor": executor_label,
            "last_run": {"ran": n_ok + n_failed, "wall_time_s": round(wall, 3), "interrupted": interrupted},
        }
        atomic_write_text(out / "sweep.json", json.dumps(meta, indent=2, default=str) + "\n")
        if plot and records:
            from scenarios.studies.sweep.plot import plot_summary

            plot_summary(grid, records, out / SUMMARY_FILE)
    outcome = SweepOutcome(total=len(grid.cases), skipped=len(grid.cases) - len(todo), ok=n_ok,
                           failed=n_failed, interrupted=interrupted, wall_time_s=wall, results=results)
    if interrupted:
        raise KeyboardInterrupt(outcome)
    return outcome


# -------------------------------------------------------------------------------------- CLI
def cmd_sweep(args) -> int:
    """``rigsim sweep``: validate the grid, run it, print where the results are."""
    grid = load_grid(args.grid)  # every case validated before anything starts
    if args.workers is not None and args.workers < 1:
        raise ScenarioError(f"--workers must be at least 1, got {args.workers}")
    if args.scheduler is not None and args.workers is not None:
        raise ScenarioError("--workers sets the local process pool; a Dask cluster's size is set where its "
                            "workers are started, so give one of --workers and --scheduler")
    out = pathlib.Path(args.out)
    quiet = getattr(args, "quiet", False)
    if args.scheduler is not None:
        executor_cm, label = dask_executor(args.scheduler), f"dask {args.scheduler}"
    else:
        n = min(args.workers or os.cpu_count() or 1, len(grid.cases))
        executor_cm, label = local_executor(n), f"local process pool, {n} worker{'s' if n > 1 else ''}"
    if not quiet:
        print(f"sweep {grid.name}: {len(grid.cases)} cases on {label}", file=sys.stderr)
    try:
        with executor_cm as executor:
            outcome = run_sweep(grid, out, executor, resume=not args.no_resume, progress=not quiet,
                                executor_label=label)
    except KeyboardInterrupt as exc:
        o = exc.args[0] if exc.args and isinstance(exc.args[0], SweepOutcome) else None
        if o is not None:
            print(f"rigsim: sweep interrupted: {o.skipped + o.ok + o.failed} of {o.total} cases finished and kept "
                  f"in {out / CASES_DIR}, {o.results} written; run the same command to resume", file=sys.stderr)
        raise
    done = outcome.skipped + outcome.ok + outcome.failed
    print(f"{done} of {outcome.total} cases finished ({outcome.skipped} from an earlier run, {outcome.ok} ok and "
          f"{outcome.failed} failed now, {outcome.wall_time_s:.1f} s, {outcome.cases_per_min:.2f} cases/min); "
          f"wrote {outcome.results}, {out / SUMMARY_FILE} and {out / CASES_DIR}/")
    return 0


def add_parser(subparsers) -> None:
    """Register ``rigsim sweep`` on an argparse sub-parsers object (``func=cmd_sweep``)."""
    sp = subparsers.add_parser(
        "sweep", help="run a grid of scenarios (road, rig, corrected) on all cores or a Dask cluster",
        description="Run every case of a grid file in road and rig mode, correct the rig forces, and "
                    "collect one row per case in OUT/results.csv (resumable; one file per case in OUT/cases).")
    sp.add_argument("grid", metavar="GRID.toml", help="grid file: a base scenario plus axes and/or [[cases]]")
    sp.add_argument("--out", required=True, help="output folder")
    sp.add_argument("--scheduler", metavar="tcp://HOST:PORT", default=None,
                    help="run on an existing Dask distributed cluster (workers started with --nthreads 1)")
    sp.add_argument("--workers", type=int, default=None, help="local worker processes (default: all cores)")
    sp.add_argument("--no-resume", action="store_true", help="run every case again, even those already finished")
    sp.add_argument("--quiet", action="store_true", help="no progress output")
    sp.set_defaults(func=cmd_sweep)
