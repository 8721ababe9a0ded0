"""Where the cases of a sweep run: the local process pool or a Dask cluster.

Both are ``concurrent.futures`` executors, so :func:`scenarios.studies.sweep.run.run_sweep` has
one code path. The local pool is :func:`scenarios.core.pool.local_executor` (one run per process
at a time: MuJoCo's callbacks are process-global). :func:`dask_executor` is the executor of a
``distributed.Client`` connected to an existing Dask cluster (``client.get_executor()``), whose
workers must run one task at a time (``--nthreads 1``) and import this package.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
from collections.abc import Iterator

from scenarios.core.config import ScenarioError
from scenarios.core.pool import local_executor

__all__ = ["dask_executor", "local_executor"]


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
