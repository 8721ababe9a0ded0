"""The ``rigsim`` help: a description for every command, one wording per shared flag, ``rigsim
correct --help`` grouped and short (the details on docs/guide/correct.md), the docs it points
to present. The help is formatted at 80 columns (``COLUMNS=80``), a terminal's usual width."""

from __future__ import annotations

import argparse
import pathlib
import re

import pytest

from rigsim.scenarios.cli.main import EXAMPLES, build_parser, main

ROOT = pathlib.Path(__file__).resolve().parents[3]

#: Flags whose help is the same text in every command that has them.
SAME_TEXT = ("--quiet", "--force", "--view", "--rig", "--noise-N", "--time-col", "--decimal", "--thousands",
             "--pairs", "--lvdt-filter", "--lvdt-delay")
#: Flags whose help is one form with the command's own object: the start they share.
SAME_FORM = {"--out": "the output ", "--duration-s": "duration of ", "--jobs": "worker processes (default: one per core",
             "--rrd": "also write a rerun recording of "}


@pytest.fixture(autouse=True)
def columns(monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")


def _commands() -> dict[str, argparse.ArgumentParser]:
    return next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices


def _help_of(parser, flag: str) -> str | None:
    return next((a.help for a in parser._actions if flag in a.option_strings), None)


def _main_help(capsys, argv) -> str:
    with pytest.raises(SystemExit) as exc:
        main(argv + ["--help"])
    assert exc.value.code == 0
    return capsys.readouterr().out


def test_every_command_has_a_summary_and_a_description():
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    summaries = {a.dest: a.help for a in sub._choices_actions}
    assert set(summaries) == set(_commands()) == set(EXAMPLES)
    for name, parser in _commands().items():
        summary = summaries[name]
        assert summary and "\n" not in summary, name
        described = " ".join((parser.description or "").split())
        assert described.startswith(summary[0].upper() + summary[1:] + "."), name  # the summary, then details


def test_rigsim_help_lists_every_command_with_its_line(capsys):
    text = _main_help(capsys, [])
    for name in _commands():
        assert re.search(rf"^    {name} +\S", text, re.M), name


@pytest.mark.parametrize("flag", SAME_TEXT)
def test_a_shared_flag_reads_the_same_in_every_command(flag):
    helps = {name: _help_of(p, flag) for name, p in _commands().items()}
    helps = {name: text for name, text in helps.items() if text is not None}
    assert len(helps) >= 2, (flag, helps)
    assert len(set(helps.values())) == 1, helps


def test_quiet_is_in_every_command_that_prints_progress_and_worded_once():
    helps = {name: _help_of(p, "--quiet") for name, p in _commands().items()}
    assert {n for n, h in helps.items() if h} == {"run", "paper", "validate", "identify", "correct", "programme", "sweep",
                                                  "iterate"}
    assert {h for h in helps.values() if h} == {"no progress bar, lines or notes on stderr"}


@pytest.mark.parametrize("flag, start", SAME_FORM.items())
def test_a_shared_flag_with_its_own_object_has_one_form(flag, start):
    helps = [h for p in _commands().values() if (h := _help_of(p, flag)) is not None]
    assert len(helps) >= 3 and all(h.startswith(start) for h in helps), helps


def test_out_is_spelled_alike_everywhere():
    for name, parser in _commands().items():
        out = [a for a in parser._actions if a.dest == "out"]
        if out:
            assert out[0].option_strings == ["-o", "--out"] and out[0].required, name


def test_no_help_speaks_of_history():
    words = re.compile(r"\b(old|older|new|newer|was|were|renamed|deprecated|formerly)\b|\b\d+\.\d+\.\d+\b", re.I)
    for name, parser in _commands().items():
        text = parser.format_help()
        assert not words.search(text), (name, words.search(text))


def test_workers_works_for_sweep_but_is_not_shown(capsys):
    args = build_parser().parse_args(["sweep", "g.toml", "-o", "o", "--workers", "3"])
    assert args.workers == 3
    assert build_parser().parse_args(["sweep", "g.toml", "-o", "o", "--jobs", "2"]).workers == 2
    assert "--workers" not in _main_help(capsys, ["sweep"])


def test_correct_help_is_grouped_and_short(capsys):
    text = _main_help(capsys, ["correct"])
    lines = text.rstrip("\n").splitlines()
    assert len(lines) <= 60, len(lines)
    assert max(len(line) for line in lines if not line.startswith("example:")) <= 80
    titles = [line for i, line in enumerate(lines[1:-1], start=1)  # a title: after a blank line, before options
              if not lines[i - 1] and line.endswith(":") and lines[i + 1].startswith("  ")]
    assert [t.split(":")[0] for t in titles] == ["options", "input", "channels", "linear correction",
                                                 "model correction", "output"], titles
    options = [line for line in lines if line.startswith("  -")]
    follow = [lines[i + 1] for i, line in enumerate(lines[:-1]) if line.startswith("  -")]
    assert len(options) >= 25 and not any(f.startswith(" " * 10) for f in follow)  # one line per option


def test_correct_help_points_to_the_docs_that_explain():
    correct = _commands()["correct"]
    assert "docs/guide/correct.md" in correct.description and (ROOT / "docs/guide/correct.md").is_file()
    cab = _help_of(correct, "--cab")
    page = re.search(r"docs/\S+\.md", cab)[0]
    assert "--cab" in (ROOT / page).read_text() and "cab" in (ROOT / page).read_text()
    guide = (ROOT / "docs/guide/correct.md").read_text()
    for action in correct._actions:  # every option of the short help is explained on the guide's page
        for option in action.option_strings:
            if option not in ("-h", "--help", "-o"):
                assert f"`{option}" in guide, option


def test_identify_and_pairs_say_how_they_relate():
    correct = _commands()["correct"]
    identify, pairs = _help_of(correct, "--identify"), _help_of(correct, "--pairs")
    assert "one T_a" in identify and "DRIVE,LVDT pair" in identify
    assert "DRIVE:LVDT pair per corner" in pairs
    metavars = {a.dest: a.metavar for a in correct._actions}
    assert metavars["identify"] == "DRIVE,LVDT" and metavars["pairs"] == "fl=DRIVE:LVDT,..."
