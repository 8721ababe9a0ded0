"""The ``rigsim`` argument parser: every command registered by its own module, each shared flag
worded once (:mod:`rigsim.scenarios.core.flags`). Building it imports nothing heavy
(``tests/scenarios/cli/test_startup.py``)."""

from __future__ import annotations

import argparse
import sys

__all__ = ["EXAMPLES", "build_parser"]

#: One example line per subcommand, shown at the end of its --help.
EXAMPLES = {
    "run": "rigsim run scenarios/data/paper/high_72kmh_3640kg.toml --mode rig --out out/run --duration-s 10",
    "paper": "rigsim paper --out out/paper",
    "validate": "rigsim validate --out out/validate --duration-s 20",
    "identify": "rigsim identify scenarios/data/paper/high_72kmh_3640kg.toml --out out/ident",
    "info": "rigsim info out/lab/messung.csv",
    "correct": "rigsim correct measured.csv --actuators out/ident/actuators.toml -o corrected.csv",
    "sweep": "rigsim sweep scenarios/data/sweeps/example.toml --out out/sweep --jobs 2",
    "iterate": "rigsim iterate scenarios/data/paper/high_72kmh_3640kg.toml --target displacement --out out/iterate",
    "model": "rigsim model --payload-kg 6360",
    "programme": "rigsim programme day1/*.csv --model truck.toml --pairs fl=Soll_FL:Weg_FL,... --out out/programme",
}


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """Help with each option's default shown (unless its help already states it), the description
    and example lines kept as written, and the help column wide enough for one line per option."""

    def __init__(self, prog, indent_increment=2, max_help_position=30, width=None):
        super().__init__(prog, indent_increment, max_help_position, width)
        # argparse measures a command's name without the 4 columns it is indented by in rigsim's
        # list of commands: room for the longest, "programme", so each command keeps one line
        self._action_max_length = len("    programme")

    def _get_help_string(self, action):
        text = action.help or ""
        if ("default" not in text and action.default not in (None, False, argparse.SUPPRESS)
                and action.option_strings and action.nargs != 0):
            text += " (default: %(default)s)"
        return text


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)

    def error(self, message):  # argparse's own errors: exit 2 with one sentence, like ours
        self.print_usage(sys.stderr)
        self.exit(2, f"rigsim: error: {message}\n")


def _version() -> str:
    import rigsim

    return rigsim.__version__


def build_parser() -> argparse.ArgumentParser:
    """The ``rigsim`` parser; each command's ``func`` runs it."""
    from rigsim.scenarios.cli import correct, info, model, run
    from rigsim.scenarios.studies.identify import command as identify
    from rigsim.scenarios.studies.iterate import command as iterate
    from rigsim.scenarios.studies.paper import command as paper
    from rigsim.scenarios.studies.programme import command as programme
    from rigsim.scenarios.studies.sweep import command as sweep
    from rigsim.scenarios.studies.validate import command as validate

    p = _Parser(prog="rigsim", description="Four-post road simulator (DYNTRAC) with a heavy truck, in MuJoCo.",
                epilog="example: " + EXAMPLES["paper"])
    p.add_argument("--version", action="version", version=f"rigsim {_version()}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser, metavar="COMMAND")
    for command in (run, paper, validate, identify, info, correct, programme, sweep, iterate, model):
        command.add_parser(sub)
    for name, parser in sub.choices.items():
        parser.epilog = f"example: {EXAMPLES[name]}"
    return p
