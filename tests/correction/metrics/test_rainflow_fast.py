"""rigsim.correction.metrics.rainflow_damage counts rainflow cycles with numpy (four-point passes, the standard's
stack on what is left, the library's order from each cycle's closing point): the result must be
exactly ``rainflow.extract_cycles``' (rainflow 3.2.0, the reference chosen in the module
docstring) on the raw history: the same cycles, bit-for-bit equal ranges and means, the same
0.5/1.0 counts, in the same order (so that sums over the cycles, pseudo-damage and DEL, are the
same floats too).

Independent references:

- ASTM E1049-85 (2011) section 5.4.4, its example history (fig. 6), worked by hand in the order
  the standard's rules count the cycles (see the test);
- ``rainflow.extract_cycles`` on generated histories (hypothesis): floats, small integer sets
  that force equal ranges, plateaus and repeated values, values of very different magnitudes so
  that float differences round (ties in the rounded ranges of unequal exact ranges), slope
  products that underflow or overflow, 2 and 3 samples, constant records; and long histories
  (random walks, integer walks full of ties, growing and decaying chirps).
"""

from __future__ import annotations

import numpy as np
import pytest

from rigsim.correction.metrics.rainflow_damage import damage_equivalent_load, pseudo_damage, rainflow_cycles

rainflow = pytest.importorskip("rainflow")
hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


def _library(f):
    """``rainflow.extract_cycles`` on the raw history, zero ranges left out (as rainflow_cycles)."""
    rows = [(r, m, c) for r, m, c, _i, _j in rainflow.extract_cycles(list(f)) if r > 0]
    return tuple(np.asarray(v, dtype=float) for v in zip(*rows)) if rows else (np.zeros(0),) * 3


def _assert_same(f):
    f = np.asarray(f, dtype=float)
    ours = rainflow_cycles(f)
    ref = _library(f)
    if f.size == 2 and f[0] != f[1]:  # the library alone drops the last point of 2 samples
        ref = (np.array([abs(f[0] - f[1])]), np.array([0.5 * (f[0] + f[1])]), np.array([0.5]))
    for a, b in zip(ours, ref):
        assert a.dtype == np.float64 and a.shape == b.shape
        assert np.array_equal(a, b), (f.tolist(), ours, ref)  # exact, in order
    return ours


def test_astm_e1049_example_in_the_order_the_standard_counts():
    """E1049-85 fig. 6: A=-2, B=1, C=-3, D=5, E=-1, F=3, G=-4, H=4, I=-2. By the rules of 5.4.4
    (X the latest range, Y the previous one, S the starting point): C read: half cycle A-B
    (range 3, mean -0.5); D read: half cycle B-C (4, -1); G read: full cycle E-F (4, 1), then
    half cycle C-D (8, 1); end: half cycles D-G (9, 0.5), G-H (8, 0), H-I (6, 1)."""
    ranges, means, counts = _assert_same([-2, 1, -3, 5, -1, 3, -4, 4, -2])
    assert ranges.tolist() == [3, 4, 4, 8, 9, 8, 6]
    assert means.tolist() == [-0.5, -1.0, 1.0, 1.0, 0.5, 0.0, 1.0]
    assert counts.tolist() == [0.5, 0.5, 1.0, 0.5, 0.5, 0.5, 0.5]


def test_nested_cycles_close_in_order_of_their_closing_point():
    # Worked by hand with the same rules: 0, 10, 5, 8, 0, 3, 0, 12. Read 0 (index 4): X = 8 >= Y = 3:
    # full 5-8 (3, 6.5); then X = 10 >= Y = 10 with S: half 0-10 (10, 5). Read 0 (index 6): full
    # 0-3 (3, 1.5). Read 12: X = 12 >= Y = 10 with S: half 10-0 (10, 5). End: half 0-12 (12, 6).
    # The four-point passes take 5-8 and 0-3 out first; the half cycle 0-10 closes at index 4,
    # before 0-3, although both are counted at the pass's next point 0 (index 6).
    ranges, means, counts = _assert_same([0, 10, 5, 8, 0, 3, 0, 12])
    assert list(zip(ranges.tolist(), means.tolist(), counts.tolist())) == [
        (3, 6.5, 1.0), (10, 5.0, 0.5), (3, 1.5, 1.0), (10, 5.0, 0.5), (12, 6.0, 0.5)]


