"""The correction filter's transient lengths stay exact where the impulse response is short and
bounded in memory where it is not.

A T_a with a slow zero (``(10 s + 1)``: T_a^-1 has a pole at -0.1 1/s, a 10 s time constant)
needs a 200 s horizon; at 100 kHz that is 20 million samples and a 2-point-per-sample FFT of
twice that (3.1 GB measured, uncapped). Each response is capped at :data:`MAX_RESPONSE_SAMPLES` samples,
the slowest pole's geometric tail standing in beyond them. Reference: the same filter's lengths computed
on the whole horizon (below the cap), against which the capped computation must agree.
"""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from rigsim.correction.output import correction_filter
from rigsim.correction.output.filters import design_correction

W8 = 2 * np.pi * 8.0
#: T_a = (10 s + 1) / ((9 s + 1) (s^2 / w^2 + 2 0.7 s / w + 1)): DC gain 1, a slow zero at -0.1 1/s.
SLOW_ZERO = ([10.0, 1.0], list(np.polymul([9.0, 1.0], [1 / W8**2, 2 * 0.7 / W8, 1.0])))


@pytest.mark.parametrize("lowpass", ["paper", "regularized"])
def test_a_capped_horizon_extrapolates_the_slow_tail(monkeypatch, lowpass):
    whole = design_correction(SLOW_ZERO, 2048.0, lowpass)  # 200 s x 2048 Hz: below the cap
    assert whole.settling_time_s > 40.0  # ln(1/tol)-ish time constants of the 10 s pole
    monkeypatch.setattr(correction_filter, "MAX_RESPONSE_SAMPLES", 2**15)  # a 16 s horizon
    capped = design_correction(SLOW_ZERO, 2048.0, lowpass)
    assert capped.settling_time_s == pytest.approx(whole.settling_time_s, rel=0.02)
    assert capped.zero_phase_margins_s[0] == pytest.approx(whole.zero_phase_margins_s[0], rel=0.02)
    assert capped.zero_phase_margins_s[1] == pytest.approx(whole.zero_phase_margins_s[1], rel=0.02)


def test_a_slow_pole_at_a_high_rate_is_designed_in_bounded_memory():
    tracemalloc.start()
    try:
        filt = design_correction(SLOW_ZERO, 100_000.0, "regularized")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1 << 30, peak
    assert filt.settling_time_s > 40.0
