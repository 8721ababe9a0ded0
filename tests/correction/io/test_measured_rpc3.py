"""MTS RPC III (.rsp/.drv/.tim): a file laid out byte by byte here, this module's writer, and the
third-party packages (rpc3-file both ways; rpc-reader, read-only), all read back."""

from __future__ import annotations

import contextlib
import io
import math
import warnings

import numpy as np
import pytest

from rigsim.correction.io.measured import MeasuredDataError, read_channels, write_channels
from rigsim.correction.io.rpc3 import INT_FULL_SCALE, read_rpc3, write_rpc3


def _rpc_bytes(params: list[tuple[str, str]], ints: np.ndarray) -> bytes:
    """An RPC III file from the published layout: FORMAT, NUM_HEADER_BLOCKS, NUM_PARAMS first,
    128-byte records (32-byte key, 96-byte value), 512-byte blocks, then the data as given."""
    n_params = len(params) + 3
    blocks = math.ceil(n_params / 4)
    fmt = dict(params).get("FORMAT", "BINARY_IEEE_LITTLE_END")
    records = [("FORMAT", fmt), ("NUM_HEADER_BLOCKS", str(blocks)), ("NUM_PARAMS", str(n_params))]
    records += [(k, v) for k, v in params if k != "FORMAT"]
    head = b"".join(k.encode().ljust(32, b"\0") + v.encode().ljust(96, b"\0") for k, v in records)
    return head.ljust(512 * blocks, b"\0") + ints.tobytes()


def _two_channel_file(samples=None, fmt="BINARY_IEEE_LITTLE_END", data_type="SHORT_INTEGER"):
    # 2 channels, 4 points a frame, 2 frames a group, 3 frames: the last group is half filled (padded)
    params = [("FORMAT", fmt), ("FILE_TYPE", "TIME_HISTORY"), ("TIME_TYPE", "RESPONSE"), ("DELTA_T", "0.001"),
              ("CHANNELS", "2"), ("PTS_PER_FRAME", "4"), ("PTS_PER_GROUP", "8"), ("FRAMES", "3"),
              ("DATA_TYPE", data_type), ("INT_FULL_SCALE", "32752"),
              ("DESC.CHAN_1", "Fz_FL"), ("UNITS.CHAN_1", "kN"), ("SCALE.CHAN_1", "0.5"),
              ("DESC.CHAN_2", "x_FL"), ("UNITS.CHAN_2", "mm"), ("SCALE.CHAN_2", "2.0"), ("TEST_RIG", "DYNTRAC")]
    if samples is not None:
        params.append(("SAMPLES", str(samples)))
    a, b = np.arange(16), 100 + np.arange(16)  # 12 samples + 4 padding each
    groups = [a[:8], b[:8], a[8:], b[8:]]  # group 1: ch1, ch2; group 2: ch1, ch2
    dtype = {"SHORT_INTEGER": "i2", "FLOATING_POINT": "f4"}[data_type]
    order = ">" if fmt.endswith("BIG_END") else "<"
    return _rpc_bytes(params, np.concatenate(groups).astype(order + dtype))


@pytest.mark.parametrize("samples, fmt, data_type, scaled", [
    (None, "BINARY_IEEE_LITTLE_END", "SHORT_INTEGER", True),
    (10, "BINARY", "SHORT_INTEGER", True),
    (None, "BINARY_IEEE_BIG_END", "SHORT_INTEGER", True),
    (None, "BINARY_IEEE_LITTLE_END", "FLOATING_POINT", False),
])
def test_a_file_laid_out_by_hand(tmp_path, samples, fmt, data_type, scaled):
    p = tmp_path / "hand.rsp"
    p.write_bytes(_two_channel_file(samples, fmt, data_type))
    mc = read_channels(p)
    n = 12 if samples is None else samples
    assert mc.format == "rpc3" and mc.fs_hz == pytest.approx(1000.0)
    np.testing.assert_allclose(mc.time_s, np.arange(n) * 0.001, atol=1e-15)
    k1, k2 = (0.5, 2.0) if scaled else (1.0, 1.0)  # FLOATING_POINT is not scaled
    np.testing.assert_allclose(mc.data["Fz_FL"], np.arange(n) * k1 * 1e3)  # kN -> N
    np.testing.assert_allclose(mc.data["x_FL"], (100 + np.arange(n)) * k2 * 1e-3)  # mm -> m
    assert dict(mc.units) == {"Fz_FL": "N", "x_FL": "m"} and dict(mc.source_units) == {"Fz_FL": "kN", "x_FL": "mm"}
    assert mc.metadata["TEST_RIG"] == "DYNTRAC" and mc.metadata["TIME_TYPE"] == "RESPONSE"
    assert "SCALE.CHAN_1" not in mc.metadata and "DELTA_T" not in mc.metadata


