"""Readers bounded by what they hold: memory and time follow the file, a rate cap on every format,
and RPC III's sample count and byte order held to the data.

Each hostile file is read in a child process (3 GB of address space: a regression fails the
test, not the machine) whose own peak memory (VmHWM) and reading time are measured: a refusal is
one :class:`MeasuredDataError` sentence naming the file, the field and the fix, within
:data:`QUICK_S` and :data:`PEAK_BYTES`; a file that is good reads right within the same bounds.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from types import SimpleNamespace

import numpy as np
import pytest

from rigsim.correction.io.measured import MeasuredDataError, read_channels, write_channels
from rigsim.correction.io.measured_csv import MAX_COLUMNS
from rigsim.correction.io.measured_time import MAX_RATE_HZ
from rigsim.correction.io.rpc3 import write_rpc3

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

#: Seconds a refusal or a read of these files may take, and its peak memory (bytes).
QUICK_S, PEAK_BYTES = 10.0, 1 << 30

_CHILD = textwrap.dedent("""
    import json, resource, sys, time
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
    from rigsim.correction.io.measured import MeasuredDataError, read_channels
    t0 = time.perf_counter()
    try:
        mc = read_channels(sys.argv[1])
        out = {"read": {n: mc.data[n][:4].tolist() for n in list(mc.data)[:4]}, "n": mc.n_samples, "fs": mc.fs_hz}
    except MeasuredDataError as exc:
        out = {"error": str(exc)}
    out["seconds"] = time.perf_counter() - t0
    hwm = next(line for line in open("/proc/self/status") if line.startswith("VmHWM:"))
    out["peak"] = int(hwm.split()[1]) * 1024
    print(json.dumps(out))
""")


def _measured(path) -> dict:
    done = subprocess.run([sys.executable, "-c", _CHILD, str(path)], capture_output=True, text=True, timeout=60,
                          check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    out = json.loads(done.stdout)
    assert out["seconds"] < QUICK_S and out["peak"] < PEAK_BYTES, out
    return out


def _refusal(path, *fragments) -> str:
    out = _measured(path)
    msg = out.get("error")
    assert msg is not None, out
    assert "\n" not in msg and repr(str(path)) in msg and "fix:" in msg and len(msg) < 500, msg
    for f in fragments:
        assert f in msg, (f, msg)
    return msg


def _lines(path, head: str, rows) -> None:
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(head + "\n")
        fh.writelines(r + "\n" for r in rows)


# ------------------------------------------------------------------ the CSV sniffer: memory of the file

def test_a_long_note_in_the_first_rows_reads_in_the_memory_of_the_file(tmp_path):
    """300 kB of note in the first rows of a 690 kB file: the layout's fields were one fixed-width
    array of rows x columns x the longest field (2.9 GB here)."""
    p = tmp_path / "note.csv"
    _lines(p, "time,F [N],note", (f"{i / 1000!r},{i % 7}.5,{'x' * 300_000 if i == 1 else ''}" for i in range(34_000)))
    assert 650e3 < p.stat().st_size < 730e3
    out = _measured(p)
    assert out["n"] == 34_000 and out["fs"] == 1000.0 and out["read"]["F"] == [0.5, 1.5, 2.5, 3.5], out
    assert out["peak"] < 200e6, out


def test_notes_in_many_text_columns_read_in_the_memory_of_the_file(tmp_path):
    p = tmp_path / "notes.csv"
    notes = ",".join(["y" * 3000] * 100)
    _lines(p, "time,F," + ",".join(f"n{j}" for j in range(100)),
           (f"{i / 1000!r},{i % 7}.5," + (notes if i < 2 else ",".join(["ok"] * 100)) for i in range(5000)))
    out = _measured(p)
    assert out["n"] == 5000 and list(out["read"]) == ["F"] and out["peak"] < 200e6, out


def test_a_note_in_a_column_read_is_refused_naming_it_briefly(tmp_path):
    p = tmp_path / "sel.csv"
    _lines(p, "time,F", (f"{i / 1000!r}," + ("z" * 300_000 if i == 9000 else f"{i % 7}.5") for i in range(20_000)))
    _refusal(p, "column 'F' is not numeric at line 9002", "(300000 characters)")


def test_a_header_of_a_million_columns_is_refused_before_it_is_split(tmp_path):
    """37-70 GiB when the layout's arrays were sized by it."""
    p = tmp_path / "wide.csv"
    m = 10 ** 6
    _lines(p, "time," + ",".join(f"c{j}" for j in range(m)), (f"{i / 1000}," + ",".join(["1"] * m) for i in range(2)))
    msg = _refusal(p, "the header (line 1)", f"has {m + 1} fields, more than the {MAX_COLUMNS} columns",
                   "fix: export only the channels needed")
    assert MAX_COLUMNS == 16384, msg


