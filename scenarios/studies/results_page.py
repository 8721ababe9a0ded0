"""A table of measured results as a Markdown file the documentation includes.

The script that measures a table writes it with :func:`write_results_page`: a title line, the
table, and one line saying how and where it was measured (the command, the date, the rigsim
version, the machine). A command's terminal output goes the same way with
:func:`write_output_page`: the command and what it printed in a code block, then that line. A
page of ``docs/`` includes the file (myst's ``{include}``), so the numbers on the page are the
ones the script measured, never copied by hand.

Light imports only (standard library and :mod:`rigsim.correction.io.atomic`): nothing here is on a
simulation's or a correction's path.
"""

from __future__ import annotations

import datetime
import os
import pathlib
import platform
import shlex
import sys
from collections.abc import Sequence

from rigsim.correction.io.atomic import atomic_write_text
from rigsim import __version__ as rigsim_version

__all__ = ["configuration_line", "markdown_table", "output_page", "results_page", "script_command", "write_block",
           "write_output_page", "write_results_page"]


def configuration_line(command: str, date: datetime.date | str | None = None) -> str:
    """The line saying how and where a table was measured.

    Parameters
    ----------
    command : str
        The command that measures the table, e.g. ``"rigsim paper --out DIR"``.
    date : datetime.date or str, optional
        When it was measured (default: today). A datetime counts by its date.

    Returns
    -------
    str
        "Measured by `<command>` on <date>, rigsim <version>, <platform>, <n> CPUs, Python
        <version>." The version, platform and CPU count are those of the running interpreter.
    """
    if date is None:
        date = datetime.date.today()
    if isinstance(date, datetime.datetime):
        date = date.date()
    day = date.isoformat() if isinstance(date, datetime.date) else str(date)
    cpus = os.cpu_count() or 1
    return (f"Measured by `{command}` on {day}, rigsim {rigsim_version}, "
            f"{platform.system()} {platform.machine()}, {cpus} CPU{'s' if cpus != 1 else ''}, "
            f"Python {platform.python_version()}.")


def script_command(script, argv: Sequence[str] | None = None) -> str:
    """The command line that runs a script of the repository, for :func:`configuration_line`.

    Parameters
    ----------
    script : str or path-like
        The script's file, e.g. ``__file__`` of ``benchmarks/generalization.py``.
    argv : sequence of str, optional
        Its arguments (default: ``sys.argv[1:]``); ``--results DIR``, where a page is written, is left out.

    Returns
    -------
    str
        ``python <folder>/<file> <arguments>``, the arguments quoted as a POSIX shell needs them,
        e.g. ``"python benchmarks/generalization.py --cases 4"``.
    """
    path = pathlib.Path(script)
    args, kept, skip = list(sys.argv[1:] if argv is None else argv), [], False
    for a in args:  # where the page goes (--results DIR) is not what was measured
        if skip:
            skip = False
        elif a == "--results":
            skip = True
        elif not a.startswith("--results="):
            kept.append(a)
    args = kept
    return " ".join(["python", f"{path.parent.name}/{path.name}", *([shlex.join(args)] if args else [])])


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A Markdown pipe table.

    Parameters
    ----------
    header : sequence of str
        The column titles.
    rows : sequence of sequences
        One sequence per row, as many cells as ``header``; each cell is written with ``str``
        (format the numbers before).

    Returns
    -------
    str
        The table, one line per row, ending in a newline.

    Raises
    ------
    ValueError
        If a row has not as many cells as the header.
    """
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join("---" for _ in header) + " |"]
    for i, row in enumerate(rows):
        cells = [str(c).replace("|", "\\|") for c in row]
        if len(cells) != len(header):
            raise ValueError(f"row {i} has {len(cells)} cells, the header {len(header)}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def results_page(title: str, header: Sequence[str], rows: Sequence[Sequence[object]], command: str,
                 date: datetime.date | str | None = None, note: str = "", script: str = "") -> str:
    """The text of a results file: title line, table, optional note, configuration line.

    Parameters
    ----------
    title : str
        One line, written in bold above the table.
    header, rows
        The table (:func:`markdown_table`).
    command : str
        The command that measures the table (:func:`configuration_line`).
    date : datetime.date or str, optional
        When it was measured (default: today).
    note : str, optional
        A paragraph after the table (what the columns mean), empty for none.
    script : str, optional
        The command that writes the file, when it is not ``command`` itself.

    Returns
    -------
    str
        Markdown, starting with a comment that says which command writes the file.
    """
    parts = [f"<!-- written by `{script or command}`: do not edit by hand -->",
             f"**{title}**", markdown_table(header, rows).rstrip("\n")]
    if note:
        parts.append(note.strip())
    parts.append(configuration_line(command, date))
    return "\n\n".join(parts) + "\n"


def _write(folder, name: str, text: str) -> pathlib.Path:
    """Write ``text`` to ``<folder>/<name>.md`` atomically (the folder made if missing)."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.md"
    atomic_write_text(path, text)
    return path


