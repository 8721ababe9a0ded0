"""One writer per output file, and channel-filter texts refused before any work.

Two commands writing the same file: the first claims it before its work (correction/io/claim.py),
the second is refused at once in one sentence (exit 2, nothing written), ``--force`` or not, and
the first's file is intact. The first writer is held inside its write (after its own check that
the file is free, where two unclaimed writers both pass) while the second runs: in a thread of
this process, or as another process holding the claim. A file that another program puts there
meanwhile is left as it is. Nothing is left behind (no claim, no temporary file) after success,
an error, an interrupt, SIGTERM; a claim a killed writer left is taken over.

The channel-filter texts of ``--force-filter`` and ``--lvdt-filter`` (``rigsim correct``,
``rigsim identify --from-file``) are held to the bad-input matrix's rules
(tests/scenarios/cli/test_bad_inputs.py): exit 2, one line naming the option and the form or the
range, no work, the folder unchanged.
"""

from __future__ import annotations

import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest

import rigsim.correction.io.measured_csv
from rigsim.correction.io.claim import claim_file
from rigsim.scenarios.cli.main import main
from tests.scenarios.cli.test_bad_inputs import (GOOD, GOOD_ACTUATOR, _import_everything, _listing, _measured_csv,
                                                 _one_error)

ROOT = pathlib.Path(__file__).resolve().parents[3]
ENV = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""), "MUJOCO_GL": "disable"}
WAIT_S = 60.0  # s; the longest a test waits for another writer


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    _import_everything()
    d = tmp_path_factory.mktemp("writers_in")
    _measured_csv(d / "rig.csv")
    (d / "act.toml").write_text(GOOD_ACTUATOR)
    (d / "good.toml").write_text(GOOD)
    return d


@pytest.fixture
def no_work(monkeypatch):
    """The actuator fit and the simulation fail the test if they are reached."""
    import rigsim.correction.identification.actuator_fit
    from rigsim.scenarios.core.rig import Rig

    def work(what):
        def fail(*a, **k):
            raise AssertionError(f"{what} started: the bad input was not refused before the work")
        return fail

    monkeypatch.setattr(Rig, "run", work("a simulation (Rig.run)"))
    monkeypatch.setattr(rigsim.correction.identification.actuator_fit, "fit_actuator", work("the actuator fit"))


def _correct(inputs, out, *extra) -> list[str]:
    return ["correct", str(inputs / "rig.csv"), "--actuator", str(inputs / "act.toml"), "--columns", "fl_N",
            "-o", str(out), "--quiet", *extra]


def _refused(capsys, code, *words) -> str:
    err = capsys.readouterr().err
    assert code == 2, err
    _one_error(err, from_argparse=False)
    for word in words:
        assert word in err, err
    return err


def _hold_write(monkeypatch, who: str, folder: pathlib.Path):
    """Make the thread named ``who`` wait inside its CSV write into ``folder`` (its check that the
    file is free passed; the scratch file of its check before the work is let through) until the
    returned ``go`` is set; ``writing`` is set when it gets there."""
    writing, go = threading.Event(), threading.Event()
    original = rigsim.correction.io.measured_csv.write_csv

    def write_csv(path, *args, **kwargs):
        if threading.current_thread().name == who and pathlib.Path(path).parent == folder:
            writing.set()
            assert go.wait(WAIT_S)
        return original(path, *args, **kwargs)

    monkeypatch.setattr(rigsim.correction.io.measured_csv, "write_csv", write_csv)
    return writing, go


def _in_thread(argv, name: str):
    codes = {}
    thread = threading.Thread(target=lambda: codes.setdefault(name, main(argv)), name=name, daemon=True)
    thread.start()
    return thread, codes


def test_a_second_writer_of_the_same_file_is_refused_and_the_first_file_kept(inputs, tmp_path, capsys, monkeypatch):
    out = tmp_path / "x.csv"
    writing, go = _hold_write(monkeypatch, "first", tmp_path)
    first, codes = _in_thread(_correct(inputs, out, "--transient", "mark"), "first")
    try:
        assert writing.wait(WAIT_S)  # the first is writing: it has checked that x.csv is free
        for extra in ((), ("--force",)):  # a second writer, with or without --force
            err = _refused(capsys, main(_correct(inputs, out, *extra)), "-o", str(out), "another command",
                           f"pid {os.getpid()}")
            assert "name another file" in err
            assert not out.exists()
    finally:
        go.set()
        first.join(WAIT_S)
    assert codes == {"first": 0}
    assert "settled" in out.read_text()  # the first's file (--transient mark), whole
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.csv"]  # no claim, no temporary file


