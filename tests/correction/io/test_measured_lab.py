"""ASAM MDF4 and NI TDMS: files written by asammdf / nptdms themselves read back to SI numbers;
this module's writers read back; a missing 'lab' extra is one sentence naming it."""

from __future__ import annotations

import importlib
from types import SimpleNamespace

import numpy as np
import pytest

from rigsim.correction.io.measured import MeasuredDataError, read_channels, write_channels

T = np.arange(2000) / 1000.0
FZ_KN = 40.0 + 2.0 * np.sin(2 * np.pi * 5 * T)
X_MM = 10.0 * np.cos(2 * np.pi * 2 * T)


def _mdf_by_asammdf(path, *, slow=False, text=False):
    asammdf = pytest.importorskip("asammdf")
    mdf = asammdf.MDF(version="4.10")
    sigs = [asammdf.Signal(FZ_KN, T, name="Fz_FL", unit="kN", comment="front left load cell"),
            asammdf.Signal(X_MM, T, name="x_FL", unit="mm")]
    mdf.append(sigs, comment="rig channels")
    if slow:
        t2 = np.arange(100) / 50.0
        mdf.append([asammdf.Signal(t2 * 2.0, t2, name="p_oil", unit="bar")], comment="slow")
    if text:
        mdf.append([asammdf.Signal(np.array([b"OK"] * T.size), T, name="status", encoding="utf-8")], comment="text")
    mdf.header.comment = ('<HDcomment><TX>road test, truck 7</TX><common_properties><e name="operator">J. Doe'
                          '</e></common_properties></HDcomment>')
    mdf.save(str(path), overwrite=True)
    mdf.close()
    return path


def test_mdf4_written_by_asammdf(tmp_path):
    p = _mdf_by_asammdf(tmp_path / "rec.mf4", text=True)
    mc = read_channels(p)
    assert mc.format == "mdf4" and mc.time_name == "time" and list(mc.data) == ["Fz_FL", "x_FL"]  # text left out
    assert mc.fs_hz == pytest.approx(1000.0, rel=1e-12)
    np.testing.assert_allclose(mc.time_s, T, atol=1e-12)
    np.testing.assert_allclose(mc.data["Fz_FL"], FZ_KN * 1e3, rtol=1e-15)
    np.testing.assert_allclose(mc.data["x_FL"], X_MM * 1e-3, rtol=1e-15)
    assert dict(mc.source_units) == {"Fz_FL": "kN", "x_FL": "mm"} and dict(mc.units) == {"Fz_FL": "N", "x_FL": "m"}
    assert mc.metadata["comment"] == "road test, truck 7" and mc.metadata["operator"] == "J. Doe"
    assert mc.metadata["Fz_FL.comment"] == "front left load cell"
    with pytest.raises(MeasuredDataError, match=r"channel 'status' of .* is not numeric \(text, bytes"):
        read_channels(p, channels=["status"])
    with pytest.raises(MeasuredDataError, match=r"channel 'Fz' is not in .*; its channels are Fz_FL, x_FL, status"):
        read_channels(p, channels=["Fz"])


def test_mdf4_channels_of_two_rates_are_refused_unless_read_apart(tmp_path):
    p = _mdf_by_asammdf(tmp_path / "rates.mf4", slow=True)
    with pytest.raises(MeasuredDataError, match=r"channels 'Fz_FL' \(1000 Hz, 2000 samples\) and 'p_oil' \(50 Hz, "
                                                r"100 samples\) .* have different time bases; read them separately"):
        read_channels(p)
    slow = read_channels(p, channels=["p_oil"])
    assert slow.fs_hz == pytest.approx(50.0) and np.allclose(slow.data["p_oil"], np.arange(100) / 25.0 * 1e5)
    assert list(read_channels(p, channels=["x_FL", "Fz_FL"]).data) == ["x_FL", "Fz_FL"]


