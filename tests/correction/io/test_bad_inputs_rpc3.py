"""MTS RPC III files with hostile or careless headers: each is read correctly or refused with one
:class:`MeasuredDataError` sentence naming the file, the key or channel at fault and the fix,
within seconds and in little memory.

The classes: counts beyond what the file holds (CHANNELS = 10^8, 10^18: the reader may not size
anything by them), counts that are no whole number (1e400, inf, nan), a DELTA_T that is no
measured sampling step, a START_TIME whose times float64 cannot tell apart, a zero or non-finite
SCALE.CHAN_n, a key given twice, a NaN or infinite sample; then a property test over generated
header values (hypothesis): any header reads to a consistent result or is refused, quickly.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from rigsim.correction.io.measured import MeasuredDataError, read_channels
from rigsim.correction.io.rpc3 import MAX_DELTA_T_S, MIN_DELTA_T_S, read_rpc3, write_rpc3

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

#: Seconds a refusal may take on a loaded 2-core machine (a small file is read in milliseconds).
QUICK_S = 5.0


def rpc_bytes(params, values: np.ndarray, blocks=None, n_params=None) -> bytes:
    """An RPC III file from the published layout: FORMAT, NUM_HEADER_BLOCKS, NUM_PARAMS first, 128-byte
    records (32-byte key, 96-byte value, latin-1), 512-byte blocks, then ``values`` as given.

    ``params`` is a list of (key, value) (a key may repeat); ``blocks`` and ``n_params``
    (strings) replace the counts that describe the header."""
    count = len(params) + 3
    need = math.ceil(count / 4)
    fmt = dict(params).get("FORMAT", "BINARY_IEEE_LITTLE_END")
    records = [("FORMAT", fmt), ("NUM_HEADER_BLOCKS", blocks or str(need)), ("NUM_PARAMS", n_params or str(count))]
    records += [(k, v) for k, v in params if k != "FORMAT"]
    head = b"".join(k.encode("latin-1").ljust(32, b"\0") + v.encode("latin-1").ljust(96, b"\0") for k, v in records)
    return head.ljust(512 * need, b"\0") + values.tobytes()


def base_params(data_type="SHORT_INTEGER", **changes):
    """Two channels (Fz_FL in kN, x_FL in mm), 4 points a frame, 2 frames a group, 3 frames at 1 kHz:
    a half-filled last group, as in test_measured_rpc3. ``changes``: key (``SCALE_CHAN_1`` for
    ``SCALE.CHAN_1``) -> value, or None to leave the key out."""
    params = {"FILE_TYPE": "TIME_HISTORY", "TIME_TYPE": "RESPONSE", "DELTA_T": "0.001", "CHANNELS": "2",
              "PTS_PER_FRAME": "4", "PTS_PER_GROUP": "8", "FRAMES": "3", "DATA_TYPE": data_type,
              "DESC.CHAN_1": "Fz_FL", "UNITS.CHAN_1": "kN", "SCALE.CHAN_1": "0.5",
              "DESC.CHAN_2": "x_FL", "UNITS.CHAN_2": "mm", "SCALE.CHAN_2": "2.0", "TEST_RIG": "DYNTRAC"}
    for k, v in changes.items():
        key = k.replace("_CHAN_", ".CHAN_")
        if v is None:
            params.pop(key, None)
        else:
            params[key] = v
    return list(params.items())


def base_values(data_type="SHORT_INTEGER") -> np.ndarray:
    """Group 1: ch1 0..7, ch2 100..107; group 2: ch1 8..15, ch2 108..115 (the last 4 of each: padding)."""
    a, b = np.arange(16), 100 + np.arange(16)
    return np.concatenate([a[:8], b[:8], a[8:], b[8:]]).astype("<i2" if data_type == "SHORT_INTEGER" else "<f4")


def write(tmp_path, params, values=None, name="bad.rsp", **counts):
    p = tmp_path / name
    p.write_bytes(rpc_bytes(params, base_values() if values is None else values, **counts))
    return p


def refused(path, *fragments, reader=read_channels) -> str:
    """The one sentence ``reader`` refuses ``path`` with, checked to name the file and ``fragments``."""
    t0 = time.perf_counter()
    with pytest.raises(MeasuredDataError) as exc:
        reader(path)
    seconds = time.perf_counter() - t0
    msg = str(exc.value)
    assert "\n" not in msg and repr(str(path)) in msg, msg
    for f in fragments:
        assert f in msg, (f, msg)
    assert seconds < QUICK_S, (seconds, msg)
    return msg


# ------------------------------------------------------------------ 1. counts beyond the file

_CHILD = textwrap.dedent("""
    import json, resource, sys, time, tracemalloc
    resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))  # a regression fails, not the machine
    from rigsim.correction.io.measured import MeasuredDataError, read_channels
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        read_channels(sys.argv[1])
        error = None
    except MeasuredDataError as exc:
        error = str(exc)
    print(json.dumps({"error": error, "seconds": time.perf_counter() - t0,
                      "peak": tracemalloc.get_traced_memory()[1]}))
