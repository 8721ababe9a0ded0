"""Files the project reads and writes: an input file never blocks or fills memory, an output file
is never seen half written, and a killed writer leaves nothing behind.

Reading: :func:`open_regular` opens a user-named input file only if it is a regular file (a named
pipe would block for ever, a device such as ``/dev/zero`` would never end), never blocking, and
:func:`read_regular` reads it whole within a limit of bytes; each refusal is one sentence naming
the file and what it is. :func:`available_memory_bytes` gives the limit that fits in memory.

Writing: :func:`atomic_write_bytes` writes a temporary file in the target's folder, flushes it to
disk and renames it onto the target (``os.replace``, atomic on POSIX and Windows). Temporary
files carry the writer's host and pid, so the next write to the same target removes those of
writers that no longer run. Inside :func:`no_replace` a target is published only where nothing
is (:mod:`rigsim.correction.io.claim`, a command's output file claimed by one command at a time).

The one home of these patterns for :mod:`correction` (measured data, actuator and TOML files) and
:mod:`scenarios` (every result file), which builds on it.
"""

from __future__ import annotations

import contextlib
import io
import os
import pathlib
import re
import secrets
import socket
import stat
import threading

__all__ = ["atomic_path", "atomic_write_bytes", "atomic_write_text", "available_memory_bytes", "dead_writers_leftovers",
           "host_tag", "no_replace", "open_regular", "pid_running", "read_regular", "remove_stale_temp_files",
           "size_text"]

#: What a path that is not a regular file is, by the test of its mode.
_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))
#: The name of a temporary file after ``.{name}.{host}.{pid}.``: a random token, ``.tmp``, and
#: the extension of the target when the writer needs it (a library that picks the format by it).
_TEMP_REST = re.compile(r"[A-Za-z0-9_]+\.tmp(\.[A-Za-z0-9]+)?")
#: The targets :func:`atomic_path` may not replace (:func:`no_replace`), by absolute path: the
#: exception it raises when one has appeared meanwhile.
_NO_REPLACE: dict[str, Exception] = {}
_NO_REPLACE_LOCK = threading.Lock()


def host_tag() -> str:
    """This machine's name as it appears in temporary file and folder names (letters, digits, '-';
    16 at most): :mod:`rigsim.scenarios.core.outputs` names its staging folders with it too."""
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


def size_text(n_bytes: float) -> str:
    """A size in bytes as people read it: ``"512 bytes"``, ``"3.2 MiB"``, ``"21 GiB"``."""
    for unit, scale in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n_bytes >= scale:
            return f"{n_bytes / scale:.3g} {unit}"
    return f"{int(n_bytes)} bytes"


def available_memory_bytes() -> int | None:
    """int, bytes: the memory this machine can give now without swapping (psutil if installed,
    else Linux's ``MemAvailable``, else the free pages of ``os.sysconf``); None where none tells."""
    try:
        import psutil
    except ImportError:
        psutil = None
    if psutil is not None:
        return int(psutil.virtual_memory().available)
    with contextlib.suppress(OSError, ValueError), open("/proc/meminfo", "rb") as fh:
        for line in fh:
            if line.startswith(b"MemAvailable:"):
                return int(line.split()[1]) * 1024
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def _kind(mode: int) -> str:
    return next((what for test, what in _KINDS if test(mode)), "not a regular file")


