"""CLI habits: --version, an example line and the defaults in every subcommand's help, the same
flag for the same thing in every subcommand."""

from __future__ import annotations

from importlib.metadata import version

import pytest

from rigsim.scenarios.cli.main import EXAMPLES, build_parser, main


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
    assert "(default: the scenario's, else 3640 kg)" in " ".join(_subparsers()["model"].format_help().split())


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


def test_model_command_shows_a_suspended_cab(capsys):
    """rigsim model --cab-mount-hz: the cab on its own mounts (TruckVariant.cab_mount_hz) appears as
    cab modes near the mount frequency (the cab's own bounce/pitch on the mount springs; see
    tests/mjcf/test_cab_mount.py for the modal reference), with the same static loads as the rigid cab
    (the cab's mass moves from the chassis to its own body); a bad value is refused with exit 2."""
    from rigsim.scenarios.cli.main import main

    assert main(["model", "--cab-mount-hz", "2"]) == 0
    cab = capsys.readouterr().out
    assert "cab on 2 Hz mounts" in cab
    cab_hz = [float(line.split(" Hz")[0].split()[-1]) for line in cab.splitlines() if line.strip().startswith("cab ")]
    assert cab_hz and all(1.0 < f < 4.0 for f in cab_hz)
    assert main(["model"]) == 0
    rigid = capsys.readouterr().out
    assert "rigid cab" in rigid and "cab " not in rigid.split("modes")[1]
    loads = [line for line in (cab, rigid) for line in line.splitlines() if line.startswith("static wheel loads")]
    assert loads[0] == loads[1]
    assert main(["model", "--cab-mount-hz", "-1"]) == 2
    assert "cab_mount_hz" in capsys.readouterr().err
