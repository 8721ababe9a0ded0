"""The one worker pool: independent runs on all cores, one run per process at a time.

MuJoCo's actuator callbacks are process-global, so two runs never share a process at the same
time; each worker ignores Ctrl-C (the parent handles it and terminates the workers, so nothing
is left running) and, on Linux, dies with its parent (a parent killed outright leaves no worker
blocked on a pipe); jobs are plain picklable calls. :func:`local_executor` is the executor the
studies and ``rigsim sweep`` use (a Dask cluster's executor can stand in for it);
:func:`run_jobs` runs a list of calls on it and returns their results in order.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import os
import signal
import sys
from collections.abc import Callable, Iterator, Sequence

__all__ = ["worker_count", "InProcessExecutor", "local_executor", "stop_process_pool", "run_jobs", "keep_heap_memory"]


def keep_heap_memory(mmap_threshold_bytes: int = 64 * 2**20) -> bool:
    """Let this process's C heap keep and reuse the memory of large arrays (glibc only).

    A run allocates arrays of a few MB per chunk, thousands of times. glibc serves blocks above
    its mmap threshold with fresh mmap'ed pages (page faults on every touch) and raises that
    threshold by itself as large blocks are freed, unless a malloc parameter was set: Dask's
    nanny starts its workers with ``MALLOC_TRIM_THRESHOLD_=65536``, which freezes the threshold at
    128 KiB, and a sweep case then runs 23 % slower (4.9 against 4.0 s, measured). Setting the
    thresholds explicitly (``mallopt``) restores the reuse; the memory stays with the process
    for its next case (:func:`rigsim.scenarios.core.memory.malloc_thresholds`). Returns whether it was
    applied (False off glibc).
    """
    from rigsim.scenarios.core.memory import malloc_thresholds

    return malloc_thresholds(mmap_threshold_bytes)


def worker_count(requested: int | None, jobs: int | None = None) -> int:
    """Worker processes to start: ``requested`` (default: all cores), at most ``jobs``, at least 1.

    Raises
    ------
    ValueError
        If ``requested`` is given and below 1.
    """
    if requested is not None and (isinstance(requested, bool) or int(requested) != requested or requested < 1):
        raise ValueError(f"the number of worker processes must be a whole number >= 1, got {requested!r}")
    n = int(requested) if requested is not None else (os.cpu_count() or 1)
    return max(1, min(n, jobs) if jobs else n)


_PR_SET_PDEATHSIG = 1  # linux/prctl.h


def _die_with_parent(parent_pid: int) -> None:
    """Linux: ask the kernel to send SIGTERM to this process when its parent dies
    (``prctl(PR_SET_PDEATHSIG)``), so a worker never outlives a killed parent holding its pipes;
    exit at once if the parent is already gone. The kernel's "parent" is the thread that started
    the worker: a pool is started and used from one thread that outlives it (the main thread in
    every command). Elsewhere nothing is done."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
    except (OSError, AttributeError):  # no prctl (an unusual libc): the parent's terminate() still works
        return
    if os.getppid() != parent_pid:  # the parent died before the request was in place
        os._exit(1)


def _init_worker(parent_pid: int) -> None:
    """Pool-worker initializer: Ctrl-C is handled by the parent, which stops the workers; SIGTERM
    ends the worker (the default, also when the parent set its own handler before forking); the
    worker dies with its parent (:func:`_die_with_parent`); its heap keeps large blocks for reuse
    (:func:`keep_heap_memory`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _die_with_parent(parent_pid)
    keep_heap_memory()


def stop_process_pool(pool: cf.ProcessPoolExecutor) -> None:
    """Cancel what has not started and terminate the workers (running jobs are abandoned)."""
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


class InProcessExecutor(cf.Executor):
    """An executor that runs each job in the calling process as it is submitted (its future done
    on return): the pool of a process that may start none, a Dask worker (a daemonic process)."""

    def submit(self, fn, /, *args, **kwargs) -> cf.Future:
        future: cf.Future = cf.Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 - handed to the future, as a pool would
            if isinstance(exc, (KeyboardInterrupt, SystemExit)):
                raise
            future.set_exception(exc)
        return future


@contextlib.contextmanager
def local_executor(workers: int | None = None) -> Iterator[cf.Executor]:
    """A process pool of ``workers`` processes (default: all cores), each one job at a time.

    On an exception (Ctrl-C included) the workers are terminated before it propagates. In a
    daemonic process (a Dask worker: it may start no process) the jobs run in this process, one
    after the other (:class:`InProcessExecutor`), whatever ``workers`` says.
    """
    import multiprocessing

    if multiprocessing.current_process().daemon:
        worker_count(workers)
        yield InProcessExecutor()
        return
    pool = cf.ProcessPoolExecutor(max_workers=worker_count(workers), initializer=_init_worker,
                                  initargs=(os.getpid(),))
    try:
        yield pool
    except BaseException:
        stop_process_pool(pool)
        raise
    else:
        pool.shutdown(wait=True)


def run_jobs(jobs: Sequence[tuple[Callable, tuple]], *, workers: int | None = None,
             on_done: Callable[[int, object], None] | None = None, executor: cf.Executor | None = None) -> list:
    """Run ``fn(*args)`` for each ``(fn, args)`` of ``jobs`` in worker processes.

    Parameters
    ----------
    jobs : sequence of (callable, tuple)
        Picklable module-level functions and their arguments.
    workers : int, optional
        Worker processes (default: all cores, at most one per job).
    on_done : callable, optional
        ``on_done(index, result)`` in the parent as each job finishes (progress lines).
    executor : concurrent.futures.Executor, optional
        Use this executor instead of starting a pool.

    Returns
    -------
    list
        The results in the order of ``jobs``. The first job that raises stops the others and its
        exception propagates.
    """
    with contextlib.ExitStack() as stack:
        ex = executor if executor is not None else stack.enter_context(local_executor(worker_count(workers, len(jobs))))
        futures = {ex.submit(fn, *args): i for i, (fn, args) in enumerate(jobs)}
        results: list = [None] * len(jobs)
        try:
            for fut in cf.as_completed(futures):
                i = futures[fut]
                results[i] = fut.result()
                if on_done is not None:
                    on_done(i, results[i])
        except BaseException as exc:
            # A pool of our own is stopped by local_executor as the exception leaves it (its futures
            # cancelled, its workers terminated); cancelling them here as well races the pool's
            # manager thread, which then raises InvalidStateError after the command's last line
            # (CPython 3.11, gh-107219). Another's executor: the jobs not started are cancelled,
            # unless an interrupt is on its way to the owner, who stops it.
            if executor is not None and not isinstance(exc, KeyboardInterrupt):
                for fut in futures:
                    fut.cancel()
            raise
        return results
