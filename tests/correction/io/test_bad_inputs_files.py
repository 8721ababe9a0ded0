"""Input files that block, never end or break a third-party reader, and what a killed writer leaves.

* A named pipe (FIFO) or a device (``/dev/zero``) as a scenario, actuator or measured file is refused
  at once in one sentence naming it and what it is. Each case runs in a subprocess with a timeout
  (and a cap on its memory), so that a reader that waits on the pipe, or reads the device until
  memory runs out, fails the test instead of hanging it or the machine.
* Damaged MDF4 and TDMS files (a valid file cut at several lengths, random bytes, empty, a valid
  header then garbage): the refusal is exactly one line on stderr naming the file (not asammdf's
  memory map), nothing is printed after it (asammdf's ``__del__``, nptdms's warnings), and nothing
  is left in the temporary folder (asammdf's copy of an unfinalised file).
* Any cut or any flipped bytes of a valid MDF4 or TDMS file (hypothesis): the file reads, or one
  MeasuredDataError naming it; never another exception, nothing printed.
* A killed writer's temporary file (named with its host and pid, the output's extension kept) is
  removed by the next write to the same target; a running writer's is kept.
"""

from __future__ import annotations

import contextlib
import gc
import os
import pathlib
import subprocess
import sys
import textwrap
from types import SimpleNamespace

import numpy as np
import pytest

from rigsim.correction.io import atomic

from rigsim.correction.io import measured_core
from rigsim.correction.io.measured import MeasuredDataError, read_channels, write_channels
from rigsim.correction.io.tomlfile import read_toml

ROOT = pathlib.Path(__file__).resolve().parents[3]
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
#: Wall time a refused file may take in a subprocess, s: imports on a loaded machine included. A
#: reader that waits on a pipe never ends; one that reads /dev/zero is stopped by the memory cap.
TIMEOUT_S = 60
#: What the reading itself (in the subprocess, after its imports) may take, s.
AT_ONCE_S = 2.0
#: The address space of a subprocess, bytes: a reader of /dev/zero stops with a MemoryError here
#: instead of taking the machine's memory.
MEMORY_CAP = 4 * 2**30
POSIX = pytest.mark.skipif(os.name != "posix", reason="named pipes, /dev/zero and pids of POSIX")

GOOD_ACTUATOR = "[transfer_function]\nnum = [1.0]\nden = [2.5e-4, 0.02, 1.0]\n"

#: Read one file in a fresh interpreter: exit code 0 when it reads, else the refusal on stderr as
#: the CLI prints it and exit code 2; on stdout the seconds the reading took. Garbage is collected
#: before the exit, so that anything a half-made object prints when collected shows.
READ = textwrap.dedent("""
    import gc, sys, time
    from rigsim.correction.io.measured import MeasuredDataError, read_channels
    from rigsim.correction.io.tomlfile import read_toml
    t0 = time.perf_counter()
    try:
        if sys.argv[1] == "toml":
            read_toml(sys.argv[2], "scenario file", ValueError)
        else:
            read_channels(sys.argv[2])
    except (MeasuredDataError, ValueError) as exc:
        print(f"rigsim: error: {exc}", file=sys.stderr, flush=True)
        code = 2
    else:
        code = 0
    took = time.perf_counter() - t0
    gc.collect()
    print(f"{took:.3f}", flush=True)
    sys.exit(code)
""")


def _cap_memory():  # runs in the child before exec
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))


def _run(argv: list[str], cwd, env=None) -> subprocess.CompletedProcess:
    """``argv`` in a subprocess, memory capped; a run that outlives :data:`TIMEOUT_S` fails the test."""
    try:
        return subprocess.run(argv, cwd=cwd, env=env or ENV, capture_output=True, text=True, timeout=TIMEOUT_S,
                              preexec_fn=_cap_memory if os.name == "posix" else None)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{argv[-3:]} still runs after {TIMEOUT_S} s: the reader waits on its input")


def _one_line(proc: subprocess.CompletedProcess) -> str:
    """The one line a refusal prints on stderr (exit code 2); anything more fails the test."""
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-3000:])
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rigsim: error: "), proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr
    return lines[0]


