"""Where the cases of a sweep run: the local process pool or a Dask cluster.

Both are ``concurrent.futures`` executors, so :func:`rigsim.scenarios.studies.sweep.run.run_sweep` has
one code path. The local pool is :func:`rigsim.scenarios.core.pool.local_executor` (one run per process
at a time: MuJoCo's callbacks are process-global). :func:`dask_executor` is the executor of a
``distributed.Client`` connected to an existing Dask cluster (``client.get_executor()``), whose
workers must run one task at a time (``--nthreads 1``) and import this package.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
from collections.abc import Iterator

from rigsim.scenarios.core.pool import local_executor, worker_count
from rigsim.scenarios.studies.sweep.scheduler import check_address, connect

__all__ = ["dask_executor", "local_executor", "checked_where", "executor_for"]


@contextlib.contextmanager
def dask_executor(address: str) -> Iterator[cf.Executor]:
    """The ``concurrent.futures`` executor of a Dask distributed cluster at ``address``.

    The connection is :func:`rigsim.scenarios.studies.sweep.scheduler.connect`'s: the address checked,
    the scheduler and its workers questioned, each step within a deadline. On an exception
    (Ctrl-C included) the cases not finished are cancelled on the cluster before it propagates.

    Raises
    ------
    ScenarioError
        One sentence naming ``--scheduler``: distributed is not installed, the address is
        refused, the scheduler cannot be reached or does not answer as one, it has no workers,
        or a worker runs more than one thread (MuJoCo's callbacks are process-global).
    """
    client = connect(address)
    try:
        executor = client.get_executor()
        try:
            yield executor
        except BaseException:
            executor.shutdown(wait=False)  # cancels the cluster's tasks of this sweep
            raise
        else:
            executor.shutdown(wait=True)
    finally:
        # Everything is written by now: a scheduler that does not acknowledge the goodbye changes nothing.
        with contextlib.suppress(Exception):
            client.close()


def checked_where(scheduler: str | None, jobs: int | None) -> str | None:
    """Check a command's ``--scheduler`` and ``--jobs`` before any work; returns the scheduler's
    address (:func:`~rigsim.scenarios.studies.sweep.scheduler.check_address`) or None (the local pool).

    Raises
    ------
    ScenarioError
        Both given, or ``--jobs`` below 1 (one sentence naming the flag).
    """
    from rigsim.scenarios.core.config import ScenarioError

    if scheduler is not None and jobs is not None:
        raise ScenarioError("--jobs sets the local process pool; a Dask cluster's size is set where its "
                            "workers are started, so give one of --jobs and --scheduler")
    try:
        worker_count(jobs)
    except ValueError:
        raise ScenarioError(f"--jobs must be a whole number >= 1, got {jobs}") from None
    return None if scheduler is None else check_address(scheduler)


def executor_for(scheduler: str | None, jobs: int | None, n: int):
    """(the executor's context manager, its label): the Dask cluster at ``scheduler`` (checked by
    :func:`checked_where`), else a local pool of ``jobs`` workers (default one per core), at most ``n``."""
    if scheduler is not None:
        return dask_executor(scheduler), f"dask {scheduler}"
    w = worker_count(jobs, n)
    return local_executor(w), f"local process pool, {w} worker{'s' if w > 1 else ''}"
