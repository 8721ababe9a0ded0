"""rigsim installs as one namespace, ``rigsim``, and a lab's script needs nothing but ``import rigsim``.

- pyproject.toml lists every folder with an ``__init__.py`` as a sub-package of ``rigsim``, and no
  other;
- the wheel holds ``rigsim/`` and its dist-info and nothing else (no top-level ``scenarios``,
  ``mjcf``, ``hydraulics`` or ``correction``), with the MJCF and scenario data files;
- installed from that wheel into an empty folder (the repository off the path, no editable finder
  reached), README's "Correct your rig's file" snippet runs as written on a record made here;
- ``import rigsim`` imports none of its sub-packages; its public names are pinned, and each
  resolves; every one-sentence error class is a :class:`rigsim.RigsimError`;
- no file of the repository imports a bare ``scenarios``, ``mjcf``, ``hydraulics`` or
  ``correction`` (the same file loaded twice, as two modules, breaks ``isinstance``).
"""

from __future__ import annotations

import ast
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from types import SimpleNamespace

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
FOLDERS = {"rigsim": "rigsim", "mjcf": "rigsim.mjcf", "hydraulics": "rigsim.hydraulics",
           "correction": "rigsim.correction", "scenarios": "rigsim.scenarios"}
#: The lab's API: what ``rigsim`` exports (a change here is a change of the public API).
PUBLIC = ["read_record", "identify_record", "correct_record", "LinearOptions", "ModelOptions", "CorrectionResult",
          "ChannelLoads", "SavedCalibration", "read_calibration",
          "RecordedIdentification", "Calibration", "RigsimError", "__version__"]


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_pyproject_lists_every_package_folder():
    tool = _pyproject()["tool"]["setuptools"]
    on_disk = set()
    for folder, name in FOLDERS.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            rel = init.parent.relative_to(ROOT / folder).parts
            on_disk.add(".".join((name, *rel)))
    assert set(tool["packages"]) == on_disk
    assert tool["package-dir"] == {name: folder for folder, name in FOLDERS.items()}
    assert _pyproject()["project"]["scripts"] == {"rigsim": "rigsim.scenarios.cli.main:main"}


def test_the_version_is_the_distributions():
    import rigsim

    assert rigsim.__version__ == _pyproject()["project"]["version"]


def test_import_rigsim_loads_no_sub_package_and_exports_the_api():
    code = ("import sys, rigsim; print(sorted(m for m in sys.modules if m.startswith('rigsim')));"
            "print(sorted(rigsim.__all__)); print(all(hasattr(rigsim, n) for n in rigsim.__all__))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=ROOT).stdout.splitlines()
    assert out[0] == str(["rigsim", "rigsim.errors"])
    assert out[1] == str(sorted(PUBLIC))
    assert out[2] == "True"
    import rigsim

    with pytest.raises(AttributeError, match="no attribute 'correct'"):
        rigsim.correct  # noqa: B018
    assert set(PUBLIC) <= set(dir(rigsim))


def test_every_one_sentence_error_is_a_rigsim_error():
    from rigsim import RigsimError
    from rigsim.correction.identification.actuator_fit_rules import ActuatorFitError
    from rigsim.correction.identification.plausibility import WiringError
    from rigsim.correction.input.convergence import IterationStabilityError
    from rigsim.correction.io.actuator_file import ActuatorFileError
    from rigsim.correction.io.measured_error import MeasuredDataError
    from rigsim.correction.output.pipeline import CorrectionError
    from rigsim.mjcf.physics import EquilibriumError
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.core.profiles import ProfileError
    from rigsim.scenarios.core.watch import SimulationError

    for cls in (ActuatorFitError, WiringError, IterationStabilityError, ActuatorFileError, MeasuredDataError,
                CorrectionError, EquilibriumError, ScenarioError, ProfileError):
        assert issubclass(cls, RigsimError) and issubclass(cls, ValueError), cls
    assert issubclass(SimulationError, RigsimError) and issubclass(SimulationError, RuntimeError)


def test_a_bad_file_is_a_rigsim_error(tmp_path):
    import rigsim

    (tmp_path / "empty.csv").write_text("", encoding="utf-8")
    with pytest.raises(rigsim.RigsimError, match="empty.csv"):
        rigsim.read_record(tmp_path / "empty.csv")


def _python_files():
    skip = {".venv", "out", "_build", ".git", "build"}
    for path in ROOT.rglob("*.py"):
        if not skip & set(path.relative_to(ROOT).parts):
            yield path


def test_nothing_imports_a_bare_layer():
    bare = []
    for path in _python_files():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module] if isinstance(node, ast.ImportFrom) and node.module and not node.level else [])
            bare += [f"{path.relative_to(ROOT)}: {n}" for n in names if n.split(".")[0] in set(FOLDERS) - {"rigsim"}]
    assert not bare, bare


