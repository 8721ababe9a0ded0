"""The on-disk cache of the compiled hydraulic callbacks (rigsim.hydraulics.kernels, rigsim.hydraulics.callback_cache).

Every check that involves compiling or loading runs in a fresh process (the callbacks are
memoized per process) against a private cache folder, and is counted, not timed: the process
reports through :func:`rigsim.hydraulics.kernels.cache_info` whether it compiled, loaded or rejected.
"""

from __future__ import annotations

import json
import os
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pytest

from rigsim.hydraulics import callback_cache, kernels

ROOT = pathlib.Path(__file__).resolve().parents[2]

PRELUDE = """
import json, mujoco
from rigsim.hydraulics import ActuatorParams, callback_cache, kernels
from rigsim.hydraulics.bridge import _find_offsets, hydraulic_callbacks, single_pan_spec
model = single_pan_spec(ActuatorParams()).compile()
offsets = _find_offsets(model, mujoco.MjData(model))
"""
INSTALL = PRELUDE + """
with hydraulic_callbacks(model):
    pass
print(json.dumps(dict(kernels.cache_info(), source=kernels.make_raw_callbacks(offsets).source)))
"""
RUN = """
import dataclasses, json, sys
import numpy as np
from rigsim.hydraulics import kernels
from rigsim.scenarios.core.config import load_scenario
from rigsim.scenarios.core.run import run
scenario = dataclasses.replace(load_scenario("scenarios/data/paper/high_72kmh_3640kg.toml"), duration_s=1.0)
result = run(scenario, "rig")
np.savez(sys.argv[1], t_s=result.t_s, **result.signals)
print(json.dumps(kernels.cache_info()))
"""


def _python(code: str, cache_dir=None, *args) -> dict:
    """Run ``code`` in a fresh interpreter with the cache in ``cache_dir`` (None: cache off);
    returns the JSON object it prints last."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("RIGSIM_")}
    if cache_dir is None:
        env["RIGSIM_NO_CACHE"] = "1"
    else:
        env["RIGSIM_CACHE_DIR"] = str(cache_dir)
    proc = subprocess.run([sys.executable, "-c", code, *map(str, args)], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _entries(folder: pathlib.Path) -> list[pathlib.Path]:
    return sorted(folder.glob("hydraulics-callbacks-*.bin")) if folder.exists() else []


@pytest.fixture(scope="module")
def primed(tmp_path_factory) -> pathlib.Path:
    """A cache folder filled by one process that compiled the callbacks."""
    folder = tmp_path_factory.mktemp("primed")
    info = _python(INSTALL, folder)
    assert (info["compiled"], info["loaded"], info["saved"], info["source"]) == (1, 0, 1, "compiled")
    assert len(_entries(folder)) == 1
    return folder


@pytest.fixture
def cache(primed, tmp_path) -> pathlib.Path:
    """A private copy of the primed folder."""
    return pathlib.Path(shutil.copytree(primed, tmp_path / "cache"))


def test_a_second_process_loads_instead_of_compiling(cache):
    before = {p: p.read_bytes() for p in _entries(cache)}
    info = _python(INSTALL, cache)
    assert (info["compiled"], info["loaded"], info["rejected"], info["saved"]) == (0, 1, 0, 0)
    assert info["source"] == "cache"
    assert {p: p.read_bytes() for p in _entries(cache)} == before  # read, not rewritten


def test_cache_off_compiles_and_writes_nothing(tmp_path, monkeypatch):
    info = _python(INSTALL, None)
    assert (info["compiled"], info["loaded"], info["saved"], info["directory"]) == (1, 0, 0, None)
    monkeypatch.setenv("RIGSIM_NO_CACHE", "1")
    assert callback_cache.cache_directory() is None


def test_cache_folder_from_the_environment(tmp_path, monkeypatch):
    for name in ("RIGSIM_NO_CACHE", "RIGSIM_CACHE_DIR", "XDG_CACHE_HOME"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert callback_cache.cache_directory() == tmp_path / "home" / ".cache" / "rigsim"
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert callback_cache.cache_directory() == tmp_path / "xdg" / "rigsim"
    monkeypatch.setenv("RIGSIM_CACHE_DIR", str(tmp_path / "mine"))
    assert callback_cache.cache_directory() == tmp_path / "mine"
    monkeypatch.setenv("RIGSIM_NO_CACHE", "0")
    assert callback_cache.cache_directory() == tmp_path / "mine"


def test_the_key_holds_what_the_machine_code_depends_on():
    off = kernels.RawOffsets(*range(8, 80, 8))
    key = kernels.cache_key(off)
    assert key["offsets"]["d_act"] == off.d_act
    assert key["layout"]["LAYOUT_TAG"] == kernels.LAYOUT_TAG and key["layout"]["P_TAG"] == 0
    assert set(key["sources"]) == {"rigsim.hydraulics.kernels", "rigsim.hydraulics.model", "rigsim.hydraulics.packing",
                                   "rigsim.hydraulics.params"}
    assert {"python", "numba", "llvmlite", "llvm", "numpy", "mujoco"} <= set(key["versions"])
    assert key["target"][1]  # CPU name
    digest = callback_cache.key_digest(key)
    assert callback_cache.key_digest(kernels.cache_key(off._replace(d_act=off.d_act + 8))) != digest
    assert callback_cache.key_digest(json.loads(json.dumps(key))) == digest  # stable through JSON


@pytest.mark.parametrize("change", [
    "offsets = offsets._replace(d_act=offsets.d_act + 8)",  # another mujoco layout
    "kernels._SOURCES = dict(kernels._SOURCES, **{'rigsim.hydraulics.model': '0' * 64})",  # an edited file
    "import rigsim.hydraulics.model; rigsim.hydraulics.model.CLIP_KNEE = 0.79",  # a constant numba bakes in
])
def test_a_changed_key_input_compiles_anew(cache, change):
    code = PRELUDE + change + """