@pytest.mark.parametrize("force", [False, True])
def test_a_file_that_appears_meanwhile_is_replaced_only_with_force(inputs, tmp_path, capsys, monkeypatch, force):
    out = tmp_path / "x.csv"
    writing, go = _hold_write(monkeypatch, "first", tmp_path)
    first, codes = _in_thread(_correct(inputs, out, *(("--force",) if force else ())), "first")
    try:
        assert writing.wait(WAIT_S)
        out.write_text("another program's\n")
    finally:
        go.set()
        first.join(WAIT_S)
    if force:
        assert codes == {"first": 0} and "fl_N_corrected" in out.read_text()
    else:
        _refused(capsys, codes["first"], "-o", str(out), "another program", "--force")
        assert out.read_text() == "another program's\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.csv"]


@pytest.mark.parametrize("stop", [KeyboardInterrupt, OSError])
def test_an_error_or_interrupt_leaves_nothing(inputs, tmp_path, capsys, monkeypatch, stop):
    out = tmp_path / "new" / "deeper" / "x.csv"  # folders the claim makes are taken back too

    def write_csv(path, *args, **kwargs):
        pathlib.Path(path).write_text("half")
        raise stop("stopped")

    monkeypatch.setattr(rigsim.correction.io.measured_csv, "write_csv", write_csv)
    assert main(_correct(inputs, out)) == (130 if stop is KeyboardInterrupt else 2)
    capsys.readouterr()
    assert list(tmp_path.iterdir()) == []


HOLDER = """
import sys, time
from rigsim.correction.io.claim import claimed_output
with claimed_output(sys.argv[1]):
    print("held", flush=True)
    sys.stdin.readline()
"""


def _holder(path) -> subprocess.Popen:
    """Another process holding the claim of ``path`` until its stdin closes."""
    proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(path)], env=ENV, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline() == "held\n"
    return proc


def test_a_writer_in_another_process_is_refused_and_a_killed_ones_claim_is_taken_over(inputs, tmp_path, capsys):
    out = tmp_path / "x.csv"
    holder = _holder(out)
    try:
        _refused(capsys, main(_correct(inputs, out)), "-o", str(out), f"pid {holder.pid}")
        assert sorted(p.name for p in tmp_path.iterdir()) == [claim_file(out).name]
    finally:
        holder.kill()  # killed: its claim file stays, its lock goes with it
        holder.wait()
    assert claim_file(out).exists()
    assert main(_correct(inputs, out)) == 0
    capsys.readouterr()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.csv"]


def test_a_recording_another_process_writes_is_refused_before_the_run(inputs, tmp_path, capsys, no_work):
    rrd = tmp_path / "x.rrd"
    holder = _holder(rrd)
    try:
        code = main(["run", str(inputs / "good.toml"), "--out", str(tmp_path / "run"), "--rrd", str(rrd), "--quiet"])
        _refused(capsys, code, "--rrd", str(rrd), "another command")
    finally:
        holder.stdin.close()
        holder.wait(WAIT_S)
    assert list(tmp_path.iterdir()) == []


HOOK = """
import os
if os.environ.pop("RIGSIM_WRITERS_TEST", None) == "1":
    import time
    import rigsim.correction.io.measured_csv

    def write_csv(path, *args, **kwargs):
        open(path, "w").write("half")
        open(os.environ["RIGSIM_WRITING"], "w").close()
        time.sleep(60)

    rigsim.correction.io.measured_csv.write_csv = write_csv
"""