def _record(n=3000, fs=1024.0, seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    return t, {"Fz_FL": 4e4 + 3e3 * rng.standard_normal(n), "x_FL": 0.01 * np.sin(2 * np.pi * 3 * t),
               "zero": np.zeros(n)}


def _within_half_step(back, data, header=None):
    for k, (name, v) in enumerate(data.items()):
        step = np.max(np.abs(v)) / INT_FULL_SCALE if np.any(v) else 1.0
        err = np.max(np.abs(back[name] - v))
        assert err <= 0.5 * step * (1 + 1e-9), (name, err / step)
        if header is not None:
            assert float(header[f"SCALE.CHAN_{k + 1}"]) == step


def test_own_writer_round_trip_within_half_a_step(tmp_path):
    t, data = _record()
    from types import SimpleNamespace

    mc = SimpleNamespace(time_s=t, data=data, units={"Fz_FL": "N", "x_FL": "m", "zero": "1"})
    for ext, kind in ((".rsp", "RESPONSE"), (".drv", "DRIVE"), (".tim", "MULT_DRIVE")):  # .tim: as given
        p = write_channels(tmp_path / f"r{ext}", mc, metadata={"TEST": "step 4", "TIME_TYPE": "MULT_DRIVE"})
        back = read_channels(p)
        assert back.fs_hz == pytest.approx(1024.0, rel=1e-15) and back.n_samples == t.size
        np.testing.assert_allclose(back.time_s, t, atol=1e-12)
        _within_half_step(back.data, data, read_rpc3(p).header)
        assert back.metadata["TIME_TYPE"] == kind and back.metadata["TEST"] == "step 4"
        assert dict(back.units) == {"Fz_FL": "N", "x_FL": "m", "zero": "1"}
        assert p.stat().st_size == 512 * math.ceil(len(read_rpc3(p).header) / 4) + 3 * 2048 * 2 * 2  # whole groups
    # a start time other than 0 comes back as metadata, the times from 0
    shifted = read_channels(write_channels(tmp_path / "s.rsp", SimpleNamespace(time_s=t + 5.0, data=data, units={})))
    np.testing.assert_allclose(shifted.time_s, t, atol=1e-12)
    assert shifted.metadata["time_start_s"] == "5.0"


def test_csv_to_rpc3_to_csv_within_the_quantization(tmp_path):
    t, data = _record(n=700, fs=500.0)
    lines = ["time;Fz_FL [kN];x_FL [mm]"] + [f"{a:.4f};{b / 1e3:.6f};{c * 1e3:.6f}".replace(".", ",")
                                             for a, b, c in zip(t, data["Fz_FL"], data["x_FL"])]
    src = tmp_path / "in.csv"
    src.write_text("\n".join(lines) + "\n")
    first = read_channels(src)
    rsp = write_channels(tmp_path / "mid.rsp", first, inputs=[src])
    out = write_channels(tmp_path / "out.csv", read_channels(rsp), inputs=[rsp])
    back = read_channels(out)
    np.testing.assert_allclose(back.time_s, first.time_s, atol=1e-12)
    _within_half_step(back.data, dict(first.data))
    assert back.fs_hz == pytest.approx(500.0)


@pytest.mark.parametrize("content, message", [
    (b"NOT AN RPC FILE" * 40, r"does not start with FORMAT, NUM_HEADER_BLOCKS, NUM_PARAMS"),
    (None, r"is truncated: its header asks for"),
    (b"FORMAT".ljust(32, b"\0") + b"ASCII".ljust(96, b"\0"), r"ends inside its header|does not start with"),
])
def test_rpc3_refusals(tmp_path, content, message):
    p = tmp_path / "bad.rsp"
    p.write_bytes(content if content is not None else _two_channel_file()[:-10])
    with pytest.raises(MeasuredDataError, match=message) as exc:
        read_channels(p)
    assert "\n" not in str(exc.value)


def test_rpc3_refusals_on_keys_units_and_options(tmp_path):
    p = tmp_path / "ascii.rsp"
    p.write_bytes(_rpc_bytes([("FORMAT", "ASCII"), ("CHANNELS", "1")], np.zeros(0, "<i2")))
    with pytest.raises(MeasuredDataError, match=r"has FORMAT 'ASCII'; only binary files"):
        read_channels(p)
    q = tmp_path / "u.rsp"
    write_rpc3(q, ["Fz", "volts"], ["N", "furlong"], np.ones((2, 10)), 0.001)
    with pytest.raises(MeasuredDataError, match=r"channel 'volts' of .* is in 'furlong'"):
        read_channels(q)
    assert list(read_channels(q, channels=["Fz"]).data) == ["Fz"]  # not selected: no matter
    with pytest.raises(MeasuredDataError, match=r"has no time column \(DELTA_T gives the time\)"):
        read_channels(q, time_col="time")
    from types import SimpleNamespace

    two = SimpleNamespace(time_s=[0.0, 0.001], data={"Fz": [1.0, 2.0]}, units={})
    with pytest.raises(MeasuredDataError, match=r"header value '.{97}' .* is 97 bytes; RPC III allows 1 to 96"):
        write_channels(tmp_path / "long.rsp", two, metadata={"NOTE": "x" * 97})
    with pytest.raises(MeasuredDataError, match=r"header key 'K{33}' .* allows 1 to 32"):
        write_channels(tmp_path / "long.rsp", two, metadata={"K" * 33: "x"})
    assert not (tmp_path / "long.rsp").exists()
    uneven = SimpleNamespace(time_s=[0.0, 0.001, 0.002, 0.004], data={"Fz": [1.0, 2.0, 3.0, 4.0]}, units={})
    with pytest.raises(MeasuredDataError, match=r"is not uniform at sample 3"):
        write_channels(tmp_path / "u2.rsp", uneven)


# ---------------------------------------------------------------- third-party packages

def test_cross_check_with_rpc3_file_both_ways(tmp_path):
    rpc3 = pytest.importorskip("rpc3.rpc3")
    t, data = _record()
    units = {"Fz_FL": "N", "x_FL": "m", "zero": "1"}
    ours = tmp_path / "ours.rsp"
    write_rpc3(ours, list(data), list(units.values()), np.array(list(data.values())), 1 / 1024.0)
    with _quiet(rpc3):
        chs, params = rpc3.read(str(ours))
    # (rpc3-file turns a unit "1" into the integer 1: it exempts "UNIT", not "UNITS", from numbers)
    assert [c.name for c in chs] == list(data) and [str(c.unit) for c in chs] == list(units.values())
    assert all(c.dt == 1 / 1024.0 and len(c.data) == t.size for c in chs)
    # rpc3-file returns float32: half a step plus the float32 rounding of the value
    for c, (name, v) in zip(chs, data.items()):
        step = float(params[f"SCALE.CHAN_{list(data).index(name) + 1}"])
        assert np.max(np.abs(c.data.astype(float) - v)) <= 0.5 * step + 1e-7 * np.max(np.abs(v))
    theirs = tmp_path / "theirs.rsp"
    with _quiet(rpc3):
        rpc3.write(str(theirs), [rpc3.Channel(name=n, unit=units[n], dt=1 / 1024.0, data=v) for n, v in data.items()])
        again, _ = rpc3.read(str(theirs))
    back = read_channels(theirs)
    assert back.fs_hz == 1024.0 and list(back.data) == list(data) and back.n_samples == t.size
    _within_half_step(back.data, data)
    for c in again:  # both readers give the same numbers from their file
        np.testing.assert_allclose(back.data[c.name], c.data.astype(float), rtol=0, atol=1e-7 * 5e4)


def test_cross_check_with_rpc_reader(tmp_path):
    mod = pytest.importorskip("rpc_reader.rpc_reader")
    t, data = _record()
    ours = tmp_path / "ours.rsp"
    write_rpc3(ours, list(data), ["N", "m", "1"], np.array(list(data.values())), 1 / 1024.0)
    with contextlib.redirect_stdout(io.StringIO()):
        r = mod.ReadRPC(ours)
        r.import_rpc_data_from_file()
    got = r.get_data()[:t.size].T
    # rpc-reader scales by SCALE * INT_FULL_SCALE / 32768, rpc3-file and FEDEM by SCALE alone
    mine = read_rpc3(ours).data
    np.testing.assert_allclose(got * 32768 / INT_FULL_SCALE, mine, rtol=1e-12, atol=1e-12)
    assert r.get_data().shape[0] == 2 * 2048  # it reads the padded whole groups (SAMPLES unknown to it)


@contextlib.contextmanager
def _quiet(rpc3):
    old, rpc3.progressbar = rpc3.progressbar, False
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield
    finally:
        rpc3.progressbar = old
