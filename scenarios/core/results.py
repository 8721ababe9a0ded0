"""Result objects of scenario runs and their atomic writing.

A :class:`RunResult` carries time, per-wheel signals with their units and labels, the
per-wheel statistics, and the run's events (python-control style: the result object knows
what its arrays are).
"""

from __future__ import annotations

import functools
import pathlib
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from rigsim.correction.metrics.dlc import force_statistics
from rigsim.scenarios.core.files import atomic_write_bytes, atomic_write_text, to_json
from rigsim.mjcf.names import CORNERS

__all__ = ["RunResult", "write_run", "csv_parts", "CSV_BLOCK_ROWS", "SIGNALS", "TIMING_KEYS", "TIMESERIES_FORMATS",
           "check_timeseries_format"]

#: Units and descriptions of the per-wheel signals a run may carry.
SIGNALS: dict[str, tuple[str, str]] = {
    "profile_m": ("m", "road profile under the wheel (the drive signal x_p, high-passed)"),
    "pan_m": ("m", "wheelpan displacement x_a (road mode: equals the profile)"),
    "tire_force_N": ("N", "tire force on the pan, compression positive"),
    "spool": ("1", "servovalve spool position, normalised to +-1"),
    "p1_Pa": ("Pa", "pressure in the lifting chamber"),
    "p2_Pa": ("Pa", "pressure in the lowering chamber"),
}


@dataclass(frozen=True)
class RunResult:
    """Outcome of one scenario run.

    Attributes
    ----------
    scenario_name : str
    mode : str
        "road" (pans follow the profile exactly) or "rig" (pans driven by the actuators).
    t_s : numpy.ndarray, s
        Sample times, shape (N,), from 0 (the end of the lead-in).
    signals : Mapping[str, numpy.ndarray]
        Per-wheel signals, each (N, 4) in :data:`rigsim.mjcf.names.CORNERS` order; names and
        units in :data:`SIGNALS`.
    vehicle_mass_kg : float, kg
        Mass of the truck (chassis, payload and axles; pans excluded).
    events : Mapping[str, object]
        Saturation and cavitation events (rig mode), empty in road mode.
    poses : rigsim.scenarios.core.poses.PoseTrack, optional
        Body poses at video rate for the 3D view of a recording (None unless asked for).
    info : Mapping[str, object]
        Run facts: time step, wall time, seed, speed...
    """

    scenario_name: str
    mode: str
    t_s: np.ndarray
    signals: Mapping[str, np.ndarray]
    vehicle_mass_kg: float
    events: Mapping = field(default_factory=dict)
    info: Mapping = field(default_factory=dict)
    corners: tuple[str, ...] = CORNERS
    poses: object = None  # rigsim.scenarios.core.poses.PoseTrack at video rate, when asked for (--rrd)

    @property
    def rate_hz(self) -> float:
        """Sampling rate of the time series, Hz."""
        return float(1.0 / np.mean(np.diff(self.t_s)))

    def statistics(self) -> dict[str, dict[str, float]]:
        """Per wheel: mean_force_N, std_force_N and dlc of the tire force."""
        stats = force_statistics(self.signals["tire_force_N"], axis=0)
        return {c: {k: float(v[i]) for k, v in stats.items()} for i, c in enumerate(self.corners)}

    def summary(self) -> dict:
        """Everything of ``result.json``."""
        stats = self.statistics()
        return {
            "scenario": self.scenario_name,
            "mode": self.mode,
            "vehicle_mass_kg": self.vehicle_mass_kg,
            "rate_hz": round(self.rate_hz, 9),
            "samples": int(self.t_s.size),
            "dlc_mean": _dlc_mean(stats),
            "wheels": stats,
            "events": dict(self.events),
            "info": dict(self.info),
        }

    def table(self) -> str:
        """The per-wheel table for the terminal and the recording: mean, std and DLC of the tire
        force, its stress factor E[(F/F_static)^4] (pavements) and damage-equivalent load (m = 5,
        1 Hz; components), from :mod:`rigsim.correction.metrics.damage`."""
        from rigsim.correction.metrics.damage import damage_equivalent_load, stress_factor

        f = np.asarray(self.signals["tire_force_N"], dtype=float)
        sf = np.atleast_1d(stress_factor(f))
        del5 = np.atleast_1d(damage_equivalent_load(f, 5, duration_s=f.shape[0] / self.rate_hz))
        stats = self.statistics()
        lines = [f"{self.scenario_name} ({self.mode} mode)",
                 f"{'wheel':>6} {'mean N':>10} {'std N':>9} {'DLC':>7} {'SF4':>7} {'DEL5 kN':>8}"]
        for i, (c, s) in enumerate(stats.items()):
            lines.append(f"{c:>6} {s['mean_force_N']:10.0f} {s['std_force_N']:9.0f} {s['dlc']:7.4f} "
                         f"{sf[i]:7.4f} {del5[i] / 1e3:8.2f}")
        lines.append(f"{'mean':>6} {'':>10} {'':>9} {_dlc_mean(stats):7.4f} {np.mean(sf):7.4f} "
                     f"{np.mean(del5) / 1e3:8.2f}")
        return "\n".join(lines)

    def series(self) -> list[tuple[str, str, str, int]]:
        """The time series' columns after ``time_s``: ``(name, unit, signal, corner index)``, named
        ``<signal stem>_<corner>[_<unit>]`` (unit "" for a dimensionless signal)."""
        out = []
        for key in self.signals:
            unit = key.rsplit("_", 1)[-1] if "_" in key else ""
            unit = unit if unit in ("m", "N", "Pa") else ""
            stem = key[: -len(unit) - 1] if unit else key
            out += [(f"{stem}_{c}" + (f"_{unit}" if unit else ""), unit, key, i) for i, c in enumerate(self.corners)]
        return out

    def column_names(self) -> list[str]:
        """Header of the time series file: ``time_s``, then :meth:`series`' names."""
        return ["time_s"] + [name for name, _unit, _key, _i in self.series()]

    def rows(self, i0: int, i1: int) -> np.ndarray:
        """Rows ``i0`` .. ``i1 - 1`` of the time series file's (N, 1 + 4 k) matrix."""
        return np.hstack([self.t_s[i0:i1, None]] + [arr[i0:i1] for arr in self.signals.values()])

    def columns(self) -> tuple[list[str], np.ndarray]:
        """Header and the whole (N, 1 + 4 k) matrix of the time series file."""
        return self.column_names(), self.rows(0, self.t_s.shape[0])