def open_regular(path, what: str, *, error: type[Exception] = OSError,
                 expected: str = "a regular file") -> io.BufferedReader:
    """Open a user-named input file for reading (binary), refusing anything but a regular file.

    The path is checked (``os.stat``: a directory, a named pipe, a device, a socket are refused
    without being opened), then opened with ``O_NONBLOCK`` (a named pipe put in its place
    meanwhile cannot block the open) and the opened descriptor checked again (``os.fstat``, the
    check that counts). A regular file then reads as usual.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is, for the messages: ``"scenario file"``, ``"input file"``...
    error : type of Exception
        The class raised, called with the message as its only argument.
    expected : str
        What the file should be, for the messages: ``"a regular file"``, ``"a TOML file"``.

    Returns
    -------
    io.BufferedReader
        The open file; the caller closes it.

    Raises
    ------
    error
        ``"{what} 'PATH' does not exist"``; ``"{what} 'PATH' is a directory, not {expected}"``;
        ``"{what} 'PATH' is a named pipe (FIFO), not {expected}: reading it could wait for ever
        or never end; ..."`` (a character or block device, a socket alike);
        ``"cannot read {what} 'PATH': <reason>"``.
    """
    name = repr(str(path))

    def refused(mode: int) -> Exception:
        kind = _kind(mode)
        if stat.S_ISDIR(mode):
            return error(f"{what} {name} is {kind}, not {expected}")
        return error(f"{what} {name} is {kind}, not {expected}: reading it could wait for ever or never end; name "
                     "a regular file")

    def failed(exc: BaseException) -> Exception:
        if isinstance(exc, (FileNotFoundError, NotADirectoryError)):
            return error(f"{what} {name} does not exist")
        return error(f"cannot read {what} {name}: {_reason(exc)}")  # ValueError: a NUL byte in the path

    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError) as exc:
        raise failed(exc) from None
    if not stat.S_ISREG(mode):
        raise refused(mode)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
                     | getattr(os, "O_BINARY", 0))
    except (OSError, ValueError) as exc:
        raise failed(exc) from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise refused(mode)
        if hasattr(os, "O_NONBLOCK"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_regular(path, what: str, *, max_bytes: int | None, too_large: str = "",
                 error: type[Exception] = OSError, expected: str = "a regular file") -> bytes:
    """The bytes of a user-named regular file (:func:`open_regular`), at most ``max_bytes``.

    Parameters
    ----------
    path, what, error, expected
        As for :func:`open_regular`.
    max_bytes : int or None
        The largest size read, bytes: a larger file is refused before reading (its size from
        ``os.fstat``), and one that grows past it while being read is refused too. None: no limit.
    too_large : str
        The end of the refusal of a larger file, after ``"{what} 'PATH' is 30 GiB"``: the limit
        and the fix, e.g. ``", more than the 16 MiB a TOML file may have; check the path"``.

    Returns
    -------
    bytes

    Raises
    ------
    error
        As :func:`open_regular`; a file above ``max_bytes``; ``"cannot read {what} 'PATH': ..."``
        when reading fails (an I/O error, not enough memory).
    """
    name = repr(str(path))
    with open_regular(path, what, error=error, expected=expected) as fh:
        size = os.fstat(fh.fileno()).st_size
        if max_bytes is not None and size > max_bytes:
            raise error(f"{what} {name} is {size_text(size)}{too_large}")
        want = size if max_bytes is None else min(size, max_bytes)
        try:
            data = fh.read(want + 1)  # one byte more: whether it grew since fstat
            if len(data) > want:
                data += fh.read() if max_bytes is None else fh.read(max_bytes + 1 - len(data))
        except MemoryError:
            raise error(f"cannot read {what} {name}: not enough memory for its {size_text(size)}") from None
        except OSError as exc:
            raise error(f"cannot read {what} {name}: {_reason(exc)}") from None
    if max_bytes is not None and len(data) > max_bytes:
        raise error(f"{what} {name} is more than {size_text(max_bytes)}{too_large}")
    return data


def _reason(exc: BaseException) -> str:
    return " ".join(str(getattr(exc, "strerror", None) or exc).split())


def _is_temp_rest(rest: str) -> bool:
    return _TEMP_REST.fullmatch(rest) is not None


def dead_writers_leftovers(path, accept) -> list[tuple[pathlib.Path, int, str]]:
    """What writers of this host that no longer run left beside ``path``: the entries named
    ``.{name}.{host}.{pid}.{rest}`` whose ``rest`` is ``accept``-ed, as ``(entry, pid, rest)``.

    Entries of other hosts (a shared folder), of running processes and of this one are left out;
    POSIX only (elsewhere nothing is found). The one scan behind :func:`remove_stale_temp_files`
    and the staging folders of :mod:`rigsim.scenarios.core.outputs`.
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
    """Remove the temporary files :func:`atomic_path` left beside ``path`` when their writer was
    killed: ``.{name}.{host}.{pid}.{random}.tmp`` (or ``...tmp.{ext}``, the target's extension
    kept) of this host whose pid no longer runs.

    Files of other hosts (a shared folder) and of running processes are kept; POSIX only (elsewhere
    nothing is removed). Returns the files removed.
    """
    removed = []
    for entry, _pid, _rest in dead_writers_leftovers(path, _is_temp_rest):
        with contextlib.suppress(FileNotFoundError):
            os.unlink(entry)
            removed.append(entry)
    return removed


def _new_temp_file(path: pathlib.Path, keep_suffix: bool) -> pathlib.Path:
    """Create ``.{name}.{host}.{pid}.{random}.tmp[{ext}]`` beside ``path``, empty, with the mode a
    new file gets (0666 less the umask, as ``open`` gives)."""
    head = f".{path.name}.{host_tag()}.{os.getpid()}."
    tail = ".tmp" + (path.suffix if keep_suffix and re.fullmatch(r"\.[A-Za-z0-9]+", path.suffix) else "")
    while True:
        tmp = path.parent / f"{head}{secrets.token_hex(4)}{tail}"
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666))
        except FileExistsError:
            continue
        return tmp


@contextlib.contextmanager
def no_replace(path, refusal: Exception):
    """While inside, :func:`atomic_path` (in any thread of this process) publishes ``path`` only
    where nothing is: a file that appeared there is left as it is and ``refusal`` raised."""
    key = os.path.abspath(path)
    with _NO_REPLACE_LOCK:
        _NO_REPLACE[key] = refusal
    try:
        yield
    finally:
        with _NO_REPLACE_LOCK:
            _NO_REPLACE.pop(key, None)


def _publish(tmp: pathlib.Path, path: pathlib.Path) -> None:
    """Rename the finished ``tmp`` onto ``path``; inside :func:`no_replace` only if nothing is
    there (a hard link, then the temporary name removed)."""
    with _NO_REPLACE_LOCK:
        refusal = _NO_REPLACE.get(os.path.abspath(path))
    if refusal is None:
        os.replace(tmp, path)
        return
    try:
        os.link(tmp, path)
    except FileExistsError:
        raise refusal from None
    except OSError:  # a file system without hard links: the check and the rename are apart
        if os.path.lexists(path):
            raise refusal from None
        os.replace(tmp, path)
        return
    os.unlink(tmp)


@contextlib.contextmanager
def atomic_path(path, *, keep_suffix: bool = False):
    """A temporary file beside ``path`` for a writer that opens the file itself (a library's file
    sink): leaving the block without error flushes it to disk and renames it onto ``path``; an
    error (or an interrupt) removes it.

    The temporary file is ``.{name}.{host}.{pid}.{random}.tmp``, created empty with the mode a new
    file gets (0666 less the umask); with ``keep_suffix`` it ends with ``path``'s extension too
    (``.out.mf4.host.123.89abcdef.tmp.mf4``), for a writer that picks the format by it. One left
    by a writer that was killed (its pid no longer runs on this host) is removed first
    (:func:`remove_stale_temp_files`). Inside :func:`no_replace` of ``path`` the file is published
    by ``os.link``, which leaves a file that appeared there meanwhile as it is (the refusal
    :func:`no_replace` was given is raised and the temporary file removed).

    Yields
    ------
    pathlib.Path
        The temporary file.
    """
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temp_files(path)
    tmp = _new_temp_file(path, keep_suffix)
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDWR)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        _publish(tmp, path)
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
