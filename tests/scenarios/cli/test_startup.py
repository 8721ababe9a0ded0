"""Start-up stays light: building the ``rigsim`` parser (``rigsim --help``, ``rigsim correct --help``)
imports none of python-control, matplotlib, scipy.signal, mujoco, numba or rerun (counted in a
fresh interpreter, not timed; the times are benchmarks/startup.py's). The parser therefore
carries numbers of the studies as literals; they are pinned to their homes here."""

from __future__ import annotations

import argparse
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
HEAVY = ("control", "matplotlib", "mujoco", "numba", "rerun", "scipy.signal")


def _loaded_after(code: str) -> str:
    probe = f"\nimport sys\nprint(sorted(m for m in {HEAVY!r} if m in sys.modules))"
    proc = subprocess.run([sys.executable, "-c", code + probe], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout.strip().splitlines()[-1]


def test_building_the_parser_imports_nothing_heavy():
    assert _loaded_after("from rigsim.scenarios.cli.main import build_parser; build_parser()") == "[]"


@pytest.mark.parametrize("argv", [["--help"], ["correct", "--help"], ["run", "--help"], ["sweep", "--help"]])
def test_help_imports_nothing_heavy(argv):
    code = ("import contextlib, io\nfrom rigsim.scenarios.cli.main import main\n"
            f"with contextlib.redirect_stdout(io.StringIO()):\n    try:\n        main({argv!r})\n"
            "    except SystemExit:\n        pass\n")
    assert _loaded_after(code) == "[]"


def test_the_probe_sees_heavy_imports():  # the test above can fail
    assert "'mujoco'" in _loaded_after("import rigsim.scenarios.core.rig")


def _help(name: str) -> str:
    from rigsim.scenarios.cli.main import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return " ".join(sub.choices[name].format_help().split())


def test_the_parser_literals_match_their_homes():
    from rigsim.correction.output.denoise import DRIFT_HZ
    from rigsim.scenarios.cli.main import build_parser
    from rigsim.scenarios.studies.iterate.compute import TARGETS
    from rigsim.scenarios.studies.scoring import NOISE_N

    for name in ("paper", "iterate"):
        assert f"(default {NOISE_N:g}; 0: off)" in _help(name), name
    assert f"(default {DRIFT_HZ:g}, at most" in _help("correct")
    args = build_parser().parse_args(["iterate", "x.toml", "--target", "force", "--out", "o"])
    assert args.noise_N is None  # None means NOISE_N in the study
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    target = next(a for a in sub.choices["iterate"]._actions if a.dest == "target")
    assert tuple(target.choices) == TARGETS


def test_paper_noise_default_is_the_studies(monkeypatch, tmp_path):
    from rigsim.scenarios.cli.main import build_parser
    from rigsim.scenarios.studies.paper import command, compute
    from rigsim.scenarios.studies.scoring import NOISE_N

    seen = {}

    def fake_run_paper(paths, **kwargs):
        seen.update(kwargs)
        raise KeyboardInterrupt  # stop before any work

    monkeypatch.setattr(compute, "run_paper", fake_run_paper)
    args = build_parser().parse_args(["paper", "--out", str(tmp_path), "--quiet"])
    with pytest.raises(KeyboardInterrupt):
        command.cmd_paper(args)
    assert seen["noise_N"] == NOISE_N


@pytest.mark.parametrize("user_value", [None, "glfw"])
def test_commands_skip_mujocos_opengl_unless_asked(tmp_path, user_value):
    """A command draws nothing with MuJoCo, so ``main`` sets MUJOCO_GL=disable (mujoco's import then
    skips glfw, ~0.06 s per process); a MUJOCO_GL the user set is kept (glfw: loaded as asked)."""
    import os

    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    if user_value is not None:
        env["MUJOCO_GL"] = user_value
    code = ("import sys\nfrom rigsim.scenarios.cli.main import main\n"
            "scenario = 'scenarios/data/paper/high_72kmh_3640kg.toml'\n"
            f"assert main(['run', scenario, '--mode', 'road', '--duration-s', '0.05', '--quiet', '--out', {str(tmp_path / 'o')!r}]) == 0\n"
            "print('mujoco' in sys.modules, 'mujoco.glfw' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.strip().splitlines()[-1] == ("True False" if user_value is None else "True True")