def _dlc_mean(stats: Mapping[str, Mapping[str, float]]) -> float:
    """The wheels' mean DLC (``result.json``'s ``dlc_mean``) from :meth:`RunResult.statistics`."""
    return float(np.mean([s["dlc"] for s in stats.values()]))


#: Rows of ``timeseries.csv`` formatted at a time: the file is streamed to disk in blocks of this
#: many rows (~3 MB of text each), never held whole in memory.
CSV_BLOCK_ROWS = 10_000


def csv_parts(result: RunResult):
    """``timeseries.csv`` as a sequence of byte blocks: the header line, then rows (``%.10g``,
    comma-separated) :data:`CSV_BLOCK_ROWS` at a time."""
    yield (",".join(result.column_names()) + "\n").encode("ascii")
    n = result.t_s.shape[0]
    for i in range(0, n, CSV_BLOCK_ROWS):
        yield _csv_rows(result.rows(i, min(n, i + CSV_BLOCK_ROWS)))


#: 10**0 .. 10**22, every power of ten a binary64 holds exactly (read from its decimal text).
_POW10 = np.array([float(f"1e{k}") for k in range(23)])
_ZERO, _DOT, _MINUS = ord("0"), ord("."), ord("-")
#: Numbers formatted per pass of :func:`_csv_rows` (its temporaries peak at ~180 bytes per number: 12 MB).
_FORMAT_VALUES = 1 << 16