def _measured_csv(path: pathlib.Path, n: int = 3000) -> pathlib.Path:
    """time [s], a wheel force [N], a drive and a pan displacement [m] at 1 kHz."""
    rng = np.random.default_rng(3)
    t = np.arange(n) / 1000.0
    drive = 0.005 * rng.standard_normal(n)
    rows = zip(t, 30e3 + 1e3 * rng.standard_normal(n), drive, 0.9 * drive, strict=True)
    path.write_text("time [s],fl_N [N],drive_m [m],pan_m [m]\n"
                    + "".join(",".join(f"{v:.9g}" for v in row) + "\n" for row in rows))
    return path


def _dead_pid() -> int:
    """A pid no process of this machine has: one of a child that has ended."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    assert not atomic.pid_running(proc.pid)
    return proc.pid


def _channels(n: int = 100):
    t = np.arange(n) / 1000.0
    return SimpleNamespace(time_s=t, data={"fl_N": 30e3 + np.sin(t)}, units={"fl_N": "N"})


# ------------------------------------------------------------------ pipes and devices: the readers
@POSIX
@pytest.mark.parametrize("kind, name", [("toml", "scenario.toml"), ("measured", "rig.csv"), ("measured", "rig.rsp"),
                                        ("measured", "rig.mf4"), ("measured", "rig.tdms")])
def test_a_named_pipe_is_refused_at_once(tmp_path, kind, name):
    if name.endswith((".mf4", ".tdms")):
        pytest.importorskip("asammdf" if name.endswith(".mf4") else "nptdms")
    fifo = tmp_path / name
    os.mkfifo(fifo)
    proc = _run([sys.executable, "-c", READ, kind, str(fifo)], tmp_path)
    line = _one_line(proc)
    assert repr(str(fifo)) in line and "is a named pipe (FIFO)" in line
    assert float(proc.stdout) < AT_ONCE_S


@POSIX
@pytest.mark.parametrize("kind, name", [("toml", "scenario.toml"), ("measured", "rig.csv"), ("measured", "rig.rsp")])
def test_a_device_is_refused_at_once(tmp_path, kind, name):
    """/dev/zero never ends: named directly, or behind a name with the right extension."""
    if not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero")
    link = tmp_path / name
    link.symlink_to("/dev/zero")
    for path in ([link, pathlib.Path("/dev/zero")] if kind == "toml" else [link]):
        proc = _run([sys.executable, "-c", READ, kind, str(path)], tmp_path)
        line = _one_line(proc)
        assert repr(str(path)) in line and "is a character device" in line
        assert float(proc.stdout) < AT_ONCE_S


@POSIX
def test_a_pipe_put_in_place_after_the_check_cannot_block(tmp_path):
    """The check on the path may be passed by a regular file that a pipe then replaces: the open
    does not wait (O_NONBLOCK) and the check of the open descriptor refuses it."""
    fifo = tmp_path / "swapped.toml"
    os.mkfifo(fifo)
    code = textwrap.dedent(f"""
        import os, stat, sys
        real = os.stat
        os.stat = lambda p, *a, **k: os.stat_result((stat.S_IFREG | 0o644,) + tuple(real(p, *a, **k))[1:])
        from rigsim.correction.io.tomlfile import read_toml
        try:
            read_toml({str(fifo)!r}, "scenario file")
        except ValueError as exc:
            print(f"rigsim: error: {{exc}}", file=sys.stderr)
            sys.exit(2)
    """)
    line = _one_line(_run([sys.executable, "-c", code], tmp_path))
    assert repr(str(fifo)) in line and "is a named pipe (FIFO)" in line


# -------------------------------------------------------------------- pipes and devices: the CLI
@POSIX
@pytest.mark.parametrize("case", ["run_scenario_pipe", "correct_actuator_pipe", "correct_input_pipe",
                                  "run_scenario_zero", "correct_actuator_zero"])
def test_the_cli_refuses_pipes_and_devices_in_one_line(tmp_path, case):
    if "zero" in case and not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero")
    os.mkfifo(tmp_path / "pipe.toml")
    os.mkfifo(tmp_path / "pipe.csv")
    _measured_csv(tmp_path / "rig.csv")
    (tmp_path / "act.toml").write_text(GOOD_ACTUATOR)
    argv, named, kind = {
        "run_scenario_pipe": (["run", "pipe.toml", "--out", "d"], "pipe.toml", "named pipe"),
        "correct_actuator_pipe": (["correct", "rig.csv", "--actuator", "pipe.toml", "-o", "o.csv"], "pipe.toml",
                                  "named pipe"),
        "correct_input_pipe": (["correct", "pipe.csv", "--actuator", "act.toml", "-o", "o.csv"], "pipe.csv",
                               "named pipe"),
        "run_scenario_zero": (["run", "/dev/zero", "--out", "d"], "/dev/zero", "character device"),
        "correct_actuator_zero": (["correct", "rig.csv", "--actuator", "/dev/zero", "-o", "o.csv"], "/dev/zero",
                                  "character device"),
    }[case]
    before = sorted(p.name for p in tmp_path.iterdir())
    line = _one_line(_run([sys.executable, "-m", "rigsim.scenarios.cli.main", *argv], tmp_path))
    assert repr(named) in line and f"is a {kind}" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written


# --------------------------------------------------------------------------- sizes and permissions
def test_a_toml_file_larger_than_any_project_file_is_refused_unread(tmp_path):
    p = tmp_path / "huge.toml"
    with open(p, "wb") as fh:
        fh.truncate(17 * 2**20)  # sparse: 17 MiB of NUL bytes
    with pytest.raises(ValueError) as err:
        read_toml(p, "scenario file")
    assert str(err.value) == (f"scenario file {str(p)!r} is 17 MiB, more than the 16 MiB a TOML file may have; "
                              "check the path")


def test_a_measured_file_larger_than_memory_allows_is_refused_unread(tmp_path, monkeypatch):
    """A reader that holds the whole file (RPC III) refuses one whose reading would not fit."""
    p = write_channels(tmp_path / "rig.rsp", _channels(200))
    monkeypatch.setattr(measured_core, "available_memory_bytes", lambda: 9 * p.stat().st_size - 9)
    with pytest.raises(MeasuredDataError) as err:
        read_channels(p)
    msg = str(err.value)
    assert msg.startswith(f"input file {str(p)!r} is ") and "reading it takes about 9 times that in memory" in msg
    assert "cut the record into shorter files" in msg and "\n" not in msg
    monkeypatch.setattr(measured_core, "available_memory_bytes", lambda: 9 * p.stat().st_size)
    assert read_channels(p).n_samples == 200  # exactly at the limit: read


def test_an_unreadable_file_says_why(tmp_path, monkeypatch):
    """A file the user may not read (root reads any file: the refusal of the open is simulated)."""
    p = tmp_path / "locked.toml"
    p.write_text("a = 1\n", encoding="utf-8")

    def refuse(path, *args, **kwargs):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(atomic.os, "open", refuse)
    with pytest.raises(ValueError) as err:
        read_toml(p, "grid file")
    assert str(err.value) == f"cannot read grid file {str(p)!r}: Permission denied"


# ------------------------------------------------------------------------- damaged MDF4 and TDMS
@pytest.fixture(scope="module")
def lab_files(tmp_path_factory):
    """A valid MDF4 and a valid TDMS file (2 s at 1 kHz: time, a force in kN)."""
    d = tmp_path_factory.mktemp("lab")
    t = np.arange(2000) / 1000.0
    found = {}
    with contextlib.suppress(ImportError):
        import asammdf

        mdf = asammdf.MDF(version="4.10")
        mdf.append([asammdf.Signal(40.0 + np.sin(t), t, name="Fz_FL", unit="kN")], comment="rig")
        mdf.save(str(d / "good.mf4"), overwrite=True)
        mdf.close()
        found[".mf4"] = (d / "good.mf4").read_bytes()
    with contextlib.suppress(ImportError):
        import nptdms

        with nptdms.TdmsWriter(str(d / "good.tdms")) as w:
            w.write_segment([nptdms.ChannelObject("g", "time", t, properties={"unit_string": "s"}),
                             nptdms.ChannelObject("g", "Fz_FL", 40.0 + np.sin(t), properties={"unit_string": "kN"})])
        found[".tdms"] = (d / "good.tdms").read_bytes()
    return found


def _damaged(good: bytes, ext: str) -> dict[str, bytes]:
    """Name -> bytes: the valid file cut at several lengths, random bytes, empty, a valid header then
    random bytes; for MDF4 also an unfinalised file cut short (asammdf copies it to finalise it)."""
    rng = np.random.default_rng(5)
    noise = rng.integers(0, 256, 5000, dtype=np.uint8).tobytes()
    cases = {f"cut_{n}": good[:n] for n in (10, 64, 100, 300, len(good) // 2, len(good) - 7)}
    cases.update(random=noise, empty=b"", header_then_garbage=good[:64 if ext == ".mf4" else 100] + noise)
    if ext == ".mf4":
        unfinalised = bytearray(good)
        unfinalised[:8] = b"UnFinMF "
        unfinalised[60:62] = (1).to_bytes(2, "little")  # update the cycle counters when read
        cases["unfinalised_cut"] = bytes(unfinalised[: len(good) // 2])
    return cases


@pytest.mark.parametrize("ext, module", [(".mf4", "asammdf"), (".tdms", "nptdms")])
def test_damaged_lab_files_are_one_line_each_and_leave_nothing(tmp_path, lab_files, ext, module):
    """Every damaged file in one interpreter, garbage collected after each: between two markers
    on stderr, exactly the refusal, naming the file."""
    pytest.importorskip(module)
    cases = _damaged(lab_files[ext], ext)
    for name, data in cases.items():
        (tmp_path / f"{name}{ext}").write_bytes(data)
    code = textwrap.dedent("""
        import gc, sys
        from rigsim.correction.io.measured import MeasuredDataError, read_channels
        for path in sys.argv[1:]:
            print(f"=== {path}", file=sys.stderr, flush=True)
            try:
                read_channels(path)
                print(f"read {path}", file=sys.stderr, flush=True)
            except MeasuredDataError as exc:
                print(f"rigsim: error: {exc}", file=sys.stderr, flush=True)
            gc.collect()
    """)
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    paths = [str(tmp_path / f"{name}{ext}") for name in cases]
    proc = _run([sys.executable, "-c", code, *paths], tmp_path, env={**ENV, "TMPDIR": str(tmp)})
    assert proc.returncode == 0, proc.stderr[-3000:]
    sections = proc.stderr.split("=== ")[1:]
    assert len(sections) == len(paths), proc.stderr[-3000:]
    bad = {}
    for path, section in zip(paths, sections, strict=True):
        head, *lines = section.splitlines()
        ok = (head == path and len(lines) == 1 and lines[0].startswith("rigsim: error: ")
              and repr(path) in lines[0] and "mmap" not in lines[0])
        if not ok:
            bad[pathlib.Path(path).name] = section[:600]
    assert not bad, bad
    assert list(tmp.iterdir()) == []  # asammdf's copy of the unfinalised file is gone


@pytest.mark.parametrize("ext, module", [(".mf4", "asammdf"), (".tdms", "nptdms")])
def test_the_cli_prints_one_line_for_a_damaged_lab_file(tmp_path, lab_files, ext, module):
    pytest.importorskip(module)
    good = lab_files[ext]
    bad = tmp_path / f"cut{ext}"
    bad.write_bytes(good[: len(good) // 2])
    (tmp_path / "act.toml").write_text(GOOD_ACTUATOR)
    line = _one_line(_run([sys.executable, "-m", "rigsim.scenarios.cli.main", "correct", bad.name, "--actuator", "act.toml",
                           "-o", "o.csv"], tmp_path))
    assert repr(bad.name) in line and "cut short" in line


# ------------------------------------------------------------- property: cut or flipped lab files
def _reads_or_refuses(path: pathlib.Path, capfd) -> None:
    """``path`` reads, or one MeasuredDataError naming it; nothing printed, nothing left to print
    when garbage is collected."""
    caught = []
    hook, sys.unraisablehook = sys.unraisablehook, caught.append
    try:
        try:
            assert read_channels(path).n_samples >= 2
        except MeasuredDataError as exc:
            msg = str(exc)
            assert msg and "\n" not in msg and repr(str(path)) in msg and "mmap" not in msg, msg
        gc.collect()
    finally:
        sys.unraisablehook = hook
    assert not caught, [repr(u.exc_value) for u in caught]
    out, err = capfd.readouterr()
    assert out == "" and err == "", (out[:500], err[:500])


@pytest.mark.parametrize("ext, module", [(".mf4", "asammdf"), (".tdms", "nptdms")])
def test_any_cut_or_flipped_bytes_read_or_refuse(tmp_path, lab_files, capfd, ext, module):
    pytest.importorskip(module)
    pytest.importorskip("hypothesis")
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    good = lab_files[ext]
    path = tmp_path / f"spoiled{ext}"
    cut = st.integers(0, len(good) - 1).map(lambda n: good[:n])
    flips = st.lists(st.tuples(st.integers(0, len(good) - 1), st.integers(0, 255)), min_size=1, max_size=8)

    def flipped(changes) -> bytes:
        out = bytearray(good)
        for i, v in changes:
            out[i] = v
        return bytes(out)

    # Deterministic examples: the readers run asammdf's C code, and a crash there (which no
    # boundary can turn into an exception) must show on every run, not now and then.
    @settings(max_examples=150, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
    @given(data=st.one_of(cut, flips.map(flipped)))
    def check(data):
        path.write_bytes(data)
        _reads_or_refuses(path, capfd)

    check()


# ------------------------------------------------------------------------ a killed writer's leftovers
@POSIX
def test_a_killed_correct_leaves_a_temp_file_the_next_write_removes(tmp_path):
    """A writer killed mid-write (SIGKILL: no handler runs) leaves its temporary file, named with
    its host and pid and the output's extension; the next write to the same output removes it."""
    target = tmp_path / "big.csv"
    code = textwrap.dedent(f"""
        import sys, time
        import numpy as np
        from types import SimpleNamespace
        import rigsim.correction.io.measured_csv as csv
        real = csv.write_csv
        def slow(path, *a, **k):
            real(path, *a, **k)
            print("writing", flush=True)
            time.sleep(600)
        csv.write_csv = slow
        from rigsim.correction.io.measured import write_channels
        t = np.arange(1000) / 1000.0
        write_channels({str(target)!r}, SimpleNamespace(time_s=t, data={{"fl_N": t}}, units={{"fl_N": "N"}}))
    """)
    proc = subprocess.Popen([sys.executable, "-c", code], env=ENV, stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "writing"
        proc.kill()
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    left = [p for p in tmp_path.iterdir() if p.name != target.name]
    assert len(left) == 1 and not target.exists(), left
    assert left[0].name.startswith(f".big.csv.{atomic.host_tag()}.{proc.pid}.") and left[0].name.endswith(".tmp.csv")
    write_channels(target, _channels())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.csv"]


@POSIX
@pytest.mark.parametrize("ext", [".csv", ".rsp", ".tdms"])
def test_a_dead_writers_leftover_goes_and_a_running_ones_stays(tmp_path, ext):
    if ext == ".tdms":
        pytest.importorskip("nptdms")
    target = tmp_path / f"out{ext}"
    host = atomic.host_tag()
    running = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    try:
        dead = tmp_path / f".{target.name}.{host}.{_dead_pid()}.0123abcd.tmp{ext}"
        dead_plain = tmp_path / f".{target.name}.{host}.{_dead_pid()}.4567cdef.tmp"
        alive = tmp_path / f".{target.name}.{host}.{running.pid}.89abcdef.tmp{ext}"
        other_host = tmp_path / f".{target.name}.elsewhere.{_dead_pid()}.0123abcd.tmp{ext}"
        other_target = tmp_path / f".other{ext}.{host}.{_dead_pid()}.0123abcd.tmp{ext}"
        for p in (dead, dead_plain, alive, other_host, other_target):
            p.write_bytes(b"half a file")
        write_channels(target, _channels())
        assert not dead.exists() and not dead_plain.exists()
        assert alive.exists() and other_host.exists() and other_target.exists()
        assert read_channels(target).n_samples == 100
    finally:
        running.kill()
        running.wait()


def test_the_temporary_file_keeps_the_outputs_extension_and_the_usual_mode(tmp_path):
    seen = []
    measured_core.atomic_output(tmp_path / "o.mf4", lambda tmp: (seen.append(tmp), pathlib.Path(tmp).write_bytes(b"x")))
    name = pathlib.Path(seen[0]).name
    assert name.startswith(f".o.mf4.{atomic.host_tag()}.{os.getpid()}.") and name.endswith(".tmp.mf4")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o.mf4"] and (tmp_path / "o.mf4").read_bytes() == b"x"
    if os.name == "posix":  # the mode a new file gets: 0666 less the umask
        umask = os.umask(0o022)
        os.umask(umask)
        assert (tmp_path / "o.mf4").stat().st_mode & 0o777 == 0o666 & ~umask
