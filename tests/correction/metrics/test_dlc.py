"""rigsim.correction.metrics.dlc: the NRMSE against a reference force, on hand-worked examples.

Over a whole number of periods a sampled unit sine has mean 0 and mean square exactly 1/2, so
its population standard deviation is 1/sqrt(2). A copy shifted by a constant c has an error of
RMS |c|, hence NRMSE = |c| / (1/sqrt(2)) = sqrt(2) |c|. A constant equal to the reference's mean
has an error of RMS std(reference): NRMSE 1.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigsim.correction.metrics.dlc import dlc, force_statistics, nrmse

N = 400  # samples over exactly 4 periods


def _sine():
    t = np.arange(N) / N
    return np.sin(2 * np.pi * 4 * t)


def test_nrmse_of_a_sine_shifted_by_a_constant_is_sqrt2_times_the_shift():
    ref = _sine()
    assert float(nrmse(ref + 0.1, ref)) == pytest.approx(0.1 * math.sqrt(2), rel=1e-12)
    assert float(nrmse(ref - 0.3, ref)) == pytest.approx(0.3 * math.sqrt(2), rel=1e-12)


def test_nrmse_is_per_column_and_along_the_given_axis():
    ref = np.column_stack([_sine(), 30e3 + 3e3 * _sine()])  # N: the static load is not in the denominator
    x = ref + np.array([0.1, 600.0])
    expected = [0.1 * math.sqrt(2), 600.0 / (3e3 / math.sqrt(2))]
    np.testing.assert_allclose(nrmse(x, ref), expected, rtol=1e-12)
    np.testing.assert_allclose(nrmse(x.T, ref.T, axis=1), expected, rtol=1e-12)


def test_nrmse_mean_free_leaves_the_errors_mean_out():
    """A shift by a constant is all mean: mean_free scores it 0; a scaled copy keeps its error."""
    ref = np.column_stack([_sine(), 30e3 + 3e3 * _sine()])
    assert np.all(nrmse(ref + np.array([0.1, 600.0]), ref, mean_free=True) < 1e-12)
    np.testing.assert_allclose(nrmse(1.1 * ref + 5.0, ref, mean_free=True), [0.1, 0.1], rtol=1e-9)
    np.testing.assert_allclose(nrmse(ref.T + 0.2, ref.T, axis=1, mean_free=True), [0.0, 0.0], atol=1e-12)


def test_nrmse_is_zero_for_the_reference_and_one_for_its_mean():
    ref = 30e3 + 3e3 * _sine()
    assert float(nrmse(ref, ref)) == 0.0
    assert float(nrmse(np.full(N, ref.mean()), ref)) == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("x, ref, match", [
    (np.zeros(3), np.zeros(4), "same shape"),
    ([1.0], [2.0], "at least two samples"),
    ([1.0, np.nan], [1.0, 2.0], "NaN or infinite"),
    ([1.0, 2.0], [5.0, 5.0], "constant"),
])
def test_nrmse_refuses_what_has_no_nrmse(x, ref, match):
    with pytest.raises(ValueError, match=match):
        nrmse(x, ref)


def test_dlc_of_a_sine_on_a_static_load():
    force = 30e3 + 3e3 * _sine()  # N
    assert float(dlc(force)) == pytest.approx((3e3 / math.sqrt(2)) / 30e3, rel=1e-12)


def test_dlc_at_its_boundaries_and_its_default_axis():
    """Each refusal exactly where it belongs (moving any of these boundaries by one, as a mutation
    test does, fails here). Hand values: [1, 3] has mean 2 and std 1 (DLC 0.5);
    [0.25, 0.75] has mean 0.5 and std 0.25 (DLC 0.5)."""
    assert dlc(np.array([1.0, 3.0])) == pytest.approx(0.5)  # two samples suffice
    with pytest.raises(ValueError, match="two force samples"):
        dlc(np.array([2.0]))
    assert dlc(np.array([0.25, 0.75])) == pytest.approx(0.5)  # a mean below 1 N is still a load
    for bad in ([-1.0, 1.0], [-3.0, -1.0]):  # mean zero, mean negative
        with pytest.raises(ValueError, match="must be positive"):
            dlc(np.array(bad))
    f = np.column_stack([[1.0, 3.0, 2.0], [10.0, 10.0, 13.0]])  # (n, k): time along axis 0 by default
    expected = [np.std(f[:, 0]) / 2.0, np.std(f[:, 1]) / 11.0]
    np.testing.assert_allclose(dlc(f), expected, rtol=1e-15)
    stats = force_statistics(f)
    np.testing.assert_allclose(stats["mean_force_N"], [2.0, 11.0], rtol=1e-15)
    np.testing.assert_allclose(stats["dlc"], expected, rtol=1e-15)


def test_nrmse_at_its_boundaries():
    r = np.array([1.0, 3.0])  # std 1
    assert nrmse(np.array([2.0, 4.0]), r) == pytest.approx(1.0)  # two samples suffice; offset 1 -> 1
    for x, ref in ((np.array([1.0, 2.0, 3.0]), r), (r, np.array([1.0, 2.0, 3.0]))):  # either longer
        with pytest.raises(ValueError, match="same shape"):
            nrmse(x, ref)
    with pytest.raises(ValueError, match="two samples"):
        nrmse(np.float64(1.0), np.float64(2.0))
    with pytest.raises(ValueError, match="two samples"):
        nrmse(np.array([1.0]), np.array([2.0]))