cbs = kernels.make_raw_callbacks(offsets)
print(json.dumps(dict(kernels.cache_info(), source=cbs.source)))
"""
    info = _python(code, cache)
    assert (info["compiled"], info["loaded"], info["saved"], info["source"]) == (1, 0, 1, "compiled")
    assert len(_entries(cache)) == 2  # the old entry stays for the old inputs


def test_an_entry_of_another_key_is_never_loaded(cache):
    # The entry of the true offsets, renamed to the file name another key would use: the key
    # inside it is compared on load, so it is rejected and the callbacks compiled.
    code = PRELUDE + """
other = offsets._replace(d_ctrl=offsets.d_ctrl + 8)
path = callback_cache.entry_path(callback_cache.cache_directory(),
                                 callback_cache.key_digest(kernels.cache_key(other)))
[entry] = callback_cache.cache_directory().glob("hydraulics-callbacks-*.bin")
entry.rename(path)
cbs = kernels.make_raw_callbacks(other)
print(json.dumps(dict(kernels.cache_info(), source=cbs.source)))
"""
    info = _python(code, cache)
    assert (info["compiled"], info["loaded"], info["rejected"], info["saved"]) == (1, 0, 1, 1)


def test_stale_code_under_a_matching_key_fails_the_reference_check(tmp_path):
    # Defence in depth: machine code built from other equations (MPA changed in memory after
    # the key was taken), stored under the true key, is caught by the check against the
    # plain-Python equations on load, deleted and compiled anew.
    folder = tmp_path / "cache"
    code = PRELUDE + """
import rigsim.hydraulics.model
key = kernels.cache_key(offsets)
rigsim.hydraulics.model.MPA = 1.1e6
kernels.cache_key = lambda off: key
kernels.make_raw_callbacks(offsets)
print(json.dumps(kernels.cache_info()))
"""
    assert _python(code, folder)["saved"] == 1
    info = _python(INSTALL, folder)
    assert (info["compiled"], info["loaded"], info["rejected"], info["saved"]) == (1, 0, 1, 1)
    assert info["source"] == "compiled"
    assert _python(INSTALL, folder)["loaded"] == 1  # the replacement is good


@pytest.mark.parametrize("damage", ["flip", "truncate", "garbage"])
def test_a_corrupted_entry_is_ignored_and_replaced(cache, damage):
    [entry] = _entries(cache)
    blob = bytearray(entry.read_bytes())
    if damage == "flip":
        blob[-100] ^= 0xFF  # inside the machine code
    elif damage == "truncate":
        del blob[len(blob) // 2:]
    else:
        blob[:] = b"\x00" * 64
    entry.write_bytes(bytes(blob))
    info = _python(INSTALL, cache)
    assert (info["compiled"], info["loaded"], info["rejected"], info["saved"]) == (1, 0, 1, 1)
    [replaced] = _entries(cache)
    assert replaced.read_bytes() != bytes(blob)
    assert _python(INSTALL, cache)["loaded"] == 1


def test_runs_with_and_without_the_cache_are_bit_identical(tmp_path):
    folder = tmp_path / "cache"
    off = _python(RUN, None, tmp_path / "off.npz")
    miss = _python(RUN, folder, tmp_path / "miss.npz")
    hit = _python(RUN, folder, tmp_path / "hit.npz")
    assert (off["compiled"], off["saved"]) == (1, 0)
    assert (miss["compiled"], miss["saved"]) == (1, 1)
    assert (hit["compiled"], hit["loaded"]) == (0, 1)
    runs = [np.load(tmp_path / f"{name}.npz") for name in ("off", "miss", "hit")]
    assert set(runs[0].files) >= {"t_s", "pan_m", "tire_force_N", "p1_Pa", "p2_Pa", "spool"}
    assert np.ptp(runs[0]["p1_Pa"]) > 0  # the actuators really worked
    for name in runs[0].files:
        for other in runs[1:]:
            assert np.array_equal(runs[0][name], other[name]), name