@functools.cache
def _tables() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lookup tables of :func:`_csv_rows`: the five ASCII digits of 0 .. 99999 (leading zeros; one
    5-byte item each), their trailing zeros (5 for 0), and which of a number's 22 byte slots
    to keep, by text length L (slots 1 .. L), plus 21 if negative (slot 0, the sign)."""
    n = np.arange(100_000)
    digits = (n[:, None] // 10 ** np.arange(4, -1, -1) % 10 + _ZERO).astype(np.uint8)
    trailing = sum((n % 10**j == 0).astype(np.int64) for j in range(1, 6))
    keep = np.zeros((42, 22), dtype=bool)
    for length in range(21):
        keep[length, 1:1 + length] = keep[21 + length, 1:1 + length] = True
    keep[21:, 0] = keep[:, 21] = True
    return np.ascontiguousarray(digits).view("V5").ravel(), trailing, keep.view("V22").ravel()


def _scaled(a: np.ndarray, e: np.ndarray) -> np.ndarray:
    """a * 10**(9 - e) in one rounding: by or through an exact power of ten (|9 - e| <= 22)."""
    k = 9 - e
    return np.where(k >= 0, a * _POW10[np.clip(k, 0, 22)], a / _POW10[np.clip(-k, 0, 22)])


def _text(g: np.ndarray, digits: np.ndarray, nd: np.ndarray, e: int, exponent: bool):
    """Write ``%.10g``'s text of numbers of decimal exponent ``e`` (sign aside) into the first slots
    of ``g`` (rows of 20 bytes), from their ten ASCII digits and the count ``nd`` of them before
    the trailing zeros (in exponent notation the same for all); return its length(s)."""
    if not exponent and e >= 0:  # 123.45, 1000
        g[:, :e + 1], g[:, e + 1], g[:, e + 2:11] = digits[:, :e + 1], _DOT, digits[:, e + 1:]
        return np.where(nd > e + 1, nd + 1, e + 1)
    if not exponent:  # 0.00123
        lead = 1 - e  # "0." and -e - 1 zeros
        g[:, :lead] = np.frombuffer(b"0.000"[:lead], dtype=np.uint8)
        g[:, lead:lead + 10] = digits
        return lead + nd
    n = int(nd[0])  # 1.2345e+15, 1e-07
    g[:, 0], g[:, 1], g[:, 2:n + 1] = digits[:, 0], _DOT, digits[:, 1:n]
    at = n + 1 if n > 1 else 1
    g[:, at:at + 4] = np.frombuffer(f"e{e:+03d}".encode("ascii"), dtype=np.uint8)
    return at + 4


def _csv_rows(block: np.ndarray) -> bytes:
    """The rows of a 2-D float array as CSV lines, each number as ``"%.10g" % x`` writes it: the bytes
    of ``numpy.savetxt(f, block, delimiter=",", fmt="%.10g")``, formatted with numpy (~2.5x faster).

    The ten significant digits d of |x| = d * 10**(e - 9) are the scaled value |x| * 10**(9 - e)
    rounded to an integer. It is computed in one correctly rounded operation (:func:`_scaled`),
    which is monotonic and maps no number across a tie k + 1/2 (a binary64 below 1e10): the
    computed value rounds as the exact one does unless it is a tie itself. Those numbers,
    non-finite ones and magnitudes outside 1e-12 .. 1e31 (none in a run's signals) are formatted
    by Python itself; zeros are "0" and "-0". Each number gets 22 byte slots: the sign, the text
    (:func:`_text`, for the numbers of one layout at a time: sorted by it), the separator; the
    slots a number does not use are dropped.
    """
    step = max(1, _FORMAT_VALUES // block.shape[1])
    if block.shape[0] > step:
        return b"".join(_csv_rows(block[i:i + step]) for i in range(0, block.shape[0], step))
    v = np.ascontiguousarray(block, dtype=float).ravel()
    a = np.abs(v)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        e = np.floor(np.log10(a))
        ok = np.isfinite(e) & (e >= -12) & (e <= 30)
        e = np.where(ok, e, 0.0).astype(np.int64)
        scaled = _scaled(a, e)
        off = np.flatnonzero((scaled >= 1e10) | (scaled < 1e9))  # log10 one off next to a power of ten
        e[off] += np.where(scaled[off] >= 1e10, 1, -1)
        scaled[off] = _scaled(a[off], e[off])
    ok &= (scaled >= 1e9) & (scaled < 1e10)
    scaled = np.where(ok, scaled, 1e9)
    whole = np.floor(scaled)
    ok &= scaled - whole != 0.5  # exact: both below 2**34
    d = whole.astype(np.int64) + (scaled - whole > 0.5)
    carry = d == 10**10  # rounded up to the next power of ten
    d[carry] = 10**9
    e += carry
    digit_table, trailing, keep_table = _tables()
    low = d % 100_000
    nd = np.where(low == 0, 5 - trailing[d // 100_000], 10 - trailing[low])
    exponent = (e < -4) | (e >= 10)
    layout = np.where(ok, np.where(exponent, 64 + (e + 16) * 11 + nd, e + 16), 1 << 14).astype(np.int16)
    order = np.argsort(layout, kind="stable")
    layout, e, nd, d = layout[order], e[order], nd[order], d[order]
    digits = np.empty((v.size, 2), dtype="V5")
    digits[:, 0], digits[:, 1] = digit_table[d // 100_000], digit_table[d % 100_000]
    digits = digits.view(np.uint8).reshape(v.size, 10)
    text, length = np.empty((v.size, 22), dtype=np.uint8), np.zeros(v.size, dtype=np.int64)
    bounds = np.append(np.flatnonzero(np.diff(layout, prepend=-1)), v.size).tolist()
    for i, j in zip(bounds[:-1], bounds[1:]):
        if layout[i] == 1 << 14:
            break
        length[i:j] = _text(text[i:j, 1:21], digits[i:j], nd[i:j], int(e[i]), layout[i] >= 64)
    grid = np.empty_like(text)
    grid.view("V22")[order] = text.view("V22")
    length[order] = length.copy()
    zero = np.flatnonzero(v == 0)
    grid[zero, 1], length[zero] = _ZERO, 1  # "0", "-0"
    for i in np.flatnonzero(~ok & (v != 0)):
        s = ("%.10g" % v[i]).encode("ascii")
        grid[i, 1:1 + len(s)], length[i] = np.frombuffer(s, dtype=np.uint8), len(s)
    grid[:, 0], grid[:, 21] = _MINUS, ord(",")
    grid[block.shape[1] - 1::block.shape[1], 21] = ord("\n")
    sign = np.signbit(v) & (ok | (v == 0))  # Python's text carries its own
    keep = keep_table[length + 21 * sign].view(bool).reshape(grid.shape)
    return grid[keep].tobytes()


#: ``timeseries.<ext>`` formats of a run (``rigsim run --format``): name -> extension. CSV for
#: people who open files in a spreadsheet; the binary ones are written by the toolkit's one writer
#: of measured data (:func:`rigsim.correction.io.measured.write_channels`), in the formats test labs already
#: read: ASAM MDF4 (``mf4``: float64, the standard of vehicle DAQ, read by asammdf, MATLAB's
#: mdfRead, CANape, DIAdem), NI TDMS (``tdms``) and MTS RPC III (``rsp``: int16 per channel, as
#: the rig controllers store it: quantized to 1/32767 of each channel's range). MDF4 and TDMS
#: need the ``lab`` extra.
TIMESERIES_FORMATS = {"csv": ".csv", "mf4": ".mf4", "tdms": ".tdms", "rsp": ".rsp"}


def check_timeseries_format(fmt: str, flag: str = "--format") -> None:
    """Refuse, before any run, a format that is not known or whose library is not installed; the
    sentence names the command's ``flag``."""
    from rigsim.scenarios.core.config import ScenarioError

    if fmt not in TIMESERIES_FORMATS:
        raise ScenarioError(f"{flag} must be one of {', '.join(TIMESERIES_FORMATS)}, got {fmt!r}")
    if fmt in ("mf4", "tdms"):
        from rigsim.correction.io import measured_lab

        try:
            measured_lab.need("asammdf" if fmt == "mf4" else "nptdms", TIMESERIES_FORMATS[fmt], "writing")
        except ValueError as exc:
            raise ScenarioError(f"{flag} {fmt}: {exc}") from None


@dataclass(frozen=True)
class _Channels:
    """A run's time series as the measured-data writer takes it (names as in the CSV header)."""

    time_s: np.ndarray
    data: dict
    units: dict
    metadata: dict


def _channels(result: RunResult) -> _Channels:
    data, units = {}, {}
    for name, unit, key, i in result.series():
        data[name] = np.ascontiguousarray(result.signals[key][:, i])
        units[name] = unit
    meta = {"source": f"rigsim run {result.scenario_name} ({result.mode} mode)"}
    return _Channels(time_s=np.asarray(result.t_s), data=data, units=units, metadata=meta)


#: Run facts of :attr:`RunResult.info` that differ from run to run of the same scenario and seed:
#: written to ``timings.json``, never to ``result.json``.
TIMING_KEYS = ("wall_time_s",)


def write_run(result: RunResult, out_dir, *, fmt: str | None = "csv") -> dict[str, pathlib.Path]:
    """Write ``result.json``, ``timeseries.<ext>`` and ``timings.json`` into ``out_dir``, each atomically.

    ``fmt`` is one of :data:`TIMESERIES_FORMATS` (default CSV), or None: no time series (``result.json``
    and ``timings.json`` only; ``rigsim paper`` without ``--series``).

    ``result.json`` and ``timeseries.csv`` depend only on the scenario and its seed: two runs give
    byte-identical files. The wall time (s) goes to ``timings.json`` beside them. All files are
    written to a temporary file and renamed, so a failure leaves no partial file; the time series is
    streamed in blocks (:func:`csv_parts`): memory does not grow with the file.
    ``timeseries.csv`` reads in one line: ``numpy.genfromtxt(p, delimiter=",", names=True)`` or
    ``pandas.read_csv(p)``.
    """
    out = pathlib.Path(out_dir)
    summary = result.summary()
    info = dict(summary["info"])
    timings = {k: info.pop(k) for k in TIMING_KEYS if k in info}
    summary["info"] = info
    paths = {"result": out / "result.json", "timings": out / "timings.json"}
    if fmt is not None:
        series = "timeseries" + TIMESERIES_FORMATS[fmt]
        summary["timeseries"] = {"file": series, "format": fmt, "columns": result.column_names(),
                                 "rate_hz": summary["rate_hz"]}
        paths = {"timeseries": out / series, **paths}
    summary["timings"] = {"file": "timings.json"}
    js = to_json(summary)
    tj = to_json(timings)
    if fmt == "csv":
        atomic_write_bytes(paths["timeseries"], csv_parts(result))
    elif fmt is not None:
        from rigsim.correction.io.measured import write_channels

        write_channels(paths["timeseries"], _channels(result), overwrite=True)
    atomic_write_text(paths["result"], js)
    atomic_write_text(paths["timings"], tj)
    return paths