def test_the_bare_import_check_can_fail(tmp_path, monkeypatch):
    (tmp_path / "m.py").write_text("def f():\n    from scenarios.core import run\n")
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    with pytest.raises(AssertionError, match="m.py: scenarios.core"):
        test_nothing_imports_a_bare_layer()


def _readme_snippet() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text[text.index("## Correct your rig's file"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def _lab_record(path: pathlib.Path, fs_hz: float = 1000.0, seconds: float = 40.0) -> None:
    """A record as a lab keeps it: per corner a random drive, the LVDT through a second-order T_a
    (12-16 Hz, 0.7 of critical damping), and a wheel force of 40 kN with a dynamic part; mm and kN."""
    from scipy import signal

    from rigsim.correction.io.measured import write_channels

    rng = np.random.default_rng(7)
    t = np.arange(int(seconds * fs_hz)) / fs_hz
    sos = signal.butter(4, 20.0, fs=fs_hz, output="sos")
    data, units = {}, {}
    for corner, hz in zip(("FL", "FR", "RL", "RR"), (12.0, 13.0, 15.0, 16.0)):
        drive = signal.sosfilt(sos, rng.standard_normal(t.size)) * 4.0  # mm
        w = 2 * np.pi * hz
        lvdt = signal.lsim(([w * w], [1.0, 1.4 * w, w * w]), drive, t)[1]
        data |= {f"Soll_{corner}": drive, f"Weg_{corner}": lvdt,
                 f"Fz_{corner}": 40.0 + 0.3 * np.gradient(np.gradient(lvdt, t), t) / 1e3 + 1.5 * lvdt}
        units |= {f"Soll_{corner}": "mm", f"Weg_{corner}": "mm", f"Fz_{corner}": "kN"}
    write_channels(path, SimpleNamespace(time_s=t, data=data, units=units))


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """rigsim built as a wheel from a copy of the repository's files and installed, without its
    dependencies (they are this environment's), into an empty folder."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("the repository's file list comes from git")
    base = tmp_path_factory.mktemp("wheel")
    files = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=ROOT,
                           capture_output=True, check=True).stdout.decode().split("\0")
    source = base / "source"
    for name in filter(None, files):
        if (ROOT / name).is_file():
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, source / name)
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    subprocess.run([*pip, "wheel", "--no-deps", "-w", str(base / "dist"), str(source)], check=True,
                   capture_output=True)
    wheel = next((base / "dist").glob("rigsim-*.whl"))
    target = base / "site"
    subprocess.run([*pip, "install", "--no-deps", "--target", str(target), str(wheel)], check=True,
                   capture_output=True)
    return SimpleNamespace(wheel=wheel, target=target)


def test_the_wheel_installs_rigsim_only(installed):
    names = zipfile.ZipFile(installed.wheel).namelist()
    assert {n.split("/")[0] for n in names} == {"rigsim", f"{installed.wheel.name.split('-py3')[0]}.dist-info"}
    assert {"rigsim/mjcf/truck_rig.xml", "rigsim/mjcf/scene.xml", "rigsim/mjcf/README.md"} <= set(names)
    for folder in ("paper", "paper_dyntrac", "sweeps", "suites", "trucks"):
        shipped = {p.name for p in (ROOT / "scenarios" / "data" / folder).glob("*.toml")}
        assert shipped and shipped <= {n.rsplit("/", 1)[1] for n in names if f"/data/{folder}/" in n}, folder
    top = {p.name for p in installed.target.iterdir()} - {"bin"}
    assert {n for n in top if not n.endswith(".dist-info")} == {"rigsim"}


def test_readme_snippet_runs_as_written_on_the_installed_package(installed, tmp_path):
    _lab_record(tmp_path / "messung.csv")
    code = ("import rigsim, rigsim.scenarios, sys\n"
            f"assert rigsim.__file__.startswith({str(installed.target)!r}), rigsim.__file__\n"
            f"assert rigsim.scenarios.__file__.startswith({str(installed.target)!r})\n" + _readme_snippet())
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"} | {"PYTHONPATH": str(installed.target)}
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "Fz_FL" in proc.stdout
    assert (tmp_path / "corrected.rsp").stat().st_size > 0
