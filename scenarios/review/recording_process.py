"""A run's rerun recording written by a child process, off the command's critical path.

``rigsim run --rrd`` starts a :class:`RecordingProcess` as soon as its arguments are checked. The
child is a fresh interpreter (``python -c``, never a fork of a process that has MuJoCo or numba
loaded, and not multiprocessing's ``spawn``, which would run the caller's main script again in
the child and start a resource tracker process too); it imports rerun and does rerun's first-use
work (:func:`rigsim.scenarios.review.recording.warm_up`) on the second core while the parent imports
the simulation and steps. When the run returns, :meth:`RecordingProcess.submit` hands the results
to the child through a socket pair, pickled and sent on a thread, so the parent goes on writing
its own files at once (the record of a 30 s rig run with its poses pickles to 7 MB; 30 MB take
0.10-0.15 s through a pipe, the GIL released while it waits, against 0.05 s of the parent's own
time to copy them into ``multiprocessing.shared_memory``, which needs the resource tracker's
bookkeeping in both processes as well). The child writes the .rrd with
:func:`rigsim.scenarios.review.recording.write_recording` (the code a single process runs) to a
temporary file beside the target, named as :mod:`rigsim.correction.io.atomic` names its temporary files
(``.{name}.{host}.{parent pid}.{random}.tmp``: a killed parent's is removed by the next write of
the same file); :meth:`RecordingProcess.commit` waits for the child and renames that file into
place. The parent never imports rerun.

Errors in the child come back as one exception of the parent: ``ValueError`` (the results do
not fit a recording), ``OSError`` (the file cannot be written; errno, text and file name kept)
or :class:`RecordingError` (anything else, and a child that died), each one sentence. On any
error or interrupt, leaving the ``with`` block stops the child (SIGTERM, then SIGKILL after
5 s) and removes the temporary file. The child runs in its own process group (a Ctrl-C reaches
the parent only, which stops the child) and turns SIGTERM into ``SystemExit``, so its own
temporary file is removed too. A child whose parent died (SIGKILL) ends by itself: the parent's
end of the socket closes and the child's wait for work ends in EOF (or, mid-write, its answer
finds no reader).
"""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import signal
import socket
import subprocess
import sys
import threading
import uuid
from collections.abc import Sequence
from multiprocessing.connection import Connection

from rigsim.correction.io.atomic import host_tag
from rigsim.errors import RigsimError

__all__ = ["RecordingError", "RecordingProcess", "serve"]

_STOP_WAIT_S = 5.0  # s; how long a stopped child may take to end before it is killed
# The child's command: the parent's import path first (a script may have extended it), then serve().
_BOOT = ("import json, sys; sys.path[:0] = [p for p in json.loads(sys.argv[2]) if p not in sys.path]; "
         "from rigsim.scenarios.review.recording_process import serve; serve(int(sys.argv[1]))")


class RecordingError(RigsimError, RuntimeError):
    """The recording process failed for a reason that is not bad input nor an unwritable file
    (one sentence); ``rigsim run`` reports it and exits 1."""


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


def _stop(signum, frame) -> None:
    raise SystemExit(128 + signum)


class _NoPandas:
    """An import finder that refuses pandas: pyarrow imports it (0.37 s, a third of the child's
    imports) only to ask whether an array is a pandas object, and then takes it for none when
    the import fails; the recording logs numpy arrays only (the .rrd is the same, tested)."""

    @staticmethod
    def find_spec(name, path=None, target=None):
        if name.partition(".")[0] == "pandas":
            raise ModuleNotFoundError(f"the recording process does not load {name}", name=name)
        return None


def serve(fd: int) -> None:
    """The child's main: warm up, take one job from the connection on file descriptor ``fd``,
    write it, answer, end. Started by :class:`RecordingProcess`, never called otherwise."""
    conn = Connection(fd)
    signal.signal(signal.SIGTERM, _stop)
    sys.meta_path.insert(0, _NoPandas)
    try:
        from rigsim.scenarios.review import recording
    except Exception as exc:  # noqa: BLE001 (reported with the job, so the parent sees it once)
        failure: BaseException | None = exc
    else:
        failure = None
        with contextlib.suppress(Exception):  # a failed warm-up costs time only; the write reports
            recording.warm_up()
    try:
        path, results, dlc_table = conn.recv()
    except (EOFError, OSError):  # the parent closed the pipe without a job, or died
        os._exit(0)
    try:
        if failure is not None:
            raise failure
        recording.write_recording(path, results, dlc_table=dlc_table)
        reply: tuple = ("ok",)
    except ValueError as exc:
        reply = ("value", str(exc))
    except OSError as exc:
        reply = ("os", exc.errno, exc.strerror or str(exc), exc.filename)
    except Exception as exc:  # noqa: BLE001 (one sentence for the parent)
        reply = ("other", _first_line(exc))
    with contextlib.suppress(OSError):
        conn.send(reply)
    os._exit(0)  # the file is written and flushed to disk; skip the interpreter's teardown


