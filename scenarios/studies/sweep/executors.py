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

from rigsim.scenarios.core.pool import local_executor
from rigsim.scenarios.studies.sweep.scheduler import connect

__all__ = ["dask_executor", "local_executor"]


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
