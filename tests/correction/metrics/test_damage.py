"""rigsim.correction.metrics.damage (with rigsim.correction.metrics.rainflow_damage and rigsim.correction.metrics.spatial_load): pavement-damage
and fatigue measures of wheel forces, each pinned to a value worked by hand or published.

Hand-worked references used below:

- Sine F = F0 + a sin(theta), r = a / F0: the binomial expansion of E[(1 + r sin theta)^4] with
  the moments over a period E[sin] = E[sin^3] = 0, E[sin^2] = 1/2, E[sin^4] = 3/8 gives
  1 + 6 r^2 / 2 + r^4 3/8 = 1 + 3 r^2 + 3/8 r^4. Sampled at N > 4 equispaced points per period,
  the sample means of sin^2 and sin^4 are these exactly (the sums of cos(2 theta), cos(4 theta)
  over the points vanish).
- Cosine F0 + a cos(2 pi t / T) from peak to peak over n periods: reversals a, -a, ..., a; every
  range is 2a and the ASTM E1049-85 rainflow rule closes them in pairs of half cycles: n cycles
  of range 2a, mean F0; sum counts * range^m = n (2a)^m, so the DEL with N_eq = n is 2a.
- Gaussian force F0 (1 + c Z): E[(1 + c Z)^4] = 1 + 6 c^2 + 3 c^4 (Eisenmann 1975; Cebon,
  Handbook of Vehicle-Road Interaction, 1999); checked also against Gauss-Hermite quadrature.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigsim.correction.metrics.damage import (
    WOHLER_PRESETS,
    DamageMetrics,
    compare,
    damage_equivalent_load,
    damage_metrics,
    impact_factors,
    level_crossings,
    pseudo_damage,
    rainflow_cycles,
    spatial_correlation,
    spatial_profile,
    stress_factor,
    stress_factor_gaussian,
    top_loads,
)

F0 = 40e3  # N, a heavy-truck wheel load
A = 4e3  # N, sine amplitude: r = 0.1
PER = 64  # samples per period


def _sine(a=A, f0=F0, periods=8, per=PER):
    """F0 + a sin over whole periods, no end point (exact sample moments)."""
    theta = 2 * np.pi * np.arange(periods * per) / per
    return f0 + a * np.sin(theta)


def _cosine(a=A, f0=F0, periods=8, per=PER):
    """F0 + a cos from peak to peak over whole periods (end point included): exact reversals."""
    theta = 2 * np.pi * np.arange(periods * per + 1) / per
    return f0 + a * np.cos(theta)


# ---------------------------------------------------------------- stress and impact factors


def test_a_constant_force_has_stress_factor_1_and_no_fatigue_damage():
    f = np.full(500, F0)
    assert stress_factor(f) == pytest.approx(1.0, abs=1e-15)
    assert np.allclose(impact_factors(f), 1.0)
    ranges, means, counts = rainflow_cycles(f)
    assert ranges.size == means.size == counts.size == 0
    assert pseudo_damage(f, 5) == 0.0
    assert damage_equivalent_load(f, 5, duration_s=5.0) == 0.0


@pytest.mark.parametrize("a", [2e3, 4e3, 12e3])
def test_stress_factor_of_a_sine_is_1_plus_3r2_plus_3r4_over_8(a):
    r = a / F0
    expected = 1 + 3 * r ** 2 + 3 / 8 * r ** 4  # hand-worked, module docstring
    assert stress_factor(_sine(a)) == pytest.approx(expected, rel=1e-12)
    assert stress_factor(_sine(a), static_N=F0) == pytest.approx(expected, rel=1e-12)
    # against a static load of 2 F0 every term scales by 2^-4
    assert stress_factor(_sine(a), static_N=2 * F0) == pytest.approx(expected / 16, rel=1e-12)


def test_stress_factor_clamps_lift_off_at_zero():
    # half the samples at 2 F0, half at -F0 (lift-off, read as tension): (2^4 + 0) / 2 = 8
    f = np.tile([2 * F0, -F0], 50)
    assert stress_factor(f, static_N=F0) == pytest.approx(8.0)
    assert stress_factor(f, static_N=F0, n=3) == pytest.approx(4.0)  # odd n stays real


def test_gaussian_stress_factor_formula_and_quadrature():
    c = np.array([0.0, 0.05, 0.1, 0.3])
    assert np.allclose(stress_factor_gaussian(c, 4), 1 + 6 * c ** 2 + 3 * c ** 4, rtol=1e-15)
    assert stress_factor_gaussian(0.2, 2) == pytest.approx(1 + 0.2 ** 2)
    assert stress_factor_gaussian(0.2, 3) == pytest.approx(1 + 3 * 0.2 ** 2)
    assert stress_factor_gaussian(0.2, 0) == 1.0
    z, w = np.polynomial.hermite_e.hermegauss(20)  # exact for polynomials of degree < 40
    for n in (1, 4, 5, 8, 10):
        quad = np.sum(w * (1 + 0.25 * z) ** n) / math.sqrt(2 * math.pi)
        assert stress_factor_gaussian(0.25, n) == pytest.approx(quad, rel=1e-12)
    with pytest.raises(ValueError, match="integer"):
        stress_factor_gaussian(0.1, 4.5)


@pytest.mark.parametrize("c", [0.1, 0.2])
def test_a_gaussian_records_stress_factor_tends_to_the_gaussian_formula(c):
    n = 200_000
    z = np.random.default_rng(7).standard_normal(n)
    f = F0 * (1 + c * z)
    # the estimator is a mean of n iid Y = (1 + cZ)^4: standard error sqrt((E[Y^2] - E[Y]^2) / n),
    # E[Y^2] = E[(1 + cZ)^8]; 5 standard errors (a false failure once in ~3.5 million seeds)
    se = math.sqrt((stress_factor_gaussian(c, 8) - stress_factor_gaussian(c, 4) ** 2) / n)
    assert abs(stress_factor(f, static_N=F0) - stress_factor_gaussian(c, 4)) < 5 * se
    # with the sample mean as static load the bias is O(c^2 / n), far below the standard error
    assert abs(stress_factor(f) - stress_factor_gaussian(c, 4)) < 6 * se
    # and the test can fail: a DLC 10 % off is many standard errors away
    assert abs(stress_factor(f, static_N=F0) - stress_factor_gaussian(1.1 * c, 4)) > 5 * se


def test_impact_factors_of_a_sine_and_a_hand_worked_record():
    f = _cosine()
    i95, i999 = impact_factors(f, static_N=F0, percentiles=(50.0, 100.0))
    assert i999 == pytest.approx(1 + A / F0)  # the peak
    assert i95 == pytest.approx(1.0, abs=1e-12)  # the median of a symmetric record
    # 1..100 kN: numpy's linear percentile 95 -> 95.05 kN, over a 50 kN static load
    g = np.arange(1, 101) * 1e3
    assert impact_factors(g, static_N=50e3, percentiles=(95.0,))[0] == pytest.approx(95.05 / 50)


# ---------------------------------------------------------------- rainflow (ASTM E1049-85)


def test_astm_e1049_example_history_reproduces_the_standards_table():
    """ASTM E1049-85 section 5.4.4 rainflow counting, its example history (fig. 6):
    A=-2, B=1, C=-3, D=5, E=-1, F=3, G=-4, H=4, I=-2, worked by hand with the standard's rules
    (X the latest range, Y the previous one, S the starting point):
    C read: Y=A-B=3 <= X=4, Y holds S: half cycle 3 (A-B), S=B. D read: Y=B-C=4 <= X=8, holds S:
    half cycle 4 (B-C), S=C. E, F read: X<Y. G read: Y=E-F=4 <= X=7, no S: full cycle 4 (E-F),
    drop E, F; then Y=C-D=8 <= X=D-G=9, holds S: half cycle 8 (C-D), S=D. H, I read: X<Y.
    End: half cycles D-G=9, G-H=8, H-I=6. The standard's table: range 10: 0, 9: 0.5, 8: 1.0,
    7: 0, 6: 0.5, 5: 0, 4: 1.5, 3: 0.5 cycles.
    """
    history = np.array([-2, 1, -3, 5, -1, 3, -4, 4, -2], dtype=float)
    ranges, means, counts = rainflow_cycles(history)
    table = {rng: float(np.sum(counts[ranges == rng])) for rng in range(3, 11)}
    assert table == {10: 0.0, 9: 0.5, 8: 1.0, 7: 0.0, 6: 0.5, 5: 0.0, 4: 1.5, 3: 0.5}
    cycles = sorted(zip(ranges.tolist(), means.tolist(), counts.tolist()))
    assert cycles == sorted([(3, -0.5, 0.5), (4, -1.0, 0.5), (4, 1.0, 1.0), (8, 1.0, 0.5),
                             (9, 0.5, 0.5), (8, 0.0, 0.5), (6, 1.0, 0.5)])


def test_rainflow_of_a_sine_is_one_cycle_of_range_2a_per_period():
    periods = 8
    ranges, means, counts = rainflow_cycles(_cosine(periods=periods))
    assert np.allclose(ranges, 2 * A) and np.allclose(means, F0)
    assert counts.sum() == pytest.approx(periods)
    # from the mean level (a sine) the ends add two half cycles of range a: n - 1/2 cycles of 2a
    ranges, _, counts = rainflow_cycles(_sine(periods=periods))
    assert counts[np.isclose(ranges, 2 * A)].sum() == pytest.approx(periods - 0.5)


def _astm_reference(x):
    """An independent transcription of ASTM E1049-85 5.4.4 (peak-valley filter, then the rules)."""
    d = np.diff(x)
    keep = np.r_[True, d[:-1] * d[1:] < 0, True]
    stack, out = [], []
    for p in x[keep]:
        stack.append(p)
        while len(stack) >= 3:
            big_x, big_y = abs(stack[-1] - stack[-2]), abs(stack[-2] - stack[-3])
            if big_x < big_y:
                break
            if len(stack) == 3:  # Y contains the starting point: half cycle, S moves on
                out.append((big_y, (stack[0] + stack[1]) / 2, 0.5))
                stack.pop(0)
            else:
                out.append((big_y, (stack[-2] + stack[-3]) / 2, 1.0))
                del stack[-3:-1]
    out += [(abs(b - a), (a + b) / 2, 0.5) for a, b in zip(stack, stack[1:])]
    return np.array(sorted(out))


def test_rainflow_matches_a_transcription_of_the_standard_on_random_data():
    x = np.random.default_rng(3).standard_normal(5000) * 3e3 + F0
    lib = np.array(sorted(zip(*rainflow_cycles(x))))
    ref = _astm_reference(x)
    assert lib.shape == ref.shape and np.allclose(lib, ref, rtol=0, atol=1e-9)


# ---------------------------------------------------------------- pseudo-damage and DEL


@pytest.mark.parametrize("m", sorted(WOHLER_PRESETS.values()))
def test_del_of_a_sine_is_2a_when_n_eq_is_the_number_of_cycles(m):
    periods = 8
    f = _cosine(periods=periods)
    assert pseudo_damage(f, m) == pytest.approx(periods * (2 * A) ** m, rel=1e-12)
    assert damage_equivalent_load(f, m, n_equivalent=periods) == pytest.approx(2 * A, rel=1e-12)
    # 1 Hz convention over 4 s of a 2 Hz sine: N_eq = 4, 8 cycles: DEL = 2a 2^(1/m)
    assert damage_equivalent_load(f, m, duration_s=4.0) == pytest.approx(2 * A * 2 ** (1 / m), rel=1e-12)
    assert damage_equivalent_load(f, m, duration_s=4.0, f_equivalent_hz=2.0) == pytest.approx(2 * A, rel=1e-12)


def test_wohler_presets_and_del_argument_errors():
    assert WOHLER_PRESETS == {"welded steel": 3, "steel": 5, "composite": 10}
    with pytest.raises(ValueError, match="n_equivalent or duration_s"):
        damage_equivalent_load(_cosine(), 5)
    with pytest.raises(ValueError, match="positive"):
        damage_equivalent_load(_cosine(), 5, n_equivalent=0)
    with pytest.raises(ValueError, match="NaN"):
        pseudo_damage(np.r_[_cosine(), np.nan], 5)


# ---------------------------------------------------------------- level crossings


def test_level_crossings_hand_worked_and_of_a_sine():
    # 0->2 crosses 1, 0->2 crosses, 2->1 no, 1->3 crosses (at or below, then above): 3;
    # 0->1->0 only touches 1: none
    assert level_crossings([0, 2, 0, 2, 1, 3], [1.0]).tolist() == [3]
    assert level_crossings([0, 1, 0], [1.0]).tolist() == [0]
    periods = 8
    levels = [F0 - 2 * A, F0 - A / 2, F0, F0 + A / 2, F0 + 0.999 * A, F0 + 2 * A]
    assert level_crossings(_sine(periods=periods), levels).tolist() == [0, 8, 8, 8, 8, 0]


# ---------------------------------------------------------------- spatial view


def test_spatial_profile_is_the_exact_cell_mean():
    speed, fs, dx = 20.0, 2000.0, 0.5  # 1 cm between samples
    x_s = speed * np.arange(2001) / fs  # 20 m
    x, p = spatial_profile(3.0 * x_s + F0, speed, fs, dx)  # a linear force: cell mean = centre value
    assert x.size == 40 and x[0] == pytest.approx(0.25)
    assert np.allclose(p, 3.0 * x + F0, rtol=1e-13)
    # a sine of wavelength lam averaged over a cell of length dx: sinc(dx / lam) times its centre value
    lam = 2.0
    _, p = spatial_profile(F0 + A * np.sin(2 * np.pi * x_s / lam), speed, fs, dx)
    expected = F0 + A * np.sinc(dx / lam) * np.sin(2 * np.pi * x / lam)
    assert np.allclose(p, expected, rtol=0, atol=1e-4 * A)


def test_spatial_correlation_of_same_and_independent_profiles():
    rng = np.random.default_rng(11)
    a = F0 + 3e3 * rng.standard_normal(10_000)
    b = F0 + 3e3 * rng.standard_normal(10_000)
    assert spatial_correlation(a, a) == pytest.approx(1.0, abs=1e-12)
    assert spatial_correlation(a, 2 * a + 5e3) == pytest.approx(1.0, abs=1e-12)  # only the dynamic part
    assert spatial_correlation(a, 2 * F0 - a) == pytest.approx(-1.0, abs=1e-12)
    # independent profiles: r ~ N(0, 1/m); 4.5 standard deviations
    assert abs(spatial_correlation(a, b)) < 4.5 / math.sqrt(a.size)
    r = spatial_correlation(np.c_[a, a], np.c_[a[:-7], b[:-7]])  # per column, cut to the shorter
    assert r[0] == pytest.approx(1.0) and abs(r[1]) < 0.05


def test_top_loads_finds_the_largest_peaks_where_they_are():
    x = np.arange(0, 12, 0.1)
    p = F0 + 1e3 * (3 * np.exp(-((x - 2) / 0.2) ** 2) + np.exp(-((x - 5) / 0.2) ** 2)
                    + 2 * np.exp(-((x - 9) / 0.2) ** 2) + 2.9 * np.exp(-((x - 2.5) / 0.2) ** 2))
    xs, fs = top_loads(x, p, k=2, min_separation_m=1.0)  # the 2.5 m bump merges into 2 m's
    assert np.allclose(xs, [2.0, 9.0], atol=0.11) and fs[0] > fs[1]
    xs, _ = top_loads(x, p, k=2, min_separation_m=0.2)
    assert np.allclose(sorted(xs), [2.0, 2.5], atol=0.11)


# ---------------------------------------------------------------- result object and comparison


def test_per_column_results_equal_the_one_column_ones():
    two = np.c_[_cosine(A), _cosine(2 * A, 30e3)]
    assert np.allclose(stress_factor(two), [stress_factor(two[:, 0]), stress_factor(two[:, 1])])
    assert np.allclose(pseudo_damage(two, 5), [pseudo_damage(two[:, 0], 5), pseudo_damage(two[:, 1], 5)])
    assert impact_factors(two).shape == (2, 2)
    assert len(rainflow_cycles(two)) == 2


def test_damage_metrics_of_a_sine_and_compare():
    fs, periods = 128.0, 8  # 2 Hz cosine, 513 samples
    f = _cosine(periods=periods)
    two = np.c_[f, F0 + 1.1 * (f - F0)]
    dm = damage_metrics(two, fs)
    assert isinstance(dm, DamageMetrics)
    r = A / F0
    assert dm.duration_s == pytest.approx(f.size / fs) and dm.n_equivalent == pytest.approx(f.size / fs)
    assert dm.stress_factor_4_gaussian[0] == pytest.approx(1 + 6 * dm.dlc[0] ** 2 + 3 * dm.dlc[0] ** 4)
    assert dm.impact_999[0] == pytest.approx((F0 + A) / dm.mean_N[0], rel=1e-12)
    # DEL: 8 cycles of 2a over N_eq = 513 / 128 equivalent cycles
    for m in (3, 5, 10):
        assert dm.del_m(m)[0] == pytest.approx(2 * A * (periods / (f.size / fs)) ** (1 / m), rel=1e-12)
    assert dm.del_m5[1] == pytest.approx(1.1 * dm.del_m5[0])
    assert dm.pseudo_damage_m5[0] == pytest.approx(periods * (2 * A) ** 5)
    d = dm.to_dict()
    assert d["del_m3_N"] == list(dm.del_N[0]) and "pseudo_damage_m10" in d and d["exponents"] == [3.0, 5.0, 10.0]

    road = damage_metrics(f, fs, static_N=F0)
    other = damage_metrics(F0 + 1.1 * (f - F0), fs, static_N=F0)
    errors = compare(road, other)
    assert errors["del_m5_N"][0] == pytest.approx(0.1)
    assert errors["pseudo_damage_m5"][0] == pytest.approx(1.1 ** 5 - 1)
    # the DLC scales by 1.1 up to the end point's shift of the mean (F0 + a / 513 vs F0 + 1.1 a / 513)
    assert errors["dlc"][0] == pytest.approx(0.1, rel=1e-3)
    # stress factor of the 513 samples: 512 over 8 whole periods (1 + 3 q^2 + 3/8 q^4 each on
    # average) and the end point at the peak, (1 + q)^4; the comparison is of the increment over 1
    sf = lambda q: (512 * (1 + 3 * q ** 2 + 3 / 8 * q ** 4) + (1 + q) ** 4) / 513  # noqa: E731
    assert road.stress_factor_4[0] == pytest.approx(sf(r), rel=1e-12)
    assert errors["stress_factor_4"][0] == pytest.approx(sf(1.1 * r) / sf(r) - 1, rel=1e-9)
    assert errors["stress_factor_4_increment"][0] == pytest.approx((sf(1.1 * r) - 1) / (sf(r) - 1) - 1, rel=1e-9)
    assert all(v == [0.0] for v in compare(road, road).values())
    with pytest.raises(ValueError, match="same columns"):
        compare(road, dm)


def test_cycles_counted_on_the_turning_points_are_the_librarys_on_every_sample():
    """rainflow_cycles counts with numpy (reversals, four-point passes, the stack on the rest;
    tests/correction/metrics/test_rainflow_fast.py for generated and awkward histories): the reference is
    ``rainflow.extract_cycles`` on the raw history, exactly (ranges, means and counts, in order),
    on 3000 short histories with plateaus, constant and monotone runs, and on a long noisy one."""
    rainflow = pytest.importorskip("rainflow")  # the test extra's reference

    from rigsim.correction.metrics.rainflow_damage import rainflow_cycles

    def library(f):
        rows = [(r, m, c) for r, m, c, _i, _j in rainflow.extract_cycles(f) if r > 0]
        return tuple(np.asarray(v, dtype=float) for v in zip(*rows)) if rows else (np.zeros(0),) * 3

    rng = np.random.default_rng(2026)
    histories = []
    for trial in range(3000):
        n = int(rng.integers(2, 40))
        kind = trial % 5
        histories.append([rng.standard_normal(n), np.round(2 * rng.standard_normal(n)),
                          np.cumsum(np.round(rng.standard_normal(n))), np.full(n, 3.0),
                          np.sort(rng.standard_normal(n))[::(1 if trial % 2 else -1)]][kind])
    histories.append(np.cumsum(rng.standard_normal(50_000)) + 5 * rng.standard_normal(50_000))
    for f in histories:
        if len(f) == 2:  # the library drops a 2-point series' last point: see the half-cycle test below
            continue
        ours = rainflow_cycles(f)
        ref = library(f)
        assert all(np.array_equal(a, b) for a, b in zip(ours, ref)), f


# ---------------------------------------------------------------- input checks and reversals (rainflow_damage)


def test_turning_points_are_the_first_sample_the_reversals_and_the_last():
    # Worked by hand from the definition (turning_points docstring): plateaus count once, a
    # monotone sample is no reversal, however small its slope; a constant record is one value.
    from rigsim.correction.metrics.rainflow_damage import turning_points

    f = np.array([0.0, 0.1, 0.2, 0.1, 0.1, 0.15, 0.3, -2.0, -2.5])
    assert turning_points(f).tolist() == [0.0, 0.2, 0.1, 0.3, -2.5]
    assert turning_points(np.array([1.0, 2.0, 3.0, 4.0])).tolist() == [1.0, 4.0]
    assert turning_points(np.array([5.0, 5.0, 5.0])).tolist() == [5.0]


def test_force_records_are_checked_with_one_sentence_naming_the_fault():
    from rigsim.correction.metrics.rainflow_damage import force_columns

    with pytest.raises(ValueError, match=r"needs at least two samples along axis 0, got 1$"):
        pseudo_damage(np.array([F0]), 5)
    with pytest.raises(ValueError, match=r"needs at least two samples along axis 0, got 1$"):
        pseudo_damage(np.full((1, 3), F0), 5)
    with pytest.raises(ValueError, match="has no columns"):
        pseudo_damage(np.zeros((5, 0)), 5)
    with pytest.raises(ValueError, match="must be 1-D"):
        force_columns(np.zeros((4, 2, 2)))
    f, one = force_columns(np.arange(2.0))  # two samples are enough
    assert f.shape == (2, 1) and one


@pytest.mark.parametrize("m, ok", [(0.5, True), (3.0, True), (0.0, False), (-1.0, False), (-0.5, False),
                                   (math.inf, False), (math.nan, False)])
def test_wohler_exponent_must_be_a_positive_number(m, ok):
    f = _cosine(periods=2)
    if ok:  # pseudo-damage sum n S^m: 2 cycles of 2a
        assert pseudo_damage(f, m) == pytest.approx(2 * (2 * A) ** m, rel=1e-12)
        return
    with pytest.raises(ValueError, match="the Woehler exponent m must be a positive number"):
        pseudo_damage(f, m)


@pytest.mark.parametrize("n_eq, ok", [(0.5, True), (-2.0, False), (0.0, False), (math.inf, False)])
def test_equivalent_cycles_must_be_positive(n_eq, ok):
    f = _cosine(periods=2)
    if ok:  # Miner: (2 (2a)^m / N_eq)^(1/m)
        assert damage_equivalent_load(f, 5, n_equivalent=n_eq) == pytest.approx(2 * A * (2 / n_eq) ** 0.2, rel=1e-12)
        return
    with pytest.raises(ValueError, match="n_equivalent must be a positive number of equivalent cycles"):
        damage_equivalent_load(f, 5, n_equivalent=n_eq)


def test_del_of_a_small_force_is_not_rounded():
    # 8 cycles of range 0.6 N, N_eq = 7: DEL = 0.6 (8/7)^(1/3) N (the damage ratio 0.247 is below 1).
    f = _cosine(a=0.3, f0=1.0, periods=8)
    assert damage_equivalent_load(f, 3, n_equivalent=7) == pytest.approx(0.6 * (8 / 7) ** (1 / 3), rel=1e-12)


def test_level_crossings_per_column_and_level_checks():
    # Column 0: the hand-worked record (3 crossings of 1.0); column 1: a ramp 0..5 (one crossing).
    two = np.c_[[0, 2, 0, 2, 1, 3], np.arange(6.0)]
    with np.errstate(all="raise"):  # counted without any numpy floating-point or division warning
        counts = level_crossings(two, [1.0, 2.5])
    assert counts.tolist() == [[3, 1], [1, 1]]
    for bad in ([np.nan], [[1.0, 2.0]], [1.0, math.inf]):
        with pytest.raises(ValueError, match="levels_N must be a finite scalar or 1-D array"):
            level_crossings(two, bad)


def test_a_two_sample_record_is_one_half_cycle_of_its_range():
    """ASTM E1049-85 5.4.4: the first and last points count as reversals, so [0, 3] is a half
    cycle of range 3 (the rainflow library alone drops the last point of a 2-point series)."""
    from rigsim.correction.metrics.rainflow_damage import rainflow_cycles

    ranges, means, counts = rainflow_cycles(np.array([0.0, 3.0]))
    assert ranges.tolist() == [3.0] and means.tolist() == [1.5] and counts.tolist() == [0.5]
    assert rainflow_cycles(np.array([2.0, 2.0]))[0].size == 0  # a constant record has none
