"""Properties of the measured-data readers and writers on generated records (hypothesis)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, assume, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from hypothesis.extra import numpy as hnp  # noqa: E402

from rigsim.correction.io.measured import read_channels, write_channels  # noqa: E402
from rigsim.correction.io.measured_core import is_time_name  # noqa: E402
from rigsim.correction.io.measured_units import suffix_unit  # noqa: E402
from rigsim.correction.io.rpc3 import INT_FULL_SCALE  # noqa: E402

NAME = st.from_regex(r"[A-Za-z][A-Za-z0-9_]{0,11}", fullmatch=True).filter(
    lambda n: not is_time_name(n) and not suffix_unit(n))
VALUE = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e12, max_value=1e12)


@st.composite
def records(draw, max_n=60):
    n = draw(st.integers(2, max_n))
    names = draw(st.lists(NAME, min_size=1, max_size=4, unique_by=str.lower))
    dt = draw(st.sampled_from([1e-4, 1 / 1024, 0.001, 0.002, 0.01]))
    t0 = draw(st.floats(-100, 100, allow_nan=False))
    t = t0 + np.arange(n) * dt
    data = {nm: draw(hnp.arrays(float, n, elements=VALUE)) for nm in names}
    units = {nm: draw(st.sampled_from(["N", "m", "Pa", "1", ""])) for nm in names}
    return SimpleNamespace(time_s=t, data=data, units=units)


SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def _same_clock(back, rec) -> None:
    """The times of ``rec`` read back from the first sample at their rate, the first sample's
    time as metadata (``time_start_s``)."""
    t = np.asarray(rec.time_s)
    assert back.fs_hz == pytest.approx((t.size - 1) / (t[-1] - t[0]), rel=1e-9)
    np.testing.assert_array_equal(back.time_s, np.arange(t.size) / back.fs_hz)
    assert float(back.metadata.get("time_start_s", "0")) == pytest.approx(t[0], rel=1e-15, abs=1e-12)


@SETTINGS
@given(rec=records())
def test_csv_round_trip_is_exact(tmp_path_factory, rec):
    p = write_channels(tmp_path_factory.mktemp("csv") / "r.csv", rec)
    back = read_channels(p)
    _same_clock(back, rec)
    assert list(back.data) == list(rec.data)
    for n, v in rec.data.items():
        np.testing.assert_array_equal(back.data[n], v)
        assert back.units[n] == rec.units[n]


@SETTINGS
@given(rec=records())
def test_german_layout_of_the_same_numbers_reads_the_same(tmp_path_factory, rec):
    """Semicolons, decimal commas and a units row: the numbers of the comma/point file, exactly."""
    names = list(rec.data)
    lines = [";".join(["Zeit"] + names), ";".join(["s"] + [rec.units[n] or "-" for n in names])]
    for i in range(rec.time_s.size):
        lines.append(";".join(repr(float(x)).replace(".", ",") for x in [rec.time_s[i]] + [rec.data[n][i] for n in names]))
    p = tmp_path_factory.mktemp("de") / "r.csv"
    p.write_text("\r\n".join(lines) + "\r\n", encoding="utf-8")
    back = read_channels(p)
    _same_clock(back, rec)
    for n, v in rec.data.items():
        np.testing.assert_array_equal(back.data[n], v)


@SETTINGS
@given(rec=records(max_n=3000))
def test_rpc3_round_trip_within_half_a_step(tmp_path_factory, rec):
    # A channel's int16 scale is its peak / 32767: a peak below ~1e-200 underflows it (not a
    # measured signal). Zeros and tiny samples inside a normal channel are fine (they quantize to
    # 0 within half a step); filtering on every sample instead fails hypothesis's health check.
    assume(all(np.max(np.abs(v)) > 1e-200 or not np.any(v) for v in rec.data.values()))
    p = write_channels(tmp_path_factory.mktemp("rpc") / "r.rsp", rec)
    back = read_channels(p)
    assert back.n_samples == rec.time_s.size
    _same_clock(back, rec)
    for n, v in rec.data.items():
        step = np.max(np.abs(v)) / INT_FULL_SCALE if np.any(v) else 1.0
        assert np.max(np.abs(back.data[n] - v)) <= 0.5 * step * (1 + 1e-9)