def test_a_data_line_of_millions_of_fields_is_refused(tmp_path):
    p = tmp_path / "line.csv"
    _lines(p, "time,F", ["0.0," + ",".join(["1"] * 2_000_000)] + [f"{i / 1000!r},1.5" for i in range(1, 100)])
    _refusal(p, "line 2 of", "has 2000001 fields but the header has 2")


@pytest.mark.parametrize("length", [1000, 5000, 300_000])
def test_a_very_long_number_is_no_sample(tmp_path, length):
    """Digits only: a number too large for float64, a missing sample, read in a time that follows
    the field (numpy's parse of one field of 300 000 digits into a fixed-width array takes 0.4 s and
    grows faster than the field); the message shows the start of the field and its length."""
    p = tmp_path / "digits.csv"
    _lines(p, "time,F", (f"{i / 1000!r}," + ("1" * length if i in (700, 1200) else "2.5") for i in range(2000)))
    _refusal(p, "column 'F' has '1111", "at line 702", f"({length} characters)")


# ------------------------------------------------------------------ a rate cap on every format

@pytest.mark.parametrize("fs", [1e9, 2e6])
def test_a_csv_faster_than_the_cap_is_refused_before_its_data_are_read(tmp_path, fs):
    """A 1 GHz file took 5.4 GB; now refused from its first lines: the memory of a 10 MB file stays
    that of its first lines."""
    p = tmp_path / "fast.csv"
    _lines(p, "time,F", (f"{i / fs!r},{i % 5}.0" for i in range(400_000)))
    assert p.stat().st_size > 5e6
    msg = _refusal(p, f"a rate of {fs:.4g} Hz, above the {MAX_RATE_HZ:g} Hz", "line 3 of")
    assert _measured(p)["seconds"] < 1.0, msg


@pytest.mark.parametrize("ext, module", [(".mf4", "asammdf"), (".tdms", "nptdms")])
def test_a_lab_file_faster_than_the_cap_is_refused(tmp_path, ext, module):
    pytest.importorskip(module)
    t = np.arange(1000) * 1e-8
    p = write_channels(tmp_path / f"fast{ext}", SimpleNamespace(time_s=t, data={"F": np.ones(1000)}, units={}))
    with pytest.raises(MeasuredDataError, match=r"a rate of 1e\+08 Hz, above the 1e\+06 Hz .*fix: check the time's unit"):
        read_channels(p)


def test_the_rate_cap_reads_and_a_step_below_it_is_refused(tmp_path):
    p = tmp_path / "cap.csv"
    _lines(p, "time_us,F", (f"{i},1.0" for i in range(3000)))  # 1 MHz: read
    assert read_channels(p).fs_hz == MAX_RATE_HZ
    _lines(p, "time_us,F", (f"{i / 2},1.0" for i in range(3000)))  # 2 MHz
    with pytest.raises(MeasuredDataError, match=r"steps 5e-07 s at line 3 of .*a rate of 2e\+06 Hz"):
        read_channels(p)


# ------------------------------------------------------------------ RPC III: SAMPLES and the byte order

FS = 1000.0


def _rsp(tmp_path, n=1500, channels=2, name="r.rsp", seed=0) -> tuple:
    rng = np.random.default_rng(seed)
    data = 5e3 * rng.standard_normal((channels, n)) + 2e4
    p = tmp_path / name
    write_rpc3(p, [f"F{k}" for k in range(channels)], ["N"] * channels, data, 1.0 / FS)
    return p, data


def _set(path, key: str, value: str) -> None:
    """Header record ``key`` given ``value`` (same record, NUL-padded)."""
    raw = bytearray(path.read_bytes())
    at = raw.index(key.encode("latin-1").ljust(32, b"\0"))
    raw[at + 32:at + 128] = value.encode("latin-1").ljust(96, b"\0")
    path.write_bytes(bytes(raw))


def _data_offset(path) -> int:
    from rigsim.correction.io.rpc3 import read_rpc3

    return int(read_rpc3(path).header["NUM_HEADER_BLOCKS"]) * 512


