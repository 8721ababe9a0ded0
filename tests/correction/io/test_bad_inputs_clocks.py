"""Clocks as labs have them: a record's time axis read relative to its first sample, its rate read
from the axis within a tolerance, a wobble or a gap named with the file and the line; records
built in Python checked as files are.

Expected values: the same samples written with a time axis starting at 0 s, at 86 400 s (a
time-of-day clock at midnight) and at 1.7e9 s (epoch seconds, 2023) read to the same time axis
(``np.arange(n) / fs``), the same rate, the same channels, and give the same truck-model forces;
the start is kept in ``metadata[TIME_START_KEY]`` as written.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from rigsim.correction.io.measured import MeasuredDataError, read_channels, write_channels
from rigsim.correction.io.measured_core import TIME_START_KEY, MeasuredChannels, make_channels
from rigsim.correction.io.measured_time import MAX_RATE_HZ

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

FS = 1000.0
N = 1000
STARTS = [0.0, 86400.0, 1.7e9, -5.25]
PAN = 0.01 * np.sin(2 * np.pi * np.arange(N) / FS)[:, None] * np.array([1.0, -1.0, 0.8, -0.8])


def _csv(path, t, columns: dict, fmt=repr) -> None:
    lines = [",".join(["time"] + list(columns))]
    lines += [",".join([fmt(float(t[i]))] + [repr(float(v[i])) for v in columns.values()]) for i in range(t.size)]
    path.write_text("\n".join(lines) + "\n")


def _pan_csv(tmp_path, start: float):
    p = tmp_path / f"pan_{start:g}.csv"
    _csv(p, start + np.arange(N) / FS, {f"pan_{c}": PAN[:, k] for k, c in enumerate(("fl", "fr", "rl", "rr"))})
    return p


def _same(a, b) -> None:
    np.testing.assert_array_equal(a.time_s, b.time_s)
    assert a.fs_hz == b.fs_hz and list(a.data) == list(b.data)
    for n in a.data:
        np.testing.assert_array_equal(a.data[n], b.data[n])


# ------------------------------------------------------------------ a time-of-day or epoch clock

@pytest.mark.parametrize("start", STARTS[1:])
def test_a_clock_that_does_not_start_at_zero_reads_and_runs_the_model_like_one_that_does(tmp_path, start):
    """The truck model runs on the record's rate: a 1 kHz record at 86 400 s read as 1000.0000000038 Hz
    was refused by the simulation ("output_rate_hz = 1000 Hz must divide the simulation rate"), one at
    1.7e9 s as not uniform (float64 rounds its steps by 2.4e-7 s)."""
    from rigsim.mjcf.variant import TruckVariant
    from rigsim.scenarios.core.config import load_scenario, paper_scenarios
    from rigsim.scenarios.records.model.model_runs import model_forces

    zero, shifted = read_channels(_pan_csv(tmp_path, 0.0)), read_channels(_pan_csv(tmp_path, start))
    _same(zero, shifted)
    assert shifted.fs_hz == FS and shifted.time_s[0] == 0.0
    np.testing.assert_array_equal(shifted.time_s, np.arange(N) / FS)
    assert float(shifted.metadata[TIME_START_KEY]) == start and TIME_START_KEY not in zero.metadata
    assert shifted.to_dict()["start_s"] == start
    sc = load_scenario(str(next(p for p in paper_scenarios() if "medium_72" in p.stem)))
    forces = [model_forces(TruckVariant(), r.time_s, r.array(), base_scenario=sc) for r in (zero, shifted)]
    np.testing.assert_array_equal(forces[0], forces[1])


@pytest.mark.parametrize("ext", [".rsp", ".mf4", ".tdms"])
@pytest.mark.parametrize("start", STARTS[1:])
def test_every_format_reads_its_clock_relative_to_the_first_sample(tmp_path, ext, start):
    if ext == ".mf4":
        pytest.importorskip("asammdf")
    if ext == ".tdms":
        pytest.importorskip("nptdms")
    t = start + np.arange(N) / FS
    rec = SimpleNamespace(time_s=t, data={"Fz_N": 3e4 + 100.0 * PAN[:, 0]}, units={"Fz_N": "N"})
    p = write_channels(tmp_path / f"r{ext}", rec)
    mc = read_channels(p)
    assert mc.time_s[0] == 0.0 and mc.fs_hz == FS
    np.testing.assert_array_equal(mc.time_s, np.arange(N) / FS)
    assert float(mc.metadata[TIME_START_KEY]) == pytest.approx(start, rel=1e-15)


def test_the_start_read_back_from_a_file_written_from_a_read_record(tmp_path):
    first = read_channels(_pan_csv(tmp_path, 86400.0))
    back = read_channels(write_channels(tmp_path / "again.csv", first))
    _same(first, back)
    assert back.metadata[TIME_START_KEY] == first.metadata[TIME_START_KEY] == repr(86400.0)


# ------------------------------------------------------------------ the rate read within a tolerance

@pytest.mark.parametrize("fs, digits", [(1024.0, 6), (2048.0, 7), (1000.0, 3), (3000.0, 7), (200.0, 4)])
@pytest.mark.parametrize("start", [0.0, 86400.0, 1.7e9])
def test_the_rate_of_rounded_times_is_the_rate_they_round(tmp_path, fs, digits, start):
    """Times printed with a few decimals (a 1024 Hz axis in whole microseconds is off by up to
    0.05 % of a step) give the rate they were rounded from, exactly."""
    n = 4000
    t = start + np.arange(n) / fs
    p = tmp_path / "r.csv"
    _csv(p, t, {"F": np.arange(n, dtype=float)}, fmt=lambda x: f"{x:.{digits}f}")
    mc = read_channels(p)
    assert mc.fs_hz == fs
    np.testing.assert_array_equal(mc.time_s, np.arange(n) / fs)


def test_a_jitter_within_the_tolerance_reads_at_the_mean_rate(tmp_path):
    rng = np.random.default_rng(3)
    t = np.arange(5000) / FS + rng.uniform(-2e-6, 2e-6, 5000)  # 0.4 % of a step
    p = tmp_path / "j.csv"
    _csv(p, t, {"F": np.ones(5000)})
    assert read_channels(p).fs_hz == FS


@pytest.mark.parametrize("where, shift, words", [
    (2500, 1e-3, "a gap, about 1 sample missing: the step from t = 2.499 s is 0.002 s"),
    (2500, 7e-3, "a gap, about 7 samples missing"),
    (1200, 0.4e-3, "1.4 times the record's step of 0.001 s"),
])
def test_a_gap_or_a_wobble_is_named_with_the_file_and_the_line(tmp_path, where, shift, words):
    t = np.arange(4000) / FS
    t[where:] += shift
    p = tmp_path / "g.csv"
    _csv(p, t, {"F": np.ones(4000)})
    with pytest.raises(MeasuredDataError) as exc:
        read_channels(p)
    msg = str(exc.value)
    assert f"column 'time' is not uniform at line {where + 2} of {str(p)!r}" in msg and words in msg, msg
    assert "\n" not in msg and "fix:" in msg


# ------------------------------------------------------------------ records built in Python

def _built(**changes):
    kw = dict(time_s=np.arange(N) / FS, data={"F": np.ones(N)}, units={"F": "N"}, source_units={"F": "N"}, fs_hz=FS,
              metadata={}, path="built", format="csv")
    kw.update(changes)
    return kw


@pytest.mark.parametrize("build", [MeasuredChannels, lambda **kw: make_channels(fmt=kw.pop("format"), **kw)],
                         ids=["class", "make_channels"])
@pytest.mark.parametrize("changes, words", [
    (dict(fs_hz=500.0), "fs_hz = 500 Hz contradicts time_s"),
    (dict(fs_hz=1000.5), "fs_hz = 1000.5 Hz contradicts time_s"),
    (dict(time_s=np.r_[np.arange(500), np.arange(501, N + 1)] / FS), "argument 'time_s' is not uniform at time_s[500]"),
    (dict(time_s=np.arange(N)[::-1] / FS), "argument 'time_s' does not increase at time_s[1]"),
    (dict(time_s=np.r_[np.nan, np.arange(1, N)] / FS), "argument 'time_s' is nan at time_s[0]"),
    (dict(time_s=np.arange(N) / 2e9, fs_hz=2e9), "above the 1e+06 Hz"),
    (dict(fs_hz=float("nan")), "fs_hz = nan Hz"),
    (dict(data={"F": np.ones(N - 1)}), "data['F'] has shape (999,) but time_s has (1000,)"),
    (dict(data={"F": np.r_[np.ones(N - 1), np.inf]}), "data['F'] is inf at sample 999"),
])
def test_a_record_built_in_python_is_checked_as_a_file_is(build, changes, words):
    with pytest.raises(MeasuredDataError) as exc:
        build(**_built(**changes))
    msg = str(exc.value)
    assert words in msg and "\n" not in msg and "fix:" in msg, msg


def test_a_record_built_in_python_on_a_clock_is_made_relative():
    mc = MeasuredChannels(**_built(time_s=86400.0 + np.arange(N) / FS))
    np.testing.assert_array_equal(mc.time_s, np.arange(N) / FS)
    assert mc.metadata[TIME_START_KEY] == repr(86400.0) and not mc.time_s.flags.writeable
    import dataclasses

    again = dataclasses.replace(mc, data={"F": np.zeros(N)})  # what a caller does to swap channels
    np.testing.assert_array_equal(again.time_s, mc.time_s)
    assert again.metadata[TIME_START_KEY] == repr(86400.0)


SETTINGS = settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@SETTINGS
@given(start=st.one_of(st.sampled_from([0.0, 86400.0, 1.7e9, 1.7e9 + 0.5]), st.floats(-1e6, 1e6)),
       fs=st.sampled_from([100.0, 200.0, 500.0, 512.0, 1000.0, 1024.0, 2000.0, 2048.0, 5000.0, 10000.0, 20000.0]),
       n=st.integers(200, 3000))
def test_any_start_and_usual_rate_builds_the_same_record(start, fs, n):
    """Any start a clock gives, with a rate labs use: the record of the same samples from 0 s."""
    t = start + np.arange(n) / fs
    if np.min(np.diff(t)) <= 0.99 / fs or np.max(np.diff(t)) >= 1.01 / fs:
        return  # float64 cannot hold this rate at this clock (1.7e9 s at 20 kHz)
    mc = make_channels(time_s=t, data={"F": np.ones(n)}, units={}, source_units={}, fs_hz=fs, metadata={},
                       path="built", fmt="csv")
    assert mc.fs_hz == fs
    np.testing.assert_array_equal(mc.time_s, np.arange(n) / fs)


@SETTINGS
@given(factor=st.one_of(st.floats(0.01, 0.999), st.floats(1.001, 100.0)), fs=st.sampled_from([100.0, 1000.0, 1024.0]))
def test_any_rate_off_the_axis_by_a_tenth_of_a_percent_is_refused(factor, fs):
    with pytest.raises(MeasuredDataError, match="contradicts time_s"):
        make_channels(time_s=np.arange(500) / fs, data={"F": np.ones(500)}, units={}, source_units={},
                      fs_hz=fs * factor, metadata={}, path="built", fmt="csv")


def test_the_rate_cap_is_a_road_simulators_and_more():
    assert MAX_RATE_HZ == 1e6