class RecordingProcess:
    """A child process that writes one .rrd file of a run (see the module's description).

    Use it as a context manager: entering starts the child, leaving stops it (and removes its
    temporary file) unless :meth:`commit` has put the file in place.

    Examples
    --------
    >>> with RecordingProcess() as rec:          # doctest: +SKIP
    ...     result = run(scenario, "rig", pose_rate_hz=50.0)
    ...     rec.submit(path, [result], dlc_table=result.table())
    ...     write_run(result, folder)
    ...     rec.commit()
    """

    def __init__(self) -> None:
        self._proc = None
        self._conn = None
        self._sender: threading.Thread | None = None
        self._send_error: BaseException | None = None
        self._path: pathlib.Path | None = None
        self._tmp: pathlib.Path | None = None
        self._committed = False

    def __enter__(self) -> RecordingProcess:
        ours, theirs = socket.socketpair()
        try:
            self._conn = Connection(ours.detach())
            fd = theirs.fileno()
            # its own process group: Ctrl-C reaches the parent only, which stops the child;
            # MUJOCO_GL=disable: it draws nothing, so mujoco's import skips loading OpenGL (0.06 s)
            self._proc = subprocess.Popen([sys.executable, "-c", _BOOT, str(fd), json.dumps(sys.path)],
                                          pass_fds=(fd,), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                          process_group=0, env={**os.environ, "MUJOCO_GL": "disable"})
        except BaseException:
            self.close()
            raise
        finally:
            theirs.close()
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    @property
    def pid(self) -> int | None:
        """The child's process id (None before it is started)."""
        return None if self._proc is None else self._proc.pid

    def submit(self, path, results: Sequence, *, dlc_table: str | None = None) -> None:
        """Hand the results to the child, which writes them as the .rrd file ``path`` (after
        :meth:`commit`). Returns at once: the results are pickled and sent on a thread.

        Parameters
        ----------
        path : str or path-like
            The .rrd file; the child writes a temporary file beside it.
        results : sequence of RunResult
            As :func:`rigsim.scenarios.review.recording.write_recording` takes them (with their poses).
        dlc_table : str, optional
            The DLC table as text, shown in the recording.
        """
        if self._conn is None or self._sender is not None:
            raise RuntimeError("submit() once, inside the with block")
        self._path = pathlib.Path(path)
        # named as rigsim.correction.io.atomic names temporary files: a killed parent's is removed by the next write
        self._tmp = self._path.parent / f".{self._path.name}.{host_tag()}.{os.getpid()}.{uuid.uuid4().hex}.tmp"
        job = (str(self._tmp), list(results), dlc_table)

        def send() -> None:
            try:
                self._conn.send(job)
            except BaseException as exc:  # noqa: BLE001 (commit() reports it)
                self._send_error = exc

        self._sender = threading.Thread(target=send, name="rigsim-recording-send", daemon=True)
        self._sender.start()

    def commit(self) -> pathlib.Path:
        """Wait for the child to write the file and rename it onto the ``path`` of :meth:`submit`.

        Raises
        ------
        ValueError
            The results do not fit a recording.
        OSError
            The file cannot be written.
        RecordingError
            Anything else the child reported, or the child ended without answering.
        """
        if self._sender is None:
            raise RuntimeError("commit() after submit()")
        self._sender.join()
        try:
            reply = self._conn.recv()
        except (EOFError, OSError):
            try:
                code = self._proc.wait(_STOP_WAIT_S)
            except subprocess.TimeoutExpired:
                code = None
            how = (f"was killed by signal {-code}" if code is not None and code < 0
                   else f"ended with exit code {code}")
            sent = "" if self._send_error is None else f" (handing it the run failed: {_first_line(self._send_error)})"
            raise RecordingError(f"the recording process {how} without writing {self._path}{sent}") from None
        if reply[0] == "value":
            raise ValueError(reply[1])
        if reply[0] == "os":
            raise OSError(reply[2]) if reply[1] is None else OSError(reply[1], reply[2], reply[3])
        if reply[0] != "ok":
            raise RecordingError(f"writing the recording {self._path} failed: {reply[1]}")
        os.replace(self._tmp, self._path)
        self._committed = True
        return self._path

    def close(self) -> None:
        """Stop the child if it still runs (SIGTERM, then SIGKILL) and remove its temporary file
        unless it was committed. Called on leaving the ``with`` block."""
        proc, self._proc = self._proc, None
        if proc is not None:
            if not self._committed and proc.poll() is None:
                proc.terminate()
            try:
                proc.wait(_STOP_WAIT_S)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if self._sender is not None:  # the child's end of the socket is closed: a blocked send fails
            self._sender.join()
        if self._conn is not None:
            self._conn.close()
        if not self._committed and self._tmp is not None:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(self._tmp)
