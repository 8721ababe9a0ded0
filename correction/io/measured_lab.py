"""ASAM MDF4 (.mf4, .mdf) through ``asammdf`` and NI TDMS (.tdms) through ``nptdms``.

Both packages are optional (the ``lab`` extra) and imported only when such a file is read or
written; without them, one sentence names the extra.

MDF4: the time is each channel group's master channel (converted to s by its unit); the channels
read must share one time base (same timestamps), else they are named with their rates. Channel
names must be unique among the channels read. ``metadata``: the header comment's text as
``"comment"``, its ``common_properties`` (``<e name="key">value</e>``, trees as ``tree.key``),
``start_time``, and ``<channel>.comment`` for channels with a comment. The writer puts every
metadata key but ``comment`` into ``common_properties`` of the header comment (MDF4's place for
key/value metadata), ``comment`` into its text.

TDMS: channels are named by their name, or ``group/name`` when the name is in several groups.
The time is a channel with a time name (``time``, ``Time``, ``t``...; datetime channels become
seconds from their first value) or the one named by ``time_col``; else the waveform properties
(``wf_increment``, ``wf_start_offset``) of the channels read, which must agree. Units from the
``unit_string`` property. ``metadata``: file properties as they are, group properties as
``group.key``. The writer puts one group ``measured`` with a ``time`` channel and waveform
properties on each channel, metadata as file properties.

The file is checked first (a regular file that fits in memory, not empty:
:func:`rigsim.correction.io.measured_core.open_input`); both libraries are then called behind one boundary
(:func:`rigsim.correction.io.lab_boundary.library_call`): nothing of theirs reaches the console, a file cut
short is refused, and any exception of theirs is one sentence naming the file.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Mapping

import numpy as np

from rigsim.correction.io.lab_boundary import library_call, said
from rigsim.correction.io.measured_core import MeasuredDataError, is_time_name, make_channels, open_input, to_si
from rigsim.correction.io.measured_time import uniform_rate

__all__ = ["read_mdf", "write_mdf", "read_tdms", "write_tdms", "need"]


#: Peak memory of nptdms reading a file (it reads every channel), bytes per byte of the file
#: (2.2 measured on a 72 MB file). asammdf maps the file and reads only the channels asked for.
_TDMS_MEMORY_PER_BYTE = 3.0


def need(module: str, ext: str, verb: str = "reading"):
    """Import an optional package of the ``lab`` extra, or one sentence naming the extra."""
    fix = 'pip install -e ".[lab]"'
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return importlib.import_module(module)
    except ImportError:
        raise MeasuredDataError(f"{verb} {ext} files needs the 'lab' extra: {fix}") from None
    except Exception as exc:  # an install that imports but breaks (a mismatched numpy...)
        raise MeasuredDataError(f"{verb} {ext} files needs the 'lab' extra, and importing {module} failed "
                                f"({said(exc, '')}): reinstall it: {fix}") from None


def _checked(path, kind: str, memory_per_byte: float | None):
    """``path`` opened (:func:`open_input`: a regular file that fits in memory), or refused when empty."""
    fh = open_input(path, memory_per_byte)
    if os.fstat(fh.fileno()).st_size == 0:
        fh.close()
        raise MeasuredDataError(f"{kind} file {str(path)!r} is empty (0 bytes); export it again from the recorder")
    return fh


def _rate(t: np.ndarray, name: str, path) -> float:
    """The sampling rate (Hz) of time ``t`` (s) named ``name``; a refusal names the file."""
    if t.size < 2:
        raise MeasuredDataError(f"time {name!r} of {str(path)!r} has {t.size} samples; at least two are needed")
    return uniform_rate(t, name, lambda i: f"sample {i} of {str(path)!r}", "time channel")


def _time_si(name: str, t, unit: str, path) -> np.ndarray:
    t, si, src = to_si(name, t, unit, path, what="time channel")
    if si not in ("s", ""):
        raise MeasuredDataError(f"time channel {name!r} of {str(path)!r} is in {src!r}, not a unit of time; it "
                                "cannot give the sampling rate")
    return t


def _pick(available: list[str], channels, path, every: list[str]) -> list[str]:
    """The channels asked for (default: ``available``, the numeric ones); ``every``: all names."""
    if channels is None:
        return available
    for c in channels:
        if c not in every:
            raise MeasuredDataError(f"channel {c!r} is not in {str(path)!r}; its channels are {', '.join(every)}")
        if c not in available:
            raise MeasuredDataError(f"channel {c!r} of {str(path)!r} is not numeric (text, bytes or a structure); "
                                    "leave it out")
    if len(set(channels)) != len(channels):
        raise MeasuredDataError(f"channels {list(channels)!r} name a channel twice; name each once")
    return list(channels)


def _common_time(times: dict, path) -> np.ndarray:
    """The one time base of the channels read (s), or one sentence naming two that differ."""
    names = list(times)
    t0 = times[names[0]]
    for n in names[1:]:
        t = times[n]
        dt = float(np.median(np.diff(t0))) if t0.size > 1 else 0.0
        if t.size != t0.size or (t0.size and np.max(np.abs(t - t0)) > 1e-6 * max(dt, 1e-12)):
            rate = (lambda x: f"{(x.size - 1) / (x[-1] - x[0]):.6g} Hz" if x.size > 1 and x[-1] > x[0] else
                    f"{x.size} samples")
            raise MeasuredDataError(f"channels {names[0]!r} ({rate(t0)}, {t0.size} samples) and {n!r} ({rate(t)}, "
                                    f"{t.size} samples) of {str(path)!r} have different time bases; read them "
                                    "separately (channels=...)")
    return t0


# ---------------------------------------------------------------- MDF4

def _hd_metadata(comment: str) -> dict[str, str]:
    meta: dict[str, str] = {}
    if not comment.lstrip().startswith("<"):
        return {"comment": comment} if comment.strip() else {}
    try:
        root = ET.fromstring(comment.replace(' xmlns="http://www.asam.net/mdf/v4"', ""))
    except ET.ParseError:
        return {"comment": comment}
    tx = root.find("TX")
    if tx is not None and (tx.text or "").strip():
        meta["comment"] = tx.text.strip()

    def walk(node, prefix):
        for el in node:
            if el.tag == "e":
                meta[prefix + el.attrib.get("name", "")] = el.text or ""
            elif el.tag in ("tree", "list", "elist", "li"):
                walk(el, prefix + (el.attrib["name"] + "." if "name" in el.attrib else ""))

    props = root.find("common_properties")
    if props is not None:
        walk(props, "")
    return meta


def read_mdf(path, *, time_col=None, channels=None):
    """Channels of an MDF4 file on their common uniform time base, in SI.

    The path is checked first (:func:`_checked`), then given to asammdf, which maps the file (and
    copies an unfinalised one to finalise it); everything it does is behind
    :func:`rigsim.correction.io.lab_boundary.library_call`.
    """
    asammdf = need("asammdf", ".mf4")
    _checked(path, "MDF", None).close()
    with library_call("MDF", "an MDF4 file", "asammdf", path):
        mdf = asammdf.MDF(str(path))
        try:
            found = _mdf_channels(mdf, path, time_col, channels)
            found["dialect"] = {"version": str(mdf.version)}
        finally:
            with contextlib.suppress(Exception):
                mdf.close()
    return make_channels(**found, path=path, fmt="mdf4")


def _mdf_channels(mdf, path, time_col, channels) -> dict:
    """The arguments of :func:`make_channels` (but the path and format) read from an open MDF."""
    where: dict[str, list[tuple[int, int]]] = {}
    masters = {}
    for g, grp in enumerate(mdf.groups):
        m = mdf.masters_db.get(g)
        if m is not None:
            masters[g] = grp.channels[m]
        for i, ch in enumerate(grp.channels):
            if i != m:
                where.setdefault(ch.name, []).append((g, i))
    if time_col is not None and time_col not in {c.name for c in masters.values()}:
        raise MeasuredDataError(f"time_col {time_col!r} is not a master channel of {str(path)!r}; MDF4 time is "
                                "the channel group's master (leave time_col out)")
    sigs = {}
    for name, places in where.items():
        if channels is not None and name not in channels:
            continue
        if len(places) > 1:
            if channels is None and not any(_numeric(_get(mdf, g, i, path)) for g, i in places):
                continue
            raise MeasuredDataError(f"channel {name!r} appears in {len(places)} channel groups of "
                                    f"{str(path)!r}; export it once")
        sig = _get(mdf, places[0][0], places[0][1], path)
        if _numeric(sig):
            sigs[name] = (sig, places[0][0])
    names = _pick(list(sigs), channels, path, list(where))
    if not names:
        raise MeasuredDataError(f"MDF file {str(path)!r} has no numeric channel to read")
    times = {}
    for n in names:
        sig, g = sigs[n]
        unit = masters[g].unit if g in masters else "s"
        times[n] = _time_si(masters[g].name if g in masters else "time", sig.timestamps, unit, path)
    t = _common_time(times, path)
    fs = _rate(t, masters[sigs[names[0]][1]].name if sigs[names[0]][1] in masters else "time", path)
    data, units, src = {}, {}, {}
    meta = _hd_metadata(mdf.header.comment or "")
    try:
        meta["start_time"] = mdf.header.start_time.isoformat()
    except (AttributeError, ValueError):
        pass
    for n in names:
        sig = sigs[n][0]
        data[n], units[n], src[n] = to_si(n, sig.samples, sig.unit, path, what="channel")
        if (sig.comment or "").strip():
            meta[f"{n}.comment"] = sig.comment.strip()
    tname = masters[sigs[names[0]][1]].name if sigs[names[0]][1] in masters else "time"
    return dict(time_s=t, data=data, units=units, source_units=src, fs_hz=fs, metadata=meta, time_name=tname or "time")


def _get(mdf, g: int, i: int, path):
    """``mdf.get`` of channel ``i`` of group ``g``, once the bytes it and its master take are seen to
    lie in the group's record: asammdf's C code copies them without looking (a damaged byte
    offset would read past the data and crash the process)."""
    grp = mdf.groups[g]
    record = getattr(grp.channel_group, "samples_byte_nr", None)
    for k in {i, mdf.masters_db.get(g, i)}:
        ch = grp.channels[k]
        try:
            end = ch.byte_offset + (ch.bit_offset + ch.bit_count + 7) // 8
        except (AttributeError, TypeError):  # an MDF 3 block: another layout
            continue
        if record is not None and ch.channel_type not in (3, 6) and end > record:  # 3, 6: virtual, no bytes
            raise MeasuredDataError(f"channel {ch.name!r} of {str(path)!r} lies outside its record (it ends at byte "
                                    f"{end}, the record has {record}): the file is damaged; export it again from "
                                    "the recorder")
    return mdf.get(group=g, index=i)


def _numeric(sig) -> bool:
    s = np.asarray(sig.samples)
    return s.ndim == 1 and s.dtype.kind in "iufb" and s.dtype.names is None


def write_mdf(dest: str, time_s: np.ndarray, data: Mapping, units: Mapping, metadata: Mapping) -> None:
    """Write one channel group (master ``time`` in s) as MDF 4.10; metadata in the header comment."""
    asammdf = need("asammdf", ".mf4", "writing")
    root = ET.Element("HDcomment")
    ET.SubElement(root, "TX").text = str(metadata.get("comment", ""))
    props = ET.SubElement(root, "common_properties")
    for k, v in metadata.items():
        if k != "comment":
            ET.SubElement(props, "e", name=str(k)).text = str(v)
    t = np.asarray(time_s, dtype=float)
    mdf = asammdf.MDF(version="4.10")
    try:
        mdf.append([asammdf.Signal(samples=np.asarray(v, dtype=float), timestamps=t, name=n, unit=units.get(n, ""))
                    for n, v in data.items()], comment="measured channels")
        mdf.header.comment = ET.tostring(root, encoding="unicode")
        written = mdf.save(dest, overwrite=True)
    finally:
        mdf.close()
    if os.path.abspath(str(written)) != os.path.abspath(dest):  # asammdf names the file .mf4
        os.replace(written, dest)


# ---------------------------------------------------------------- TDMS

def read_tdms(path, *, time_col=None, channels=None):
    """Channels of a TDMS file on one uniform time axis, in SI.

    nptdms reads the file opened and checked here (:func:`_checked`: no second open by path, no
    ``.tdms_index`` beside it), behind :func:`rigsim.correction.io.lab_boundary.library_call`.
    """
    nptdms = need("nptdms", ".tdms")
    with _checked(path, "TDMS", _TDMS_MEMORY_PER_BYTE) as fh, library_call("TDMS", "a TDMS file", "nptdms", path):
        found = _tdms_channels(nptdms.TdmsFile.read(fh), path, time_col, channels)
    return make_channels(**found, path=path, fmt="tdms")


def _tdms_channels(f, path, time_col, channels) -> dict:
    """The arguments of :func:`make_channels` (but the path and format) from a TDMS file read."""
    entries = [(g.name, ch) for g in f.groups() for ch in g.channels()]
    if not entries:
        raise MeasuredDataError(f"TDMS file {str(path)!r} holds no channel: it is cut short or not a TDMS file; "
                                "export it again from the recorder")
    count: dict[str, int] = {}
    for _, ch in entries:
        count[ch.name] = count.get(ch.name, 0) + 1
    named = {(ch.name if count[ch.name] == 1 else f"{g}/{ch.name}"): ch for g, ch in entries}
    if time_col is not None:
        if time_col not in named:
            raise MeasuredDataError(f"time_col {time_col!r} is not a channel of {str(path)!r}; its channels are "
                                    f"{', '.join(named)}")
        tnames = [time_col]
    else:
        tnames = [n for n, ch in named.items() if is_time_name(ch.name)]
    numeric = [n for n, ch in named.items() if n not in tnames and np.asarray(ch[:]).dtype.kind in "iufb"]
    names = _pick(numeric, channels, path, [n for n in named if n not in tnames])
    if not names:
        raise MeasuredDataError(f"TDMS file {str(path)!r} has no numeric channel to read")
    tname = "time"
    if tnames:
        values = {n: _tdms_time(named[n], path) for n in tnames}
        tname = tnames[0]
        t = _common_time(values, path)
        for n in names:
            if len(named[n]) != t.size:
                raise MeasuredDataError(f"channel {n!r} of {str(path)!r} has {len(named[n])} samples but its time "
                                        f"channel {tname!r} has {t.size}; read them separately (channels=...)")
    else:
        times = {}
        for n in names:
            try:
                times[n] = np.asarray(named[n].time_track(), dtype=float)
            except (KeyError, ValueError):
                raise MeasuredDataError(f"channel {n!r} of {str(path)!r} has no time: no time channel and no "
                                        "waveform properties (wf_increment); name one with time_col") from None
        t = _common_time(times, path)
    fs = _rate(t, tname, path)
    data, units, src = {}, {}, {}
    for n in names:
        data[n], units[n], src[n] = to_si(n, named[n][:], named[n].properties.get("unit_string"), path,
                                          what="channel")
    meta = {str(k): str(v) for k, v in f.properties.items()}
    for g in f.groups():
        meta.update({f"{g.name}.{k}": str(v) for k, v in g.properties.items()})
    return dict(time_s=t, data=data, units=units, source_units=src, fs_hz=fs, metadata=meta, time_name=tname,
                dialect={"time": "channel" if tnames else "waveform"})


def _tdms_time(ch, path) -> np.ndarray:
    v = np.asarray(ch[:])
    if v.dtype.kind == "M":
        return (v - v[0]) / np.timedelta64(1, "s") if v.size else v.astype(float)
    if v.dtype.kind not in "iuf":
        raise MeasuredDataError(f"time channel {ch.name!r} of {str(path)!r} is not numeric")
    return _time_si(ch.name, v, ch.properties.get("unit_string"), path)


def write_tdms(dest: str, time_s: np.ndarray, data: Mapping, units: Mapping, metadata: Mapping) -> None:
    """Write group ``measured``: a ``time`` channel (s) and each channel with waveform properties."""
    nptdms = need("nptdms", ".tdms", "writing")
    t = np.asarray(time_s, dtype=float)
    dt = float((t[-1] - t[0]) / (t.size - 1))
    objs = [nptdms.RootObject(properties={str(k): str(v) for k, v in metadata.items()}),
            nptdms.GroupObject("measured"),
            nptdms.ChannelObject("measured", "time", t, properties={"unit_string": "s"})]
    objs += [nptdms.ChannelObject("measured", n, np.asarray(v, dtype=float),
                                  properties={"unit_string": units.get(n, ""), "wf_increment": dt,
                                              "wf_start_offset": float(t[0]), "wf_samples": int(t.size)})
             for n, v in data.items()]
    with nptdms.TdmsWriter(dest) as w:
        w.write_segment(objs)