""")


@pytest.mark.parametrize("data_type", ["FLOATING_POINT", "SHORT_INTEGER"])
@pytest.mark.parametrize("channels", ["100000000", "1e18", "100000", "1e8"])
def test_a_channel_count_beyond_the_header_is_refused_quickly_in_little_memory(tmp_path, channels, data_type):
    """No count may size anything before it is held to the file: a reader that makes a name per
    claimed channel needs 9.3 GB for 10^8 and minutes for 10^5 (with a check over the names that is
    quadratic), and numpy cannot shape 10^18. Read in a child process with 2 GB of address space
    and a minute, so that a regression fails the test rather than the machine."""
    p = write(tmp_path, base_params(data_type, CHANNELS=channels, FRAMES="0"), np.zeros(0, "<f4"))
    try:
        done = subprocess.run([sys.executable, "-c", _CHILD, str(p)], capture_output=True, text=True, timeout=60,
                              check=False)
    except subprocess.TimeoutExpired:
        pytest.fail(f"CHANNELS = {channels}: still reading after 60 s")
    assert done.returncode == 0, done.stderr[-2000:]
    out = json.loads(done.stdout)
    assert out["error"] is not None and "\n" not in out["error"], out
    assert f"has CHANNELS = {channels!r}, not a whole number of channels the file can hold" in out["error"], out
    assert "fix:" in out["error"], out
    assert out["seconds"] < QUICK_S and out["peak"] < 100e6, out


def test_many_channels_the_file_holds_are_read_in_linear_time(tmp_path):
    """60 000 channels, each with its DESC.CHAN_n, one frame: the checks over the names are linear
    (a count per name would be 3.6e9 comparisons, a minute)."""
    n_ch = 60_000
    params = [("DELTA_T", "0.001"), ("CHANNELS", str(n_ch)), ("PTS_PER_FRAME", "2"), ("PTS_PER_GROUP", "2"),
              ("FRAMES", "1"), ("DATA_TYPE", "FLOATING_POINT")]
    params += [(f"DESC.CHAN_{c}", f"ch{c}") for c in range(1, n_ch + 1)]
    values = np.repeat(np.arange(n_ch, dtype="<f4")[:, None], 2, axis=1)
    p = write(tmp_path, params, values)
    t0 = time.perf_counter()
    mc = read_channels(p)
    assert time.perf_counter() - t0 < QUICK_S
    assert mc.n_samples == 2 and len(mc.names) == n_ch and mc.data[f"ch{n_ch}"][1] == n_ch - 1
    bad = write(tmp_path, params[:-1] + [(f"DESC.CHAN_{n_ch}", "ch1")], values, name="dup.rsp")
    refused(bad, "channel 'ch1' appears more than once")


def test_data_sizes_are_held_to_the_bytes_present(tmp_path):
    """FRAMES or PTS_PER_GROUP far beyond the file: refused by the size in Python ints, exactly."""
    for key, value in (("FRAMES", "1" + "0" * 40), ("PTS_PER_GROUP", str(2 ** 64)), ("PTS_PER_FRAME", "8")):
        p = write(tmp_path, base_params(**{key: value}))
        refused(p, "is truncated: its header asks for", "fix:")
    p = write(tmp_path, base_params(), blocks=str(10 ** 30))  # data "after" 5e32 bytes
    refused(p, "NUM_HEADER_BLOCKS = 1000000000000000000000000000000")


# ------------------------------------------------------------ 2. counts that are no whole number

@pytest.mark.parametrize("key, value", [
    ("CHANNELS", "1e400"), ("SAMPLES", "inf"), ("FRAMES", "nan"), ("FRAMES", "-inf"), ("PTS_PER_FRAME", "-4"),
    ("PTS_PER_GROUP", "8.5"), ("CHANNELS", "two"), ("SAMPLES", ""), ("PARTITIONS", "nan"), ("HALF_FRAMES", "inf"),
])
def test_a_count_that_is_no_whole_number_is_one_sentence_naming_the_key(tmp_path, key, value):
    p = write(tmp_path, base_params(**{key: value}))
    refused(p, f"has {key} = {value!r}, not a whole number of", "fix:")


def test_a_huge_float_count_is_refused_not_overflowed(tmp_path):
    """CHANNELS = 1e18 with data: a number, but of channels no file holds (numpy cannot shape it)."""
    refused(write(tmp_path, base_params(CHANNELS="1e18")), "CHANNELS = '1e18'", "fix:")


# ----------------------------------------------------------------------------------- 3. DELTA_T

@pytest.mark.parametrize("dt", ["1e-300", "1e-7", "9.9e-7", "0", "-0.001", "10.5", "1e300", "inf", "nan"])
def test_a_delta_t_that_is_no_measured_step_is_refused(tmp_path, dt):
    refused(write(tmp_path, base_params(DELTA_T=dt)), "DELTA_T", "fix:")


@pytest.mark.parametrize("dt", ["1e-6", "9.999999e-07", "1e-5", "0.001", "10"])
def test_delta_t_at_the_bounds_reads(tmp_path, dt):
    mc = read_channels(write(tmp_path, base_params(DELTA_T=dt)))
    assert mc.fs_hz == pytest.approx(1 / float(dt)) and MIN_DELTA_T_S <= float(dt) * (1 + 1e-6)
    assert float(dt) <= MAX_DELTA_T_S


# -------------------------------------------------------------------------------- 4. START_TIME

@pytest.mark.parametrize("start", ["inf", "nan", "-inf", "noon"])
def test_a_start_time_that_is_no_number_is_refused(tmp_path, start):
    refused(write(tmp_path, base_params(START_TIME=start)), f"START_TIME = {start!r}", "fix:")


@pytest.mark.parametrize("start, dt", [("0", "0.001"), ("-100.5", "0.001"), ("1.7e9", "0.001"), ("86400", "0.001"),
                                       ("1e300", "0.001"), ("-1e15", "0.001"), ("1e12", "1e-6")])
def test_any_finite_start_time_reads_as_metadata_the_times_from_0(tmp_path, start, dt):
    """The times start at 0, whatever START_TIME (a POSIX time at 1 MHz has a float64 spacing of
    a fourth of a step), and START_TIME is kept as metadata."""
    mc = read_channels(write(tmp_path, base_params(START_TIME=start, DELTA_T=dt)))
    np.testing.assert_array_equal(mc.time_s, np.arange(12) / (1 / float(dt)))
    assert mc.fs_hz == 1 / float(dt) and float(mc.metadata.get("time_start_s", "0")) == float(start)


# ------------------------------------------------------------------------------------- 5. SCALE

@pytest.mark.parametrize("scale", ["0", "-0", "0.0e5", "nan", "inf", "-inf", "", "half"])
def test_a_zero_or_non_finite_scale_is_refused_naming_the_channel(tmp_path, scale):
    """SCALE.CHAN_2 = 0 would read as an all-zero channel, and `rigsim correct` would write all zeros."""
    refused(write(tmp_path, base_params(SCALE_CHAN_2=scale)), f"SCALE.CHAN_2 = {scale!r}", "channel 'x_FL'",
            "fix:")
    refused(write(tmp_path, base_params(SCALE_CHAN_2=None), name="none.rsp"), "no SCALE.CHAN_2 key", "'x_FL'")


def test_a_scale_that_overflows_and_a_negative_scale(tmp_path):
    refused(write(tmp_path, base_params(SCALE_CHAN_1="1e308")), "channel 'Fz_FL' (DESC.CHAN_1) at sample 2",
            "SCALE.CHAN_1 = '1e308' exceed float64")
    r = read_rpc3(write(tmp_path, base_params(SCALE_CHAN_1="-0.5"), name="neg.rsp"))  # a sign: kept
    np.testing.assert_array_equal(r.data[0], -0.5 * np.arange(12))


# ------------------------------------------------------------------------------ 6. a key twice

@pytest.mark.parametrize("key, first, second", [("CHANNELS", "2", "1"), ("FRAMES", "3", "2"),
                                                ("DELTA_T", "0.001", "0.002"), ("SCALE.CHAN_1", "0.5", "5"),
                                                ("DESC.CHAN_2", "x_FL", "y_FL"), ("TEST_RIG", "DYNTRAC", "MAST")])
def test_a_key_given_twice_with_two_values_is_refused(tmp_path, key, first, second):
    """Taking either record would lay the data out silently in one of two ways."""
    params = [(k, first if k == key else v) for k, v in base_params()] + [(key, second)]
    refused(write(tmp_path, params), f"gives {key} twice, as {first!r} and as {second!r}", "fix:")


def test_a_key_repeated_with_the_same_value_reads_once(tmp_path):
    params = base_params() + [("CHANNELS", "2"), ("SCALE.CHAN_1", "0.5"), ("TEST_RIG", "DYNTRAC")]
    mc = read_channels(write(tmp_path, params))
    assert mc.n_samples == 12 and mc.metadata["TEST_RIG"] == "DYNTRAC"
    np.testing.assert_allclose(mc.data["Fz_FL"], 0.5e3 * np.arange(12))


# ------------------------------------------------------------------------ 7. NaN or inf samples

@pytest.mark.parametrize("bad, index, channel, sample", [(np.nan, 9, "x_FL", 1), (np.inf, 5, "Fz_FL", 5),
                                                         (-np.inf, 27, "x_FL", 11), (np.nan, 16, "Fz_FL", 8)])
def test_a_non_finite_float_sample_is_refused_naming_channel_sample_and_time(tmp_path, bad, index, channel,
                                                                              sample):
    """Values 0-7: Fz_FL samples 0-7, 8-15: x_FL 0-7, 16-23: Fz_FL 8-15, 24-31: x_FL 8-15."""
    values = base_values("FLOATING_POINT")
    values[index] = bad
    p = write(tmp_path, base_params("FLOATING_POINT", START_TIME="2.5"), values)
    desc = "DESC.CHAN_2" if channel == "x_FL" else "DESC.CHAN_1"
    refused(p, f"channel {channel!r} ({desc}) at sample {sample} (t = {2.5 + sample * 0.001:.9g} s)", "fix:")
    refused(p, f"at sample {sample}", reader=read_rpc3)


def test_a_non_finite_sample_in_the_padding_is_not_data(tmp_path):
    values = base_values("FLOATING_POINT")
    values[20:24] = np.nan  # Fz_FL samples 12-15: the padding of the last group, beyond 3 frames
    values[28:32] = np.nan  # x_FL's
    mc = read_channels(write(tmp_path, base_params("FLOATING_POINT"), values))
    assert mc.n_samples == 12 and np.all(np.isfinite(mc.array()))


# ------------------------------------------------------------------------- the writer agrees

def test_the_writer_writes_no_file_its_reader_refuses(tmp_path):
    with pytest.raises(MeasuredDataError, match=r"cannot hold a record sampled every 1e-07 s"):
        write_rpc3(tmp_path / "w.rsp", ["a"], ["N"], np.ones((1, 4)), 1e-7)
    with pytest.raises(MeasuredDataError, match=r"from 1e\+15 s"):
        write_rpc3(tmp_path / "w.rsp", ["a"], ["N"], np.ones((1, 4)), 1e-3, start_s=1e15)
    with pytest.raises(MeasuredDataError, match=r"cannot hold a NaN or infinite sample"):
        write_rpc3(tmp_path / "w.rsp", ["a"], ["N"], np.array([[1.0, np.nan]]), 1e-3)
    assert not (tmp_path / "w.rsp").exists()
    write_rpc3(tmp_path / "tiny.rsp", ["a"], ["N"], np.array([[1e-320, -1e-320, 0.0]]), 1e-3)  # step underflows
    r = read_rpc3(tmp_path / "tiny.rsp")
    assert float(r.header["SCALE.CHAN_1"]) == 1.0 and np.all(r.data == 0.0)


# -------------------------------------------------------------------------------- the command

_COMMAND = textwrap.dedent("""
    import json, resource, sys
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))  # a regression fails, not the machine
    from rigsim.scenarios.cli.main import main
    code = main(sys.argv[1:])
    # this process's own peak (VmHWM starts anew at exec; ru_maxrss keeps the parent's peak)
    hwm = next(line for line in open("/proc/self/status") if line.startswith("VmHWM:"))
    print(json.dumps({"code": code, "peak_kB": int(hwm.split()[1])}))
