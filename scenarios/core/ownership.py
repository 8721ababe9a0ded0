"""Whose is an output folder: the marker rigsim leaves in every folder it writes, and the checks
that keep a command's output folder off anything it did not write.

:data:`MARKER` lists the entries a command wrote. :func:`check_owned` refuses a folder that holds
anything else (a folder rigsim did not write, or a file added to a result since); :func:`check_not_over`
refuses an output folder that is or contains an input file, the working folder or the home folder.
:mod:`rigsim.scenarios.core.outputs` applies them before any work and again before it replaces a folder.
"""

from __future__ import annotations

import json
import os
import pathlib

from rigsim.correction.io.atomic import read_regular
from rigsim.scenarios.core.config import ScenarioError

__all__ = ["MARKER", "check_not_over", "check_owned", "count_files", "entries", "plural", "read_marker",
           "write_marker"]

#: The marker file of a folder rigsim wrote: JSON ``{"written_by": ..., "entries": [...]}``, the entries
#: (files and folders, relative POSIX paths) the command wrote, or ``null`` for a folder that a
#: command keeps adding to (``rigsim sweep``).
MARKER = ".rigsim-output"
_MARKER_MAX_BYTES = 16 << 20


def plural(n: int, word: str) -> str:
    """``"1 file"``, ``"2 files"``."""
    return f"{n} {word}{'' if n == 1 else 's'}"


def count_files(folder: pathlib.Path) -> int:
    """Files below ``folder`` (rigsim's marker left out), or its entries when it holds no file."""
    n = sum(len(files) for _, _, files in os.walk(folder)) - os.path.isfile(folder / MARKER)
    return n or sum(1 for p in folder.iterdir() if p.name != MARKER)


def entries(folder: pathlib.Path) -> set[str]:
    """Every entry below ``folder`` (files, folders, links, which are not followed) as a relative
    POSIX path; the marker itself left out."""
    found = set()
    for top, dirs, files in os.walk(folder):
        rel = pathlib.Path(top).relative_to(folder)
        found.update((rel / name).as_posix() for name in dirs + files)
    found.discard(MARKER)
    return found


def read_marker(folder: pathlib.Path) -> dict | None:
    """The marker of ``folder`` as ``{"entries": list or None}``, or None when it has none, or one
    that is not a small regular file of the expected form (then the folder is not rigsim's)."""
    try:
        doc = json.loads(read_regular(folder / MARKER, "marker", max_bytes=_MARKER_MAX_BYTES))
    except (OSError, ValueError):  # none, not a small regular file, not JSON: not rigsim's
        return None
    listed = doc.get("entries", ()) if isinstance(doc, dict) else ()
    if listed is not None and not (isinstance(listed, list) and all(isinstance(e, str) for e in listed)):
        return None
    return {"entries": listed, "written_by": str(doc.get("written_by", "rigsim"))}


def write_marker(folder: pathlib.Path, listed: list[str] | None, written_by: str) -> None:
    with open(folder / MARKER, "w", encoding="utf-8") as fh:
        json.dump({"written_by": written_by, "entries": listed}, fh, indent=1)
        fh.write("\n")


def check_not_over(path: pathlib.Path, text: str, option: str, inputs) -> None:
    """Refuse an output folder that is, or contains, an input file, the working or the home folder
    (symbolic links resolved): replacing it would delete them."""
    real = pathlib.Path(os.path.realpath(path))
    guarded = [(os.getcwd(), "the working folder"), (os.path.expanduser("~"), "the home folder")]
    guarded += [(p, "the input") for p in inputs if p is not None]
    for p, what in guarded:
        other = pathlib.Path(os.path.realpath(p))
        if other == real or real in other.parents:
            verb = "is" if other == real else "contains"
            raise ScenarioError(f"{option} {text} {verb} {what} {os.fspath(p)}; name an output folder that holds "
                                "no input, nor the working or the home folder (for example a new folder out/NAME)")


def check_owned(path: pathlib.Path, text: str, option: str, force: bool) -> None:
    """Refuse an existing folder that holds anything rigsim did not write there, and, without
    ``force``, a previous result."""
    if not path.is_dir():
        return
    try:
        found = entries(path)
        n = count_files(path)
    except OSError as exc:
        raise ScenarioError(f"{option} {text} cannot be read ({exc.strerror}); name another folder") from None
    if not found:
        return  # empty, or only a marker
    marker = read_marker(path)
    if marker is None:
        raise ScenarioError(f"{option} {text} holds {plural(n, 'file')} that rigsim did not write; name a new or "
                            "empty folder (--force replaces only a folder rigsim wrote)")
    if marker["entries"] is None:
        raise ScenarioError(f"{option} {text} holds the results of {marker['written_by']}, which resumes into it; "
                            "name another folder")
    extra = sorted(found - set(marker["entries"]))
    if extra:
        more = f" and {plural(len(extra) - 1, 'other entry')}" if len(extra) > 1 else ""
        more = more.replace("entrys", "entries")
        raise ScenarioError(f"{option} {text} holds {extra[0]}{more} that rigsim did not write there; move "
                            "it out of the folder or name another folder")
    if not force:
        raise ScenarioError(f"{option} {text} already holds a previous result ({plural(n, 'file')}); choose "
                            "another folder or give --force to replace it")