def _tdms_by_nptdms(path, *, waveform: bool):
    nptdms = pytest.importorskip("nptdms")
    props = {"wf_increment": 0.001, "wf_start_offset": 0.0} if waveform else {}
    objs = [nptdms.RootObject(properties={"title": "rig run 12", "operator": "J. Doe"}),
            nptdms.GroupObject("Analog", properties={"rate": 1000}),
            nptdms.ChannelObject("Analog", "Fz_FL", FZ_KN, properties={"unit_string": "kN", **props}),
            nptdms.ChannelObject("Analog", "x_FL", X_MM, properties={"unit_string": "mm", **props}),
            nptdms.ChannelObject("Analog", "status", np.array(["OK"] * T.size))]
    if not waveform:
        objs.append(nptdms.ChannelObject("Analog", "Time", T * 1e3, properties={"unit_string": "ms"}))
    with nptdms.TdmsWriter(str(path)) as w:
        w.write_segment(objs)
    return path


@pytest.mark.parametrize("waveform", [True, False])
def test_tdms_written_by_nptdms(tmp_path, waveform):
    mc = read_channels(_tdms_by_nptdms(tmp_path / "rec.tdms", waveform=waveform))
    assert mc.format == "tdms" and list(mc.data) == ["Fz_FL", "x_FL"]
    assert mc.time_name == ("time" if waveform else "Time")
    assert mc.fs_hz == pytest.approx(1000.0, rel=1e-9)
    np.testing.assert_allclose(mc.time_s, T, atol=1e-12)
    np.testing.assert_allclose(mc.data["Fz_FL"], FZ_KN * 1e3, rtol=1e-15)
    np.testing.assert_allclose(mc.data["x_FL"], X_MM * 1e-3, rtol=1e-15)
    assert mc.metadata["title"] == "rig run 12" and mc.metadata["Analog.rate"] == "1000"


def test_tdms_without_time_is_refused(tmp_path):
    nptdms = pytest.importorskip("nptdms")
    p = tmp_path / "no_time.tdms"
    with nptdms.TdmsWriter(str(p)) as w:
        w.write_segment([nptdms.ChannelObject("g", "Fz", FZ_KN, properties={"unit_string": "kN"})])
    with pytest.raises(MeasuredDataError, match=r"channel 'Fz' of .* has no time: no time channel and no waveform"):
        read_channels(p)


@pytest.mark.parametrize("ext, module", [(".mf4", "asammdf"), (".mdf", "asammdf"), (".tdms", "nptdms")])
def test_own_writers_read_back(tmp_path, ext, module):
    pytest.importorskip(module)
    mc = SimpleNamespace(time_s=T + 2.0, data={"Fz_FL": FZ_KN * 1e3, "x_FL": X_MM * 1e-3},
                         units={"Fz_FL": "N", "x_FL": "m"})
    p = write_channels(tmp_path / f"out{ext}", mc, metadata={"comment": "corrected", "rig": "DYNTRAC"})
    assert sorted(f.name for f in tmp_path.iterdir()) == [f"out{ext}"]  # no temporary file left
    back = read_channels(p)
    np.testing.assert_array_equal(back.time_s, T)  # from the first sample, which is kept
    assert back.metadata["time_start_s"] == "2.0"
    for n in mc.data:
        np.testing.assert_array_equal(back.data[n], mc.data[n])
    assert dict(back.units) == mc.units
    assert back.metadata["comment"] == "corrected" and back.metadata["rig"] == "DYNTRAC"
    with pytest.raises(MeasuredDataError, match=r"exists; pass --force"):
        write_channels(p, mc)


@pytest.mark.parametrize("ext, verb, call", [
    (".mf4", "reading", "read"), (".tdms", "reading", "read"), (".mf4", "writing", "write"),
    (".tdms", "writing", "write")])
def test_a_missing_lab_extra_is_named(tmp_path, monkeypatch, ext, verb, call):
    real = importlib.import_module

    def without_lab(name, *args):
        if name in ("asammdf", "nptdms"):
            raise ImportError(f"No module named {name!r}")
        return real(name, *args)

    import rigsim.correction.io.measured_lab as lab

    monkeypatch.setattr(lab.importlib, "import_module", without_lab)
    p = tmp_path / f"f{ext}"
    with pytest.raises(MeasuredDataError) as exc:
        if call == "read":
            p.write_bytes(b"\0" * 64)
            read_channels(p)
        else:
            write_channels(p, SimpleNamespace(time_s=T, data={"Fz": FZ_KN}, units={}))
    assert str(exc.value) == f"{verb} {ext} files needs the 'lab' extra: pip install -e \".[lab]\""
    assert call == "read" or not p.exists()
