"""An output file written by one command: claimed before the work, published only where nothing is.

Two commands writing the same file at once would each check that it is free, do their work and
rename their result onto it, the second replacing the first. :func:`claimed_output` claims the
file before the work (a second writer is refused at once, in one sentence naming the file and the
fix) and, unless the command may replace the file (its ``--force``), makes
:func:`rigsim.correction.io.atomic.atomic_path` publish it without replacing a file that appeared there
meanwhile. The claim is a lock file beside the output, removed at the end (an error and an
interrupt too); one left by a killed writer is taken over by the next. :func:`make_parents` and
:func:`remove_empty` create an output's missing folders and take back those left empty.
"""

from __future__ import annotations

import contextlib
import errno
import os
import pathlib

from rigsim.correction.io.atomic import host_tag, no_replace

__all__ = ["claim_file", "claimed_output", "make_parents", "remove_empty"]


def make_parents(folder) -> list[pathlib.Path]:
    """Create ``folder`` and its missing parents; returns those created (deepest last)."""
    folder = pathlib.Path(folder)
    missing = []
    p = folder
    while not os.path.lexists(p) and p.parent != p:
        missing.append(p)
        p = p.parent
    folder.mkdir(parents=True, exist_ok=True)
    return missing[::-1]


def remove_empty(folders) -> None:
    """Remove those of ``folders`` (deepest last, as :func:`make_parents` gives them) that are empty."""
    for p in reversed(folders):
        with contextlib.suppress(OSError):
            p.rmdir()


def claim_file(path) -> pathlib.Path:
    """The claim file of the output ``path``: ``.{name}.claim`` beside it."""
    path = pathlib.Path(path)
    return path.parent / f".{path.name}.claim"


def _lock(claim: pathlib.Path) -> int | None:
    """``claim`` opened and locked by this process (its descriptor), or None when another holds it.

    POSIX: ``flock``, released by the kernel when its holder ends, killed or not, so a claim file
    a killed writer left is taken by the next one; a holder removes the file before it unlocks,
    so a lock won on a file no longer at ``claim`` is tried again. Elsewhere: the file created
    with ``O_EXCL`` is the claim.
    """
    try:
        import fcntl
    except ImportError:
        fcntl = None
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_BINARY", 0) | getattr(os, "O_NOFOLLOW", 0)
    while True:
        if fcntl is None:
            try:
                return os.open(claim, flags | os.O_EXCL, 0o666)
            except FileExistsError:
                return None
        fd = os.open(claim, flags, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(fd)
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                return None
            raise
        try:
            if os.path.samestat(os.fstat(fd), os.stat(claim)):
                return fd
        except FileNotFoundError:
            pass
        os.close(fd)


def _holder(claim: pathlib.Path) -> str:
    """Who holds ``claim``, as its file says: ``" (pid 123 on host)"``, or nothing (not yet written)."""
    with contextlib.suppress(OSError, ValueError, UnicodeDecodeError):
        host, pid = claim.read_text("ascii").split()
        return f" (pid {int(pid)} on {host})"
    return ""


@contextlib.contextmanager
def claimed_output(path, *, replace: bool = False, error: type[Exception] = OSError, option: str = "output"):
    """Claim the output file ``path`` for this command, from before its work to its end.

    The claim is :func:`claim_file` holding this host's name and this process's pid, locked while
    the block runs (:func:`_lock`): a second claim of the same file, from another process or
    thread, is refused at once, ``replace`` or not. Inside the block
    :func:`~rigsim.correction.io.atomic.atomic_path` publishes ``path`` without replacing a file that
    appeared there meanwhile, unless ``replace``. On leaving the block (an error, an interrupt,
    SIGTERM raised as one too) the claim file is removed, and the folders made for it when ``path``
    was not written.

    Parameters
    ----------
    path : str or os.PathLike
        The output file.
    replace : bool
        Whether a file at ``path`` may be replaced (the command's ``--force``).
    error : type of Exception
        The class raised, called with the message as its only argument.
    option : str
        The option naming ``path`` in the messages (``"-o"``).

    Yields
    ------
    pathlib.Path
        ``path``.

    Raises
    ------
    error
        ``"{option} 'PATH' is being written by another command (pid N on HOST); wait for it to
        end, or name another file"``; ``"{option} 'PATH' cannot be claimed: ..."`` (a folder that
        cannot be written); inside the block, from ``atomic_path``, ``"{option} 'PATH' was written
        by another program while this command ran; ..."``.
    """
    path = pathlib.Path(path)
    name, claim = repr(str(path)), claim_file(path)
    created: list[pathlib.Path] = []
    try:
        created = make_parents(path.parent)
        fd = _lock(claim)
    except OSError as exc:
        remove_empty(created)
        raise error(f"{option} {name} cannot be claimed ({claim.name}): {exc.strerror or exc}; choose a folder you "
                    "can write to") from None
    if fd is None:
        remove_empty(created)
        raise error(f"{option} {name} is being written by another command{_holder(claim)}; wait for it to end, or "
                    "name another file")
    refusal = error(f"{option} {name} was written by another program while this command ran; it was left as it "
                    "is, run again with another file or give --force")
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"{host_tag()} {os.getpid()}\n".encode("ascii"))
        with contextlib.nullcontext() if replace else no_replace(path, refusal):
            yield path
    finally:
        with contextlib.suppress(OSError):
            os.unlink(claim)
        os.close(fd)
        if not os.path.lexists(path):
            remove_empty(created)
