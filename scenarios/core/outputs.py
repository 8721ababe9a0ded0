"""Outputs whole or absent: a command's folder appears at once, complete, or not at all.

:func:`staged_output` checks an output folder before any work (an empty path, a file in its
place, a previous result without ``--force``, a parent that cannot be written: one sentence
each), yields a staging folder ``.{name}.{host}.{pid}.partial`` beside the target into which the
command writes everything, and renames it onto the target when the work succeeds; on any error or
interrupt the staging folder is removed and the target is as before. Staging folders left by
killed runs of this host are removed by the next command writing the same target (or named in a
warning).

A folder rigsim wrote carries a marker file, :data:`MARKER`, listing every entry the command put
there. ``--force`` replaces a folder only when it carries the marker and holds nothing the marker
does not list: a folder rigsim did not write, or one where something was added since, is refused
with one sentence, ``--force`` or not. An output folder may never be, or contain, an input file
of the command, the working folder or the home folder. :func:`check_output_file` checks a single output file (``--rrd``, ``rigsim correct
-o``) before any work and :func:`claimed_output_file` claims it for the command's run, so that a
second command writing it is refused (:mod:`rigsim.correction.io.claim`). Files inside the staging folder
are still written by :func:`rigsim.correction.io.atomic.atomic_write_bytes`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import pathlib
import shutil
import sys

from rigsim.correction.io.atomic import dead_writers_leftovers, host_tag
from rigsim.correction.io.claim import claimed_output, make_parents, remove_empty
from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.ownership import (MARKER, check_not_over, check_owned, count_files, entries, plural,
                                       read_marker, write_marker)

_KINDS = ("partial", "old")  # staging folders, and previous results moved aside by --force

__all__ = ["MARKER", "Staging", "check_output_file", "check_output_folder", "claim_output_folder",
           "claimed_output_file", "remove_stale_staging", "staged_output"]


@dataclasses.dataclass(frozen=True)
class Staging:
    """The staging folder of :func:`staged_output`.

    Attributes
    ----------
    path : pathlib.Path
        The staging folder (absolute): write everything here.
    target : pathlib.Path
        The output folder as the user named it: where ``path`` is renamed on success.
    """

    path: pathlib.Path
    target: pathlib.Path

    def final(self, p) -> pathlib.Path:
        """Where ``p`` (a path inside :attr:`path`) will be once the staging folder is renamed."""
        return self.target / pathlib.Path(p).relative_to(self.path)

    def place(self, p) -> pathlib.Path:
        """Where to write a file meant for ``p``: inside the staging folder when ``p`` lies inside
        the target (it then appears with the rest), else ``p`` itself."""
        rel = _inside(p, self.target)
        return pathlib.Path(p) if rel is None else self.path / rel


def _inside(p, folder) -> pathlib.Path | None:
    """``p`` relative to ``folder`` when it lies inside it (both made absolute), else None."""
    try:
        return pathlib.Path(os.path.abspath(p)).relative_to(os.path.abspath(folder))
    except ValueError:
        return None


def _warn(text: str) -> None:
    print(f"rigsim: warning: {text}", file=sys.stderr, flush=True)


def _remove(path: pathlib.Path) -> None:
    if path.is_symlink() or not path.is_dir():
        path.unlink()
    else:
        shutil.rmtree(path)


def remove_stale_staging(target) -> list[pathlib.Path]:
    """Remove the staging folders ``.{name}.{host}.{pid}.partial`` that runs of this host left
    beside ``target`` when they were killed (their pid no longer runs); a previous result a killed
    ``--force`` had moved aside (``.old``) is put back when the target is missing, else removed.

    Folders of other hosts and of running processes are kept; one that cannot be removed is named
    in a warning line on stderr. POSIX only (elsewhere nothing is removed). Returns those removed.
    """
    target = pathlib.Path(os.path.abspath(target))
    removed = []
    for path, pid, kind in dead_writers_leftovers(target, lambda rest: rest in _KINDS):
        try:
            if kind == "old" and not os.path.lexists(target):
                os.rename(path, target)
                _warn(f"put back the previous result {target} that a killed run (pid {pid}) had moved aside")
                continue
            _remove(path)
            removed.append(path)
        except OSError as exc:
            _warn(f"cannot remove {path}, left by a killed run (pid {pid}): {exc.strerror or exc}; remove it by hand")
    return removed


def _writable_ancestor(path: pathlib.Path, option: str, text: str) -> pathlib.Path:
    """The nearest existing folder above ``path`` (where it will be created); refused if a file."""
    above = path.parent
    while not os.path.lexists(above) and above.parent != above:
        above = above.parent
    if not above.is_dir():
        raise ScenarioError(f"{option} {text} cannot be written: {above} is not a folder")
    return above


def check_output_folder(target, option: str = "--out") -> pathlib.Path:
    """Refuse, before any work, an output folder that cannot be one: an empty path, the root, a
    file in its place, a file among its parents, a symbolic link to nothing, a parent folder without
    write permission. An existing folder is accepted (``rigsim sweep`` resumes into it). Returns the absolute path.

    Raises
    ------
    ScenarioError
        One sentence naming ``option`` and the fix.
    """
    text = os.fspath(target)
    if not text.strip():
        raise ScenarioError(f"{option} is empty; name the output folder")
    path = pathlib.Path(os.path.abspath(text))
    if path.parent == path:
        raise ScenarioError(f"{option} {text} is the root folder; name an output folder")
    if os.path.islink(path) and not path.exists():
        raise ScenarioError(f"{option} {text} is a symbolic link to {os.readlink(path)}, which does not exist; "
                            "create that folder or name another one")
    if path.exists() and not path.is_dir():
        raise ScenarioError(f"{option} {text} exists and is not a folder; name a new folder")
    above = _writable_ancestor(path, option, text)
    if not path.is_dir() and not os.access(above, os.W_OK | os.X_OK):
        raise ScenarioError(f"{option} {text} cannot be created: no permission to write in {above}")
    if path.is_dir() and not os.access(path, os.W_OK | os.X_OK):
        raise ScenarioError(f"{option} {text} cannot be written: no permission to write in it")
    return path


def _check_target(target, force: bool, option: str, inputs=()) -> pathlib.Path:
    path = check_output_folder(target, option)
    text = os.fspath(target)
    check_not_over(path, text, option, inputs)
    check_owned(path, text, option, force)
    return path


def claim_output_folder(target, *, written_by: str, option: str = "--out", inputs=(),
                        create: bool = False) -> pathlib.Path:
    """Check, or with ``create`` make, a folder that a command keeps adding to (``rigsim sweep``).

    Accepted: a new or empty folder, or one whose marker names no entries (a folder of such a
    command). Refused (:class:`ScenarioError`, one sentence): what :func:`check_output_folder`
    refuses, a folder that is or contains an input, the working or the home folder, a folder that
    holds anything else. With ``create`` the folder (and its parents) is made and marked.

    Returns
    -------
    pathlib.Path
        The folder (absolute).
    """
    path = check_output_folder(target, option)
    text = os.fspath(target)
    check_not_over(path, text, option, inputs)
    marker = read_marker(path) if path.is_dir() else None
    if marker is None or marker["entries"] is not None:
        try:
            check_owned(path, text, option, force=False)
        except ScenarioError:
            if marker is None and path.is_dir() and entries(path):
                raise ScenarioError(f"{option} {text} holds {plural(count_files(path), 'file')} that "
                                    f"{written_by} did not write; name a new or empty folder") from None
            raise
    if create:
        path.mkdir(parents=True, exist_ok=True)
        if marker is None:
            write_marker(path, None, written_by)
    return path


def _holds_anything(path: pathlib.Path) -> bool:
    return path.is_dir() and any(path.iterdir())


def _publish(staging: pathlib.Path, target: pathlib.Path, shown: str, option: str, force: bool) -> None:
    """Mark ``staging`` and rename it onto ``target``; with ``force`` a previous result (checked
    again: it holds only what rigsim wrote) is moved aside first, removed after, and put back if the
    rename fails (the target is never left missing)."""
    write_marker(staging, sorted(entries(staging)), "rigsim")
    if not _holds_anything(target):
        os.replace(staging, target)  # a missing target, or an empty folder (POSIX replaces it)
        return
    if not force:
        raise ScenarioError(f"{option} {shown} was filled by another program while this command ran; nothing "
                            "was written, run it again with another folder")
    check_owned(target, shown, option, force)  # another program may have added to it while this one ran
    aside = target.parent / f".{target.name}.{host_tag()}.{os.getpid()}.old"
    os.rename(target, aside)
    try:
        os.rename(staging, target)
    except BaseException:
        os.rename(aside, target)
        raise
    try:
        _remove(aside)
    except OSError as exc:
        _warn(f"cannot remove the previous result moved aside to {aside}: {exc.strerror or exc}; remove it by hand")


@contextlib.contextmanager
def staged_output(target, *, force: bool = False, option: str = "--out", inputs=()):
    """Build an output folder in a staging folder beside it; rename it onto ``target`` on success.

    Parameters
    ----------
    target : str or os.PathLike
        The output folder. Refused (:class:`ScenarioError`, one sentence, before any work): an empty
        or blank path, the root folder, a path that exists and is not a folder, a symbolic link to
        nothing, a folder that is or contains an input, the working or the home folder, a folder
        that holds anything rigsim did not write there (see :data:`MARKER`), a previous result
        unless ``force``, a parent that cannot be created or written.
    force : bool
        Replace a previous result of rigsim: on success the old folder is moved aside, the new one
        renamed in and the old one removed; if the work fails, the old result stays as it was.
    option : str
        The command-line option named in the messages (``--out``).
    inputs : sequence of str or os.PathLike
        The files the command reads: the output folder may not be or contain one (None entries are
        skipped).

    Yields
    ------
    Staging
        ``.path`` the staging folder ``.{name}.{host}.{pid}.partial`` (write everything into it),
        ``.final(p)`` where a path inside it ends up, ``.place(p)`` where to write a file meant for
        ``p`` (inside the staging folder when ``p`` lies inside the target).

    Notes
    -----
    On any exception, KeyboardInterrupt or SystemExit inside the block the staging folder (and the
    parent folders this call created) are removed and the exception goes on. Leftovers of killed runs
    are cleaned first (:func:`remove_stale_staging`).
    """
    shown = os.fspath(target)
    path = _check_target(target, force, option, inputs)
    remove_stale_staging(path)
    staging = path.parent / f".{path.name}.{host_tag()}.{os.getpid()}.partial"
    created: list[pathlib.Path] = []
    try:
        created = make_parents(path.parent)
        if os.path.lexists(staging):  # only this process can have left it (its pid is ours)
            _remove(staging)
        os.mkdir(staging)
    except OSError as exc:
        remove_empty(created)
        where = pathlib.Path(exc.filename).parent if exc.filename else path.parent
        raise ScenarioError(f"{option} {shown} cannot be written: cannot create a folder in {where} "
                            f"({exc.strerror or exc}); choose a folder you can write to") from None
    try:
        yield Staging(path=staging, target=pathlib.Path(shown))
        _publish(staging, path, shown, option, force)
    except BaseException:
        with contextlib.suppress(OSError):
            if os.path.lexists(staging):
                _remove(staging)
        remove_empty(created)
        raise


def check_output_file(path, option: str, *, force: bool = False, folder=None) -> pathlib.Path:
    """Refuse, before any work, an output file that cannot be written.

    Parameters
    ----------
    path : str or os.PathLike
        The output file (``--rrd``, ``-o``).
    option : str
        The option named in the messages.
    force : bool
        Allow replacing an existing file.
    folder : str or os.PathLike, optional
        The command's output folder (``--out``): the file may lie inside it, not be it.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ScenarioError
        An empty or blank path, a folder, a path ending in ``/``, the ``--out`` folder itself, an
        existing file without ``force``, or a parent folder that cannot be created or written (one sentence).
    """
    text = os.fspath(path)
    if not text.strip():
        raise ScenarioError(f"{option} is empty; name the output file")
    p = pathlib.Path(os.path.abspath(text))
    if folder is not None and _inside(p, folder) == pathlib.Path("."):
        raise ScenarioError(f"{option} {text} is the --out folder; name a file (inside it or elsewhere)")
    if p.is_dir():
        raise ScenarioError(f"{option} {text} is a folder; name a file")
    if text.endswith(("/", os.sep)):
        raise ScenarioError(f"{option} {text} ends in '/', which names a folder; name a file (without the '/')")
    if os.path.lexists(p) and not force:
        raise ScenarioError(f"{option} {text} already exists; choose another file or give --force to replace it")
    parent = _writable_ancestor(p, option, text)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ScenarioError(f"{option} {text} cannot be written: no permission to write in {parent}")
    return pathlib.Path(text)


@contextlib.contextmanager
def claimed_output_file(path, option: str, *, force: bool = False, check=None):
    """Check the output file ``path`` (:func:`check_output_file`, or ``check()`` when given) and
    claim it for the block (:func:`rigsim.correction.io.claim.claimed_output`): a second command writing
    it is refused, and a file that appears there meanwhile is not replaced without ``force``.

    Raises
    ------
    ScenarioError
        One sentence naming ``option``: what the check refuses (checked again once claimed: the
        writer before may have finished meanwhile), or a file another command is writing.
    """
    def checked():
        return check_output_file(path, option, force=force) if check is None else check()

    checked()
    with claimed_output(path, replace=force, error=ScenarioError, option=option):
        checked()
        yield pathlib.Path(path)
