"""The ``rigsim`` flags that several commands share, each worded once.

Every command adds a shared flag through the function here, so ``--quiet`` (or ``--force``,
``--jobs``, ``-o/--out``...) reads the same in every ``rigsim COMMAND --help``. A flag's
details beyond its one line are on the command's page of the user guide (``docs/guide/``).
Imports nothing heavy: building the parser stays light (``tests/scenarios/cli/test_startup.py``).
"""

from __future__ import annotations

import argparse
import textwrap

__all__ = ["DESCRIPTION_WIDTH", "add_command", "add_out", "add_force", "add_quiet", "add_jobs", "add_duration",
           "add_recording", "add_rig", "add_noise", "add_time_col", "add_pairs", "add_number_format",
           "add_channel_timing"]

#: Characters per line of a command's description (kept as written by the help formatter).
DESCRIPTION_WIDTH = 78


def add_command(subparsers, name: str, summary: str, details: str = "", **kwargs) -> argparse.ArgumentParser:
    """Register command ``name``: ``summary`` is its line in ``rigsim --help`` and the first
    sentence of its own ``--help``, ``details`` (optional) follow it there.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        ``rigsim``'s sub-parsers.
    name : str
        The command.
    summary : str
        One line, lower case, no final stop.
    details : str
        More sentences for the command's own ``--help``.
    **kwargs
        Passed to ``add_parser`` (``usage=``...).
    """
    text = summary[0].upper() + summary[1:] + "." + (" " + details if details else "")
    return subparsers.add_parser(name, help=summary, description=textwrap.fill(text, DESCRIPTION_WIDTH), **kwargs)


def add_out(parser, kind: str = "folder", holds: str = "") -> None:
    """``-o/--out`` (required): the output ``kind`` (``"folder"`` or ``"file"``) and what it holds."""
    parser.add_argument("-o", "--out", required=True, metavar="OUT",
                        help=f"the output {kind}" + (f": {holds}" if holds else ""))


def add_force(parser) -> None:
    """``--force``: replace a previous result (never an input)."""
    parser.add_argument("--force", action="store_true", help="replace a previous result in --out, not an input")


def add_quiet(parser) -> None:
    """``--quiet``: nothing on stderr but errors."""
    parser.add_argument("--quiet", action="store_true", help="no progress bar, lines or notes on stderr")


def add_jobs(parser, most: int | None = None, dest: str = "jobs") -> None:
    """``--jobs N``: worker processes (at most ``most`` by default, when given)."""
    cap = "" if most is None else f", at most {most}"
    parser.add_argument("--jobs", dest=dest, type=int, default=None, metavar="N",
                        help=f"worker processes (default: one per core{cap})")


def add_duration(parser, of: str, default: str) -> None:
    """``--duration-s S``: the duration, in s, of ``of`` (``default`` when not given)."""
    parser.add_argument("--duration-s", type=float, default=None, metavar="S",
                        help=f"duration of {of}, s (default: {default})")


def add_recording(parser, of: str) -> None:
    """``--rrd FILE.rrd`` (a rerun recording of ``of``) and ``--view``."""
    parser.add_argument("--rrd", default=None, metavar="FILE.rrd",
                        help=f"also write a rerun recording of {of} (replaced with --force)")
    parser.add_argument("--view", action="store_true", help="with --rrd: open the recording in the rerun viewer")


def add_rig(parser, default: str = "design") -> None:
    """``--rig design|dyntrac``: the configuration of the paper's cases (the choices are
    ``rigsim.scenarios.studies.paper.PAPER_CONFIGURATIONS``, pinned by the tests)."""
    parser.add_argument("--rig", choices=("design", "dyntrac"), default=default,
                        help="design: the project's actuator gains, ISO class roads and leaf friction; dyntrac: the "
                             "rig's loop gains, the roads and the leaf friction fitted to the paper's Table 2 "
                             "(benchmarks/dyntrac_fit.py)")


def add_noise(parser) -> None:
    """``--noise-N``: the load cells' white noise (None: ``rigsim.scenarios.studies.scoring.NOISE_N``,
    which importing here would load the simulator for ``rigsim --help``; the tests pin the number)."""
    parser.add_argument("--noise-N", type=float, default=None, metavar="N",
                        help="rms of the white noise added to the measured rig force, N (default 100; 0: off)")


def add_time_col(parser) -> None:
    """``--time-col NAME``: the time column of a measured file."""
    parser.add_argument("--time-col", default=None, metavar="NAME", help="the time column (default: time, t, zeit...)")


def add_pairs(parser) -> None:
    """``--pairs fl=DRIVE:LVDT,...``: each corner's drive and pan displacement channels."""
    parser.add_argument("--pairs", default=None, metavar="fl=DRIVE:LVDT,...",
                        help="one DRIVE:LVDT pair per corner (fl, fr, rl, rr)")


def add_number_format(parser) -> None:
    """``--decimal`` and ``--thousands``: how a text input writes its numbers."""
    from rigsim.correction.io.measured_numbers import DECIMALS, THOUSANDS

    parser.add_argument("--decimal", choices=DECIMALS, default=None, metavar="MARK",
                        help="decimal mark, . or , (default: from the numbers)")
    parser.add_argument("--thousands", choices=tuple(THOUSANDS), default=None, metavar="SEP",
                        help="none, ',', '.', \"'\" or space (default: detected)")


def add_channel_timing(parser, force: bool = True) -> None:
    """``--lvdt-filter`` and ``--lvdt-delay`` (with ``force``, ``--force-filter`` and
    ``--force-delay`` before them): the lab's channel timing, undone before anything else."""
    for what, name in ((("force", "load cells'"),) if force else ()) + (("lvdt", "LVDTs'"),):
        parser.add_argument(f"--{what}-filter", default=None, metavar="HZ[:...]",
                            help=f"the {name} anti-alias filter (phase undone)")
        parser.add_argument(f"--{what}-delay", type=float, default=None, metavar="S",
                            help=f"the {name} delay beyond their filter, s")
