"""Atomic files: a reader never sees half a file, and a killed writer leaves nothing behind.

:func:`atomic_write_bytes` writes a temporary file in the target's folder, flushes it to disk
and renames it onto the target (``os.replace``, atomic on POSIX and Windows). Temporary files
carry the writer's host and pid, so the next write to the same target removes those of writers
that no longer run. The one home of this pattern for :mod:`correction` (actuator and TOML files)
and :mod:`scenarios` (every result file), which builds on it.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import re
import socket
import tempfile

__all__ = ["atomic_path", "atomic_write_bytes", "atomic_write_text", "dead_writers_leftovers", "host_tag", "pid_running",
           "remove_stale_temp_files"]


def host_tag() -> str:
    """This machine's name as it appears in temporary file and folder names (letters, digits, '-';
    16 at most): :mod:`scenarios.core.outputs` names its staging folders with it too."""
    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname().split(".")[0])[:16] or "host"


def pid_running(pid: int) -> bool:
    """Whether process ``pid`` of this machine still runs (a process of another user counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def dead_writers_leftovers(path, accept) -> list[tuple[pathlib.Path, int, str]]:
    """What writers of this host that no longer run left beside ``path``: the entries named
    ``.{name}.{host}.{pid}.{rest}`` whose ``rest`` is ``accept``-ed, as ``(entry, pid, rest)``.

    Entries of other hosts (a shared folder), of running processes and of this one are left out;
    POSIX only (elsewhere nothing is found). The one scan behind :func:`remove_stale_temp_files`
    and the staging folders of :mod:`scenarios.core.outputs`.
    """
    path = pathlib.Path(path)
    if os.name != "posix":
        return []
    prefix, host, found = f".{path.name}.", host_tag(), []
    try:
        entries = sorted(os.scandir(path.parent), key=lambda e: e.name)
    except OSError:
        return []
    for entry in entries:
        if not entry.name.startswith(prefix):
            continue
        parts = entry.name[len(prefix):].split(".", 2)
        if len(parts) != 3 or parts[0] != host or not parts[1].isdigit() or not accept(parts[2]):
            continue  # another target's, another host's, or not a leftover of this kind
        pid = int(parts[1])
        if pid != os.getpid() and not pid_running(pid):
            found.append((pathlib.Path(entry.path), pid, parts[2]))
    return found


def remove_stale_temp_files(path) -> list[pathlib.Path]:
    """Remove the temporary files :func:`atomic_write_bytes` left beside ``path`` when their writer
    was killed: ``.{name}.{host}.{pid}.{random}.tmp`` of this host whose pid no longer runs.

    Files of other hosts (a shared folder) and of running processes are kept; POSIX only (elsewhere
    nothing is removed). Returns the files removed.
    """
    removed = []
    for entry, _pid, _rest in dead_writers_leftovers(path, lambda rest: rest.endswith(".tmp") and rest.count(".") == 1):
        with contextlib.suppress(FileNotFoundError):
            os.unlink(entry)
            removed.append(entry)
    return removed


@contextlib.contextmanager
def atomic_path(path):
    """A temporary file beside ``path`` for a writer that opens the file itself (a library's file
    sink): leaving the block without error flushes it to disk and renames it onto ``path``; an
    error (or an interrupt) removes it.

    The temporary file is ``.{name}.{host}.{pid}.{random}.tmp``, created empty; one left by a
    writer that was killed (its pid no longer runs on this host) is removed first
    (:func:`remove_stale_temp_files`).

    Yields
    ------
    pathlib.Path
        The temporary file.
    """
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temp_files(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.{host_tag()}.{os.getpid()}.", suffix=".tmp")
    os.close(fd)
    try:
        yield pathlib.Path(tmp)
        fd = os.open(tmp, os.O_RDWR)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        os.chmod(tmp, 0o644)  # mkstemp creates 0600; results are meant to be shared
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def atomic_write_bytes(path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temporary file in the same folder, then rename:
    :func:`atomic_path`).

    ``data`` is bytes, or an iterable of bytes written one after the other (a large file
    streamed without being held whole in memory).
    """
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        for part in ((data,) if isinstance(data, (bytes, bytearray, memoryview)) else data):
            fh.write(part)


def atomic_write_text(path, text: str) -> None:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))
