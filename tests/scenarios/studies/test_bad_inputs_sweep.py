"""rigsim sweep refuses a grid too large and a scheduler it cannot use at once, and ends cleanly.

* A grid's number of cases is known from the lengths of its lists: an axis of a million values,
  a ``[[cases]]`` list of a million tables, a product of axes over the cap are refused before
  any value is looked at (the TOML parse of a big file is tomllib's and comes first).
* ``--scheduler``: an address that is not ``tcp://HOST:PORT`` (or ``tls://`` with Dask's TLS
  settings) is refused before any connection; a peer that accepts the connection and stays
  silent, one that sends random bytes and one that answers in HTTP are each refused in one
  sentence naming ``--scheduler`` and the address, exit 2, within the connection timeout plus a
  margin. The servers are the test's own, on 127.0.0.1 only.
* SIGTERM during a sweep on the process pool: exit 143, no traceback from the pool's threads.

Everything that could hang runs in a subprocess with a hard timeout, so a hang fails the test.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import json
import os
import pathlib
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time
import tomllib

import pytest

from rigsim.scenarios.cli.main import main
from rigsim.scenarios.studies.sweep.grid import MAX_CASES
from rigsim.scenarios.studies.sweep.scheduler import CONNECT_TIMEOUT_S

ROOT = pathlib.Path(__file__).resolve().parents[3]
LOOPBACK = "127.0.0.1"

BASE = textwrap.dedent("""
    [sweep]
    name = "t"

    [base]
    name = "t"
    speed_kmh = 72.0
    duration_s = 5.0
    lead_in_s = 0.5
    seed = 3
    road = { roughness = "high" }
    """)

#: s allowed on top of a deadline for the subprocess's start (imports) and the grid's load, on a
#: machine shared with other work.
MARGIN_S = 10.0


def _env(**extra: str) -> dict[str, str]:
    """The environment of a rigsim subprocess: this checkout first on the path, no Dask settings
    of the user's (a TLS configuration would change what tls:// does)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("DASK_")}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    return {**env, **extra}


def _rigsim(args: list[str], cwd: pathlib.Path, timeout_s: float) -> tuple[subprocess.CompletedProcess, float]:
    """``python -m rigsim.scenarios.cli.main ARGS``, killed after ``timeout_s`` (the test then fails)."""
    t0 = time.monotonic()
    try:
        proc = subprocess.run([sys.executable, "-m", "rigsim.scenarios.cli.main", *args], check=False, cwd=cwd,
                              env=_env(DASK_CONFIG=str(cwd / "no-dask-config")), capture_output=True, text=True,
                              timeout=timeout_s)
    except subprocess.TimeoutExpired as exc:
        pytest.fail(f"rigsim {' '.join(args)} did not end within {timeout_s:g} s; stderr: {exc.stderr!r}")
    return proc, time.monotonic() - t0


def _one_error(stderr: str) -> str:
    """The single line of ``stderr``: ``rigsim: error: ...``, no traceback."""
    assert "Traceback" not in stderr and "Exception" not in stderr, stderr
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rigsim: error: "), stderr
    return lines[0]


# ------------------------------------------------------------------------------ grid size
def test_an_axis_of_a_million_values_is_refused_within_seconds(tmp_path):
    grid = tmp_path / "big.toml"
    grid.write_text(BASE + "\n[axes]\nseed = [" + ", ".join(map(str, range(10**6))) + "]\n")
    t0 = time.perf_counter()
    with open(grid, "rb") as fh:
        tomllib.load(fh)
    parse_s = time.perf_counter() - t0  # tomllib's share, ~1.6 s on a quiet machine
    proc, took = _rigsim(["sweep", str(grid), "--out", str(tmp_path / "out"), "--quiet"], tmp_path, 120)
    assert proc.returncode == 2, proc.stderr
    line = _one_error(proc.stderr)
    assert line == (f"rigsim: error: big.toml: axis seed has 1000000 values, more than the cap of {MAX_CASES} "
                    "cases; split the grid into several grids or give the axis fewer values")
    assert took < parse_s + MARGIN_S, (took, parse_s)
    assert not (tmp_path / "out").exists()