def test_a_tie_of_rounded_ranges_is_left_to_the_stack():
    """A = 1e16+6, B = -1e16, C = 1e16+6, D = 1, E = 1e16+4 (doubles are 2 apart near 1e16, 4 near
    2e16): |C - D| = 1e16+5 and |D - E| = 1e16+3 both round to 1e16+4, though E lies below C.
    The standard's stack counts the half cycle A-B when C arrives (X = Y = 2e16+8 rounded), the
    full cycle C-D when E arrives, then the residue B-E (2e16+4). Taking C-D out first on the
    rounded ranges alone would leave A-B (2e16+8 > 2e16+4) to the residue, counted after C-D."""
    ranges, means, counts = _assert_same([1e16 + 6, -1e16, 1e16 + 6, 1.0, 1e16 + 4])
    assert ranges.tolist() == [2e16 + 8, 1e16 + 4, 2e16 + 4] and counts.tolist() == [0.5, 1.0, 0.5]
    assert means.tolist() == [3.0, 5e15 + 4, 2.0]


def test_short_and_constant_records():
    assert [a.tolist() for a in _assert_same([0.0, 3.0])] == [[3.0], [1.5], [0.5]]
    assert [a.tolist() for a in _assert_same([3.0, 1.0, 2.0])] == [[2.0, 1.0], [2.0, 1.5], [0.5, 0.5]]
    for f in ([2.0, 2.0], [2.0, 2.0, 2.0], np.full(100, 4e4)):
        assert all(a.size == 0 for a in _assert_same(f))


_SETTINGS = settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
_floats = st.floats(min_value=-1e5, max_value=1e5, allow_nan=False, allow_infinity=False)
#: values of very different magnitudes: differences round, unequal exact ranges tie when rounded,
#: slope products underflow (1e-170 squared) or overflow (1e200 squared)
_awkward = st.sampled_from([0.0, -0.0, 1.0, 2.0, 3.0, -1.0, 0.1, 0.2, 0.3, 1e-170, -1e-170, 2e-170, 5e-324,
                            1e200, -1e200, 40e3, 40e3 + 1e-11] + [s * 1e16 + k for s in (1, -1) for k in range(-8, 9, 2)])


def _with_plateaus(values):
    """Each value repeated 1 to 3 times (plateaus, and equal samples a run apart)."""
    return st.lists(st.tuples(values, st.integers(1, 3)), min_size=2, max_size=40).map(
        lambda runs: [v for v, k in runs for _ in range(k)])


@_SETTINGS
@given(st.lists(_floats, min_size=2, max_size=60))
def test_same_as_the_library_on_floats(f):
    _assert_same(f)


@_SETTINGS
@given(st.lists(st.integers(-2, 2), min_size=2, max_size=60) | _with_plateaus(st.integers(0, 3)))
def test_same_as_the_library_with_equal_ranges_and_plateaus(f):
    _assert_same(f)


@_SETTINGS
@given(st.lists(_awkward, min_size=2, max_size=40) | _with_plateaus(_awkward))
def test_same_as_the_library_when_float_differences_round(f):
    with np.errstate(over="ignore"):
        _assert_same(f)


@_SETTINGS
@given(st.lists(_floats, min_size=2, max_size=3), st.integers(2, 50), _floats)
def test_same_as_the_library_on_2_and_3_samples_and_constants(f, n, c):
    _assert_same(f)
    _assert_same([c] * n)


def test_same_as_the_library_on_long_records():
    """Long enough for many four-point passes, long closing searches and a long stack: a noisy
    random walk (the wheel-force case), integer walks and random integers (ties everywhere), a
    chirp growing out of zero (all ranges grow: the stack counts it) and one decaying to zero."""
    rng = np.random.default_rng(2026)
    n = 40_000
    t = np.linspace(0.0, 2000.0, n)  # 318 periods of 126 samples
    records = [np.cumsum(rng.standard_normal(n)) * 300 + 2e3 * rng.standard_normal(n) + 4e4,
               np.cumsum(rng.integers(-3, 4, n)).astype(float), rng.integers(0, 4, n).astype(float),
               np.sin(t) * (t / t[-1]) ** 2 * 5e3, np.sin(t) * (1 - t / t[-1]) * 5e3]
    for f in records:
        ranges, _, counts = _assert_same(f)
        assert counts.sum() > 250


def test_damage_sums_are_the_library_order_sums():
    """pseudo_damage and the DEL sum count * range^m in the library's order: the same floats."""
    f = np.cumsum(np.random.default_rng(5).standard_normal(20_000)) * 500 + 4e4
    r, _, c = _library(f)
    assert pseudo_damage(f, 5) == float(np.sum(c * r ** 5.0))
    assert damage_equivalent_load(f, 5, duration_s=20.0) == (float(np.sum(c * r ** 5.0)) / 20.0) ** 0.2
