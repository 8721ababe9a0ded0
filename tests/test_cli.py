"""CLI habits: --version, an example line and the defaults in every subcommand's help, the same
flag for the same thing in every subcommand."""

from __future__ import annotations

from importlib.metadata import version

import pytest

from scenarios.cli.main import EXAMPLES, build_parser, main


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"rigsim {version('rigsim')}"


def _subparsers():
    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    return action.choices


def test_every_subcommand_has_an_example_that_parses():
    subs = _subparsers()
    assert set(subs) == set(EXAMPLES)
    for name, sub in subs.items():
        assert sub.format_help().rstrip().endswith(EXAMPLES[name]), name
        argv = EXAMPLES[name].split()[1:]
        args = build_parser().parse_args(argv)  # the example is a valid command line
        assert args.command == name


def test_defaults_are_shown_in_help():
    # added by the formatter where the help text does not state the default itself
    assert "(default: road)" in " ".join(_subparsers()["run"].format_help().split())
    assert "(default: 3640.0)" in " ".join(_subparsers()["model"].format_help().split())


@pytest.mark.parametrize("flag, commands", [
    ("--jobs", ("paper", "validate", "sweep")),
    ("--out", ("run", "paper", "validate", "identify", "correct", "sweep", "iterate")),
    ("-o", ("run", "paper", "validate", "identify", "correct", "sweep", "iterate")),
    ("--duration-s", ("run", "paper", "validate", "identify", "iterate")),
    ("--quiet", ("run", "paper", "validate", "identify", "sweep", "iterate")),
])
def test_the_same_flag_in_every_subcommand(flag, commands):
    subs = _subparsers()
    for name in commands:
        options = {o for a in subs[name]._actions for o in a.option_strings}
        assert flag in options, f"rigsim {name} has no {flag}"