def test_the_cap_is_checked_from_the_lengths_before_any_value(tmp_path):
    """In memory (no TOML parse): every refusal within a second, whatever the size of the lists."""
    code = textwrap.dedent("""
        import json, time
        from rigsim.scenarios.core.config import ScenarioError
        from rigsim.scenarios.studies.sweep.grid import parse_grid

        base = {"sweep": {"name": "t"}, "base": {"name": "t", "speed_kmh": 72.0, "duration_s": 5.0,
                                                 "road": {"roughness": "high"}}}
        docs = {
            "axis_1e6": {"axes": {"seed": [7] * 10**6}},
            "axis_1e7": {"axes": {"seed": [7] * 10**7}},
            "cases_1e6": {"cases": [{"seed": 7}] * 10**6},
            "product": {"axes": {"seed": list(range(9000)), "speed_kmh": list(range(1, 9001)),
                                 "lead_in_s": [0.5, 1.0]}},
        }
        out = {}
        for name, part in docs.items():
            t0 = time.perf_counter()
            try:
                parse_grid({**base, **part})
                out[name] = ["accepted", 0.0]
            except ScenarioError as exc:
                out[name] = [str(exc), time.perf_counter() - t0]
        print(json.dumps(out))
        """)
    try:
        proc = subprocess.run([sys.executable, "-c", code], check=False, cwd=tmp_path, env=_env(),
                              capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        pytest.fail("a grid over the cap was not refused within 120 s")
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout)
    assert got["axis_1e6"][0].startswith("axis seed has 1000000 values, more than the cap")
    assert got["axis_1e7"][0].startswith("axis seed has 10000000 values, more than the cap")
    assert got["cases_1e6"][0] == (f"[[cases]] lists 1000000 cases, more than the cap of {MAX_CASES}; "
                                   "split the grid into several grids")
    assert got["product"][0].startswith("the grid has 162000000 cases (9000 seed x 9000 speed_kmh x 2 lead_in_s)")
    for name, (message, took) in got.items():
        assert "\n" not in message
        assert took < 1.0, (name, took)


# ---------------------------------------------------------------------------- --scheduler
@pytest.fixture
def grid(tmp_path) -> pathlib.Path:
    path = tmp_path / "grid.toml"
    path.write_text(BASE + "\n[axes]\nseed = [1, 2]\n")
    return path


@pytest.mark.parametrize("address, message", [
    ("ucx://127.0.0.1:8786", "--scheduler ucx://127.0.0.1:8786: ucx:// needs the distributed-ucxx package"),
    ("tls://127.0.0.1:8786", "--scheduler tls://127.0.0.1:8786: tls:// needs Dask's TLS settings"),
    ("inproc://127.0.0.1/1/1", "--scheduler inproc://127.0.0.1/1/1: inproc:// reaches only a scheduler inside "),
    ("http://127.0.0.1:8787", "--scheduler http://127.0.0.1:8787: http:// is a web address"),
    ("tcp://127.0.0.1", "--scheduler tcp://127.0.0.1 is not an address of the form tcp://HOST:PORT"),
    ("tcp://127.0.0.1:8786/status", "--scheduler tcp://127.0.0.1:8786/status is not an address of the form"),
    ("tcp://127.0.0.1:0", "--scheduler tcp://127.0.0.1:0: port 0 is outside 1-65535"),
    ("tcp://127.0.0.1:65536", "--scheduler tcp://127.0.0.1:65536: port 65536 is outside 1-65535"),
    ("", "--scheduler '' is not an address of the form tcp://HOST:PORT"),
])
def test_an_unusable_scheduler_address_is_refused_before_connecting(grid, tmp_path, address, message, capsys,
                                                                     monkeypatch):
    import dask
    import distributed.comm.core

    def no_connection(*args, **kwargs):
        raise AssertionError("a connection was attempted")

    monkeypatch.setattr(distributed.comm.core, "connect", no_connection)
    monkeypatch.setattr(distributed.comm, "connect", no_connection)
    monkeypatch.setattr(distributed, "Client", no_connection)
    t0 = time.perf_counter()
    with dask.config.set({"distributed.comm.tls.ca-file": None, "distributed.comm.tls.client.cert": None,
                          "distributed.comm.tls.client.key": None}):
        code = main(["sweep", str(grid), "--out", str(tmp_path / "out"), "--scheduler", address, "--quiet"])
    line = _one_error(capsys.readouterr().err)
    assert code == 2 and line.startswith(f"rigsim: error: {message}"), line
    assert "tcp://" in line.rpartition(";")[2]  # the fix: the address to give instead
    assert time.perf_counter() - t0 < 10.0  # no connection timeout waited for
    assert not (tmp_path / "out").exists()