def write_results_page(folder, name: str, title: str, header: Sequence[str], rows: Sequence[Sequence[object]],
                       command: str, date: datetime.date | str | None = None, note: str = "",
                       script: str = "") -> pathlib.Path:
    """Write ``<folder>/<name>.md`` atomically (:func:`results_page`'s text).

    Parameters
    ----------
    folder : str or path-like
        Where the file goes, e.g. ``docs/results``; made if missing.
    name : str
        The file's name without ``.md``.
    title, header, rows, command, date, note, script
        As :func:`results_page`.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    return _write(folder, name, results_page(title, header, rows, command, date, note, script))


def output_page(commands: Sequence[str], output: str, command: str, date: datetime.date | str | None = None,
                title: str = "", note: str = "", script: str = "") -> str:
    """The text of a results file that shows a command's terminal output.

    Parameters
    ----------
    commands : sequence of str
        The commands, as a terminal shows them: each one's first line after ``$ ``, its further
        lines (a here-document) after ``> ``.
    output : str
        What they printed (trailing blank lines are dropped).
    command : str
        The command that measured the output (:func:`configuration_line`), e.g. the script that
        ran ``commands``.
    date : datetime.date or str, optional
        When it was measured (default: today).
    title : str, optional
        One line, written in bold above the code block, empty for none.
    note : str, optional
        A paragraph after the code block, empty for none.
    script : str, optional
        The command that writes the file, when it is not ``command`` itself.

    Returns
    -------
    str
        Markdown, starting with a comment that says which command writes the file, then a
        ``text`` code block (its fence longer than any run of backticks in it).
    """
    lines = []
    for c in commands:
        first, *more = c.strip("\n").splitlines()
        lines += [f"$ {first}"] + [f"> {m}" for m in more]
    lines += output.rstrip().splitlines()
    body = "\n".join(lines)
    fence = "```"
    while fence in body:
        fence += "`"
    parts = [f"<!-- written by `{script or command}`: do not edit by hand -->"]
    if title:
        parts.append(f"**{title}**")
    parts.append(f"{fence}text\n{body}\n{fence}")
    if note:
        parts.append(note.strip())
    parts.append(configuration_line(command, date))
    return "\n\n".join(parts) + "\n"


def write_output_page(folder, name: str, commands: Sequence[str], output: str, command: str,
                      date: datetime.date | str | None = None, title: str = "", note: str = "",
                      script: str = "") -> pathlib.Path:
    """Write ``<folder>/<name>.md`` atomically (:func:`output_page`'s text).

    Parameters
    ----------
    folder : str or path-like
        Where the file goes, e.g. ``docs/results``; made if missing.
    name : str
        The file's name without ``.md``.
    commands, output, command, date, title, note, script
        As :func:`output_page`.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    return _write(folder, name, output_page(commands, output, command, date, title, note, script))


def write_block(path, begin: str, end: str, block: str) -> pathlib.Path:
    """Rewrite the lines of the page ``path`` between the marker lines ``begin`` and ``end`` with
    ``block`` (atomically); the markers stay.

    Raises
    ------
    SystemExit
        The page does not hold each marker exactly once (one sentence).
    """
    path = pathlib.Path(path)
    text = path.read_text(encoding="utf-8")
    if text.count(begin) != 1 or text.count(end) != 1:
        raise SystemExit(f"{path}: needs one line {begin!r} and one line {end!r}")
    head, rest = text.split(begin)
    _, tail = rest.split(end)
    atomic_write_text(path, head + begin + "\n" + block.rstrip("\n") + "\n" + end + tail)
    return path