def test_sigterm_leaves_no_claim(inputs, tmp_path):
    hook, out, writing = tmp_path / "hook", tmp_path / "out" / "x.csv", tmp_path / "writing"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(textwrap.dedent(HOOK))
    env = {**ENV, "PYTHONPATH": os.pathsep.join([str(hook), ENV["PYTHONPATH"]]), "RIGSIM_WRITERS_TEST": "1",
           "RIGSIM_WRITING": str(writing)}
    proc = subprocess.Popen([sys.executable, "-m", "rigsim.scenarios.cli.main", *_correct(inputs, out)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        t0 = time.monotonic()
        while not writing.exists() and proc.poll() is None and time.monotonic() - t0 < WAIT_S:
            time.sleep(0.02)
        assert writing.exists(), proc.communicate()
        assert claim_file(out).exists()  # claimed while it writes
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=WAIT_S)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 143, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hook", "writing"]  # out/ made for the claim: gone


# ------------------------------------------------------------------- channel-filter texts
FILTER_CASES = [
    # (what, argv after the input, words the sentence holds)
    ("two_kinds", ["--force-filter", "200:4:bessel:butterworth"], ["--force-filter", "HZ[:ORDER[:KIND][:DOMAIN]]"]),
    ("two_domains", ["--force-filter", "200:4:digital:analog"], ["--force-filter", "HZ[:ORDER[:KIND][:DOMAIN]]"]),
    ("same_kind_twice", ["--force-filter", "200:4:bessel:bessel"], ["--force-filter", "kinds given"]),
    ("five_words", ["--force-filter", "200:4:bessel:digital:analog"], ["--force-filter", "domains given"]),
    ("corner_tiny", ["--force-filter", "1e-300"], ["--force-filter", "from 1 Hz to below half the record's rate"]),
    ("corner_low", ["--force-filter", "0.5"], ["--force-filter", "from 1 Hz"]),
    ("corner_zero", ["--force-filter", "0"], ["--force-filter", "from 1 Hz"]),
    ("corner_negative", ["--force-filter", "-200"], ["--force-filter", "from 1 Hz"]),
    ("corner_nan", ["--force-filter", "nan"], ["--force-filter", "from 1 Hz"]),
    ("corner_inf", ["--force-filter", "inf:4"], ["--force-filter", "from 1 Hz"]),
    ("corner_nyquist", ["--force-filter", "500"], ["--force-filter", "half the record's rate (500 Hz)"]),
    ("corner_huge", ["--force-filter", "1e300:2:digital"], ["--force-filter", "half the record's rate (500 Hz)"]),
]
_LVDT = ["--identify", "drive_m,pan_m", "--columns", "fl_N"]
FILTER_CASES += [
    ("lvdt_two_kinds", [*_LVDT, "--lvdt-filter", "150:4:bessel:butterworth"], ["--lvdt-filter", "HZ[:ORDER"]),
    ("lvdt_corner_tiny", [*_LVDT, "--lvdt-filter", "1e-300"], ["--lvdt-filter", "from 1 Hz"]),
    ("lvdt_corner_nyquist", [*_LVDT, "--lvdt-filter", "700:4:digital"], ["--lvdt-filter", "half the record's rate"]),
]


@pytest.mark.parametrize("argv, words", [pytest.param(a, w, id=i) for i, a, w in FILTER_CASES])
def test_correct_refuses_a_bad_channel_filter(inputs, tmp_path, capsys, no_work, argv, words):
    out = tmp_path / "x.csv"
    before = _listing(inputs)
    timing = [] if "--identify" in argv else ["--actuator", str(inputs / "act.toml"), "--columns", "fl_N"]
    code = main(["correct", str(inputs / "rig.csv"), *timing, *argv, "-o", str(out), "--quiet"])
    _refused(capsys, code, *words)
    assert _listing(inputs) == before and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("spec, words", [("150:4:bessel:butterworth", "HZ[:ORDER"), ("1e-300", "from 1 Hz"),
                                         ("600", "half the record's rate")])
def test_identify_refuses_a_bad_lvdt_filter(inputs, tmp_path, capsys, no_work, spec, words):
    before = _listing(inputs)
    code = main(["identify", "--from-file", str(inputs / "rig.csv"), "--pairs", "fl=drive_m:pan_m", "--lvdt-filter",
                 spec, "--out", str(tmp_path / "id"), "--quiet"])
    _refused(capsys, code, "--lvdt-filter", words)
    assert _listing(inputs) == before and list(tmp_path.iterdir()) == []
