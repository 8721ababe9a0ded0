"""``timeseries.csv`` is formatted with numpy (rigsim.scenarios.core.results._csv_rows): its bytes must be
exactly ``numpy.savetxt(..., delimiter=",", fmt="%.10g")``'s, i.e. Python's own ``"%.10g" % x``
for every number (the reference: CPython's correctly rounded float formatting, round half to
even on exact ties), over every magnitude, the numbers whose ten-digit rounding is a tie or
nearly one, powers of ten and their neighbours, zeros, non-finite and subnormal values.
"""

from __future__ import annotations

import io

import numpy as np
import pytest

from rigsim.scenarios.core import results
from rigsim.scenarios.core.results import CSV_BLOCK_ROWS, RunResult, csv_parts


def _savetxt(block: np.ndarray) -> bytes:
    buf = io.StringIO()
    np.savetxt(buf, block, delimiter=",", fmt="%.10g")
    return buf.getvalue().encode("ascii")


def _assert_same(block):
    block = np.atleast_2d(np.asarray(block, dtype=float))
    ours, ref = results._csv_rows(block), _savetxt(block)
    if ours != ref:  # name the first number that differs
        for a, b in zip(ours.decode().split("\n"), ref.decode().split("\n")):
            assert a == b
    assert ours == ref


RNG = np.random.default_rng(7)


@pytest.mark.parametrize("scale", [1e-13, 1e-12, 1e-6, 1e-5, 1e-4, 1e-3, 0.1, 1.0, 10.0, 1e4, 1e5, 1e9, 1e10,
                                   1e11, 1e15, 1e30, 1e31, 1e35, 1e300])
def test_every_magnitude_as_savetxt_writes_it(scale):
    _assert_same(RNG.standard_normal((700, 5)) * scale)
    _assert_same(np.round(RNG.standard_normal((700, 5)) * 1e4) * scale)  # short decimals, trailing zeros


def test_ties_and_near_ties_of_the_tenth_digit():
    k = RNG.integers(1, 10**10, 20_000)
    ties = (k + 0.5) / 10.0 ** RNG.integers(0, 12, 20_000)  # many are exact binary ties, the rest near ones
    for x in (ties, np.nextafter(ties, np.inf), np.nextafter(ties, -np.inf)):
        _assert_same(x.reshape(-1, 4))
    _assert_same([[0.5, 1.5, 2.5, 123456789.5, 1234567890.5, 12345678905.0, 0.12345678905, 9.9999999995]])


def test_powers_of_ten_their_neighbours_and_roundings_up_to_them():
    p = 10.0 ** np.arange(-20, 40)
    _assert_same(np.concatenate([p, np.nextafter(p, 0), np.nextafter(p, np.inf), -p, 9.9999999995 * p,
                                 9.999999999 * p, 9.99999999949 * p]).reshape(-1, 1))


def test_zeros_non_finite_subnormal_and_extreme_values():
    _assert_same([[0.0, -0.0, np.nan, np.inf, -np.inf, 5e-324, -1e-310, 1.7976931348623157e308, 1e-4,
                   9.9999999999e-5, -123.0, 1e10, 9999999999.5]])


def test_log_uniform_values_of_both_signs_in_blocks_larger_than_one_pass():
    x = np.exp(RNG.uniform(-30, 70, (40_000, 3))) * RNG.choice([-1.0, 1.0], (40_000, 3))
    assert x.size > results._FORMAT_VALUES
    _assert_same(x)
    _assert_same(x[:1, :1])  # one number


def test_a_runs_timeseries_file_is_savetxts():
    n = 2 * CSV_BLOCK_ROWS + 37
    t = np.arange(n) / 1000.0
    signals = {"profile_m": RNG.standard_normal((n, 4)) * 3e-3,
               "tire_force_N": 3e4 + 4e3 * RNG.standard_normal((n, 4)),
               "spool": np.clip(RNG.standard_normal((n, 4)), -1, 1), "p1_Pa": 1e7 + 1e6 * RNG.standard_normal((n, 4))}
    r = RunResult(scenario_name="s", mode="rig", t_s=t, signals=signals, vehicle_mass_kg=1.0)
    expected = [(",".join(r.column_names()) + "\n").encode("ascii")]
    expected += [_savetxt(r.rows(i, min(n, i + CSV_BLOCK_ROWS))) for i in range(0, n, CSV_BLOCK_ROWS)]
    assert b"".join(csv_parts(r)) == b"".join(expected)