class _Peer:
    """A TCP server on 127.0.0.1 (a free port) that is not a Dask scheduler.

    ``kind``: ``"silent"`` accepts and never sends; ``"garbage"`` sends random bytes until the
    client leaves; ``"http"`` reads what the client sends and answers it with an HTTP 400
    response, as a web server does with a request it cannot parse.
    """

    def __init__(self, kind: str):
        self.kind = kind
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.bind((LOOPBACK, 0))
        self.sock.listen(8)
        self.port = self.sock.getsockname()[1]
        self.conns: list[socket.socket] = []
        self.stop = threading.Event()
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while not self.stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(conn)
            if self.kind != "silent":
                threading.Thread(target=self._talk, args=(conn,), daemon=True).start()

    def _talk(self, conn: socket.socket) -> None:
        with contextlib.suppress(OSError):
            if self.kind == "garbage":
                while not self.stop.is_set():
                    conn.sendall(os.urandom(4096))
                    time.sleep(0.01)
            else:
                conn.recv(65536)
                body = b"<html><body>400 Bad Request</body></html>"
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Type: text/html\r\nContent-Length: "
                             + str(len(body)).encode() + b"\r\nConnection: close\r\n\r\n" + body)
                conn.shutdown(socket.SHUT_WR)
                while not self.stop.is_set() and conn.recv(65536):
                    pass

    def close(self) -> None:
        self.stop.set()
        for s in (self.sock, *self.conns):
            with contextlib.suppress(OSError):
                s.close()


@pytest.mark.parametrize("kind, says", [
    ("silent", f"nothing answered there as a Dask scheduler within {CONNECT_TIMEOUT_S:g} s"),
    ("garbage", "the peer there does not answer as a Dask scheduler"),
    ("http", "the peer there does not answer as a Dask scheduler"),
])
def test_a_peer_that_is_not_a_dask_scheduler_is_refused_in_one_sentence(grid, tmp_path, kind, says):
    peer = _Peer(kind)
    try:
        address = f"tcp://{LOOPBACK}:{peer.port}"
        proc, took = _rigsim(["sweep", str(grid), "--out", str(tmp_path / "out"), "--scheduler", address, "--quiet"],
                             tmp_path, timeout_s=CONNECT_TIMEOUT_S + 90)
    finally:
        peer.close()
    assert proc.returncode == 2, proc.stderr
    line = _one_error(proc.stderr)
    assert line.startswith(f"rigsim: error: --scheduler {address}: {says}"), line
    assert line.endswith("give the address `dask scheduler` prints when it starts (tcp://HOST:8786 by default)"), line
    assert took < CONNECT_TIMEOUT_S + MARGIN_S, took
    assert not (tmp_path / "out").exists()


def test_a_refused_connection_names_its_reason(grid, tmp_path):
    """Nothing listens on the port (a socket bound, never listening): distributed's retries end
    in "Connection refused" at the timeout, not a silent wait."""
    with socket.socket() as held:
        held.bind((LOOPBACK, 0))
        address = f"tcp://{LOOPBACK}:{held.getsockname()[1]}"
        proc, took = _rigsim(["sweep", str(grid), "--out", str(tmp_path / "out"), "--scheduler", address, "--quiet"],
                             tmp_path, timeout_s=CONNECT_TIMEOUT_S + 90)
    assert proc.returncode == 2, proc.stderr
    line = _one_error(proc.stderr)
    assert line.startswith(f"rigsim: error: --scheduler {address}: cannot connect within "
                           f"{CONNECT_TIMEOUT_S:g} s (Connection refused); start a Dask scheduler there"), line
    assert took < CONNECT_TIMEOUT_S + MARGIN_S, took