@pytest.mark.parametrize("samples", ["2049", "4096", "1e9", "99999999999999999999"])
def test_samples_beyond_the_frames_present_are_refused(tmp_path, samples):
    """1500 samples in one group of 2 frames of 1024: SAMPLES above 2048 read the padding as data."""
    p, _ = _rsp(tmp_path)
    _set(p, "SAMPLES", samples)
    _refusal(p, f"has SAMPLES = {samples!r} but its FRAMES 2 x PTS_PER_FRAME 1024 hold 2048 samples",
             "fix: set SAMPLES to the samples recorded (at most 2048)")


@pytest.mark.parametrize("samples", ["1500", "1000", "2048"])
def test_samples_within_the_frames_read_that_many(tmp_path, samples):
    p, data = _rsp(tmp_path)
    _set(p, "SAMPLES", samples)
    mc = read_channels(p)
    assert mc.n_samples == int(samples)
    np.testing.assert_allclose(mc.data["F0"][:1000], data[0, :1000], atol=np.abs(data[0]).max() / 32752)


def _swap_data(path) -> None:
    """The same file written big-endian: its data bytes swapped, FORMAT set to say so."""
    off = _data_offset(path)
    raw = path.read_bytes()
    path.write_bytes(raw[:off] + np.frombuffer(raw[off:], "<i2").astype(">i2").tobytes())
    _set(path, "FORMAT", "BINARY_IEEE_BIG_END")


@pytest.mark.parametrize("swapped", [False, True], ids=["little_read_big", "big_read_little"])
def test_a_byte_order_the_limits_contradict_is_refused_naming_format_and_the_fix(tmp_path, swapped):
    """Read in the wrong order, 20 kN forces came out as values of +-160 kN; the file's own
    LOWER_LIMIT/UPPER_LIMIT say which order is right."""
    p, data = _rsp(tmp_path)
    if swapped:
        _swap_data(p)
        good = read_channels(p)  # big-endian as FORMAT says: right
        np.testing.assert_allclose(good.data["F1"], data[1], atol=np.abs(data[1]).max() / 32752)
    wrong, right = ("BINARY_IEEE_LITTLE_END", "BINARY_IEEE_BIG_END") if swapped else (
        "BINARY_IEEE_BIG_END", "BINARY_IEEE_LITTLE_END")
    _set(p, "FORMAT", wrong)
    _refusal(p, f"has FORMAT = {wrong!r}", "LOWER_LIMIT.CHAN_1", f"fix: set FORMAT to {right!r}")


def test_a_byte_order_without_limits_or_with_stale_limits_is_read_as_declared(tmp_path):
    p, data = _rsp(tmp_path)
    _set(p, "UPPER_LIMIT.CHAN_1", "10.0")  # stale: the declared order is outside, and so is the other
    mc = read_channels(p)
    np.testing.assert_allclose(mc.data["F0"], data[0], atol=np.abs(data[0]).max() / 32752)
    for c in (1, 2):
        _set(p, f"LOWER_LIMIT.CHAN_{c}", "")
    _set(p, "FORMAT", "BINARY_IEEE_BIG_END")
    assert read_channels(p).n_samples == 1500  # nothing says the order is wrong: read as declared


SETTINGS = settings(max_examples=40, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@st.composite
def loads(draw):
    """(samples, channels, mean, spread): a noise around a mean at least twice its spread away
    from 0, N, as a wheel's load cell gives under the truck's weight. (A channel around 0 filling
    the int16 scale both ways reads within its limits in either byte order: they cannot tell.)"""
    spread = draw(st.floats(1.0, 2e4))
    return (draw(st.integers(50, 3000)), draw(st.integers(1, 4)),
            draw(st.floats(2.0, 20.0)) * spread * draw(st.sampled_from([-1.0, 1.0])), spread)


@SETTINGS
@given(case=loads(), seed=st.integers(0, 2 ** 16))
def test_any_load_read_in_the_wrong_byte_order_is_refused(tmp_path_factory, case, seed):
    """Written by this module, read back right as written and refused with the other byte order declared."""
    n, channels, level, spread = case
    d = tmp_path_factory.mktemp("order")
    rng = np.random.default_rng(seed)
    data = level + spread * rng.standard_normal((channels, n))
    p = d / "r.rsp"
    write_rpc3(p, [f"F{k}" for k in range(channels)], ["N"] * channels, data, 1.0 / FS)
    np.testing.assert_allclose(read_channels(p).array().T, data, atol=np.abs(data).max() / 32752 * 0.51)
    _set(p, "FORMAT", "BINARY_IEEE_BIG_END")
    with pytest.raises(MeasuredDataError, match=r"has FORMAT = 'BINARY_IEEE_BIG_END'.*fix: set FORMAT to "
                                                r"'BINARY_IEEE_LITTLE_END'"):
        read_channels(p)