""")


@pytest.mark.parametrize("changes, fragment", [
    ({"DELTA_T": "1e-300"}, "DELTA_T = '1e-300'"),  # taken as read: 11.4 GB of filter design at 1e300 Hz
    ({"START_TIME": "inf"}, "START_TIME = 'inf'"),
    ({"SCALE_CHAN_1": "0"}, "SCALE.CHAN_1 = '0'"),  # taken as read: an all-zero corrected file
    ({"CHANNELS": "1e400"}, "CHANNELS = '1e400'"),  # taken as read: an OverflowError traceback
])
def test_rigsim_correct_refuses_the_file_in_one_line_in_seconds_and_little_memory(tmp_path, changes, fragment):
    """The command, in a child process (3 GB of address space, a minute): exit code 2, one line
    on stderr naming the key, within 10 s (imports included) and 1 GB."""
    # 4 s at 1 kHz of two force channels in N: long enough to correct
    params = base_params(**{"PTS_PER_FRAME": "1000", "PTS_PER_GROUP": "2000", "FRAMES": "4", "UNITS_CHAN_1": "N",
                            "UNITS_CHAN_2": "N", **changes})
    rng = np.random.default_rng(1)
    values = (3000 + 1000 * rng.standard_normal((2, 2, 2000))).astype("<i2")
    p = write(tmp_path, params, values, name="rig.rsp")
    act = tmp_path / "act.toml"
    act.write_text("[transfer_function]\nnum = [1.0]\nden = [2.5e-4, 0.02, 1.0]\n")
    argv = ["correct", str(p), "--actuator", str(act), "-o", str(tmp_path / "out.rsp")]
    t0 = time.perf_counter()
    try:
        done = subprocess.run([sys.executable, "-c", _COMMAND, *argv], capture_output=True, text=True, timeout=60,
                              check=False)
    except subprocess.TimeoutExpired:
        pytest.fail(f"rigsim correct on {changes}: still running after 60 s")
    seconds = time.perf_counter() - t0
    assert done.returncode == 0, done.stderr[-2000:]  # the child itself: main returned
    out = json.loads(done.stdout.splitlines()[-1])
    err = done.stderr
    assert out["code"] == 2 and err.count("\n") == 1 and err.startswith("rigsim: error: RPC III file "), err
    assert fragment in err and "fix:" in err and not (tmp_path / "out.rsp").exists()
    assert seconds < 10.0 and out["peak_kB"] < 1e6, (seconds, out)


# ------------------------------------------------------------------------ generated headers

_TEXT = st.text(st.characters(min_codepoint=32, max_codepoint=255), max_size=10)
COUNT = st.one_of(
    st.integers(-3, 40).map(str),
    st.integers(-10 ** 40, 10 ** 40).map(str),
    st.sampled_from([10 ** 5, 10 ** 8, 10 ** 18, 2 ** 31, 2 ** 63, 2 ** 64]).map(str),
    st.integers(0, 40).map(lambda i: f"{i}.0"),
    st.floats().map(repr),  # inf, nan, 1e+300, -0.0, 2.5 ...
    st.sampled_from(["1e400", "-1e400", "1e18", "1e8", "nan", "inf", "", "0x10", "1_0", " 3 "]),
    _TEXT,
)
REAL = st.one_of(
    st.floats().map(repr),
    st.floats(1e-7, 20.0).map(repr),
    st.sampled_from(["1e-300", "1e-7", "1e-6", "9.999999e-07", "10", "10.000001", "1e300", "1e400", "0", "-0",
                     "nan", "inf", "-inf", "", "1.7e9", "1e15"]),
    _TEXT,
)
KEYS = {"CHANNELS": COUNT, "FRAMES": COUNT, "PTS_PER_FRAME": COUNT, "PTS_PER_GROUP": COUNT, "SAMPLES": COUNT,
        "PARTITIONS": COUNT, "HALF_FRAMES": COUNT, "DELTA_T": REAL, "START_TIME": REAL, "SCALE_CHAN_1": REAL,
        "SCALE_CHAN_2": REAL}


@st.composite
def rpc_files(draw):
    """(header records, data bytes, header counts): the two-channel file with up to three keys set
    to generated values or left out, sometimes a key repeated, the data generated, sometimes
    truncated, and now and then a damaged NUM_HEADER_BLOCKS or NUM_PARAMS."""
    data_type = draw(st.sampled_from(["SHORT_INTEGER", "FLOATING_POINT"]))
    changes = {}
    for key in draw(st.lists(st.sampled_from(sorted(KEYS)), max_size=3, unique=True)):
        changes[key] = draw(st.none() | KEYS[key] | KEYS[key] | KEYS[key])  # None: the key left out
    params = base_params(data_type, **changes)
    if draw(st.integers(0, 3)) == 0:  # a key repeated, with its own value or another
        k, v = draw(st.sampled_from(params))
        params.append((k, draw(st.just(v) | REAL)))
    if data_type == "SHORT_INTEGER":
        values = np.array(draw(st.lists(st.integers(-32768, 32767), min_size=32, max_size=32)), "<i2")
    else:
        element = draw(st.sampled_from([st.floats(-1e6, 1e6, width=32), st.floats(width=32)]))
        values = np.array(draw(st.lists(element, min_size=32, max_size=32)), "<f4")
    cut = draw(st.sampled_from([0] * 6 + [1, 17, 64]))  # truncated files too
    counts = draw(st.sampled_from([{}] * 12 + [{"blocks": "1"}, {"blocks": "100"}, {"n_params": "9999"},
                                               {"blocks": "1e3"}]))
    return params, values.tobytes()[:values.nbytes - cut], counts


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow])
@given(case=rpc_files())
def test_any_header_reads_consistently_or_is_one_sentence(tmp_path_factory, case):
    params, data, counts = case
    p = tmp_path_factory.mktemp("gen") / "g.rsp"
    p.write_bytes(rpc_bytes(params, np.frombuffer(data, "u1"), **counts))
    t0 = time.perf_counter()
    try:
        r = read_rpc3(p)
    except MeasuredDataError as exc:
        assert "\n" not in str(exc) and repr(str(p)) in str(exc), str(exc)
        r = None
    assert time.perf_counter() - t0 < QUICK_S  # counts of any size cost no more than the file
    if r is not None:
        n_ch, n = r.data.shape
        assert len(r.names) == len(r.units) == n_ch == int(float(r.header["CHANNELS"])) >= 1
        assert r.data.dtype == float and np.all(np.isfinite(r.data))
        assert n * n_ch * 2 <= len(data)  # every sample came from the file's bytes
        assert MIN_DELTA_T_S <= r.dt_s * (1 + 1e-6) and r.dt_s <= MAX_DELTA_T_S and math.isfinite(r.start_s)
    try:
        mc = read_channels(p)
    except MeasuredDataError as exc:
        assert "\n" not in str(exc), str(exc)
        return
    assert r is not None and mc.n_samples == r.data.shape[1] >= 2 and list(mc.names) == list(r.names)
    assert np.all(np.isfinite(mc.array())) and np.all(np.diff(mc.time_s) > 0) and mc.time_s[0] == 0.0
    assert mc.fs_hz == pytest.approx(1.0 / r.dt_s) and float(mc.metadata.get("time_start_s", "0")) == r.start_s