# -------------------------------------------------------------------------------- SIGTERM
#: The child's case function (through a ``sitecustomize`` on its path, as tests/scenarios/cli/test_sigterm.py
#: does): seed 1 finishes at once, every other case keeps its worker's core busy as a real case
#: does, so the pool's queue is full of cases waiting when the signal comes and the parent's
#: threads compete for the cores.
_HOOK = """
import os
import time


def slow_payload(case_id, doc, source, settings):
    end = time.monotonic() + (0 if doc.get("seed") == 1 else 120)
    while time.monotonic() < end:
        pass
    return {"case_id": case_id, "status": "failed", "error": "stand-in", "retry": False, "result": None,
            "wall_time_s": 0.0}


if os.environ.pop("RIGSIM_SWEEP_SIGTERM_TEST", None) == "1":
    import rigsim.scenarios.studies.sweep.run

    rigsim.scenarios.studies.sweep.run.evaluate_payload = slow_payload
"""


def _terminated_sweep(tmp_path: pathlib.Path, name: str) -> tuple[int, str]:
    """A sweep of 12 cases on 2 workers, as the ``rigsim`` script runs it (``sys.exit(main())``:
    the interpreter's exit joins the pool's threads), sent SIGTERM when its first case is kept."""
    hook = tmp_path / "hook"
    hook.mkdir(exist_ok=True)
    (hook / "sitecustomize.py").write_text(_HOOK)
    grid = tmp_path / f"{name}.toml"
    grid.write_text(BASE + "\n[axes]\nseed = [" + ", ".join(map(str, range(1, 13))) + "]\n")
    out = tmp_path / name
    env = _env(RIGSIM_SWEEP_SIGTERM_TEST="1", MUJOCO_GL="disable")
    env["PYTHONPATH"] = os.pathsep.join([str(hook), env["PYTHONPATH"]])
    script = "import sys\nfrom rigsim.scenarios.cli.main import main\nsys.exit(main())\n"
    proc = subprocess.Popen([sys.executable, "-c", script, "sweep", str(grid), "--out", str(out), "--jobs", "2"],
                            cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not list((out / "cases").glob("*.json")):
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.01)
        time.sleep(0.2)  # the pool refills its queue after the first result
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return proc.returncode, err


def test_an_interrupted_sweep_leaves_the_cases_not_started_to_the_executors_owner(tmp_path, monkeypatch):
    """``run_sweep`` does not cancel the executor's futures on Ctrl-C or SIGTERM: a process
    pool's manager thread fails every future it still holds when its workers are terminated,
    and one cancelled from the main thread makes it raise InvalidStateError (a traceback after
    "rigsim: terminated", whenever the threads interleave so). The owner (``local_executor``,
    ``dask_executor``) cancels them."""
    from rigsim.scenarios.studies.sweep import run as sweep_run
    from rigsim.scenarios.studies.sweep.grid import parse_grid

    release = threading.Event()

    def payload(case_id, doc, source, settings):
        if doc["seed"] != 1:
            release.wait(60)
        return {"case_id": case_id, "status": "failed", "error": "stand-in", "retry": False, "result": None,
                "wall_time_s": 0.0}

    def interrupt(case_id, record):
        raise KeyboardInterrupt

    submitted: list[cf.Future] = []

    class Recording(cf.ThreadPoolExecutor):
        def submit(self, *args, **kwargs):
            submitted.append(super().submit(*args, **kwargs))
            return submitted[-1]

    monkeypatch.setattr(sweep_run, "evaluate_payload", payload)
    g = parse_grid(tomllib.loads(BASE + "\n[axes]\nseed = [1, 2, 3, 4, 5]\n"))
    ex = Recording(1)
    try:
        with pytest.raises(KeyboardInterrupt):
            sweep_run.run_sweep(g, tmp_path / "out", ex, progress=False, plot=False, on_record=interrupt)
        assert len(submitted) == 5 and not any(f.cancelled() for f in submitted)
    finally:
        release.set()
        ex.shutdown(wait=True, cancel_futures=True)


def test_sigterm_during_a_sweep_ends_without_a_traceback(tmp_path):
    """Five terminated sweeps (the pool's race is one of timing): each exits 143 and its stderr
    ends with the sweep's summary and "rigsim: terminated", nothing after, no traceback."""
    for i in range(5):
        code, err = _terminated_sweep(tmp_path, f"run{i}")
        assert code == 143, err
        assert "Traceback" not in err and "InvalidStateError" not in err and "Exception" not in err, err
        lines = err.splitlines()
        assert lines[-1] == "rigsim: terminated", err
        assert lines[-2].startswith("rigsim: sweep interrupted: 1 of 12 cases finished and kept"), err
