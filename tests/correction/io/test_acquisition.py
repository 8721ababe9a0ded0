"""A channel's anti-alias filter and delay: described, applied, undone."""

import math

import numpy as np
import pytest
from scipy import signal

from rigsim.correction.io.acquisition import ChannelFilter, parse_channel_filter, undo_timing

FS = 1000.0


def _band_noise(n=20000, k=2, corner_hz=30.0, seed=0):
    rng = np.random.default_rng(seed)
    sos = signal.butter(4, corner_hz, fs=FS, output="sos")
    return 4e4 + 3e3 * signal.sosfilt(sos, rng.standard_normal((n, k)), axis=0)


def test_analog_butterworth_group_delay_is_the_prototypes():
    # A normalized n-th order Butterworth's group delay at DC is 1 / sin(pi / (2 n)) s: 2.6131 for n = 4
    # (Williams & Taylor, Electronic Filter Design Handbook, the Butterworth group delay curves at w = 0).
    tau0 = 1.0 / math.sin(math.pi / 8) / (2 * math.pi * 150.0)
    h = ChannelFilter(150.0, 4).response(np.array([0.0, 0.01]), FS)
    delay = -np.diff(np.unwrap(np.angle(h)))[0] / (2 * math.pi * 0.01)
    assert delay == pytest.approx(tau0, rel=1e-4)  # 2.77 ms
    assert abs(ChannelFilter(150.0, 4).response(np.array([150.0]), FS)[0]) == pytest.approx(2 ** -0.5, rel=1e-9)


def test_delay_is_a_pure_phase():
    h = ChannelFilter(None, delay_s=2e-4).response(np.array([10.0, 100.0]), FS)
    np.testing.assert_allclose(np.abs(h), 1.0)
    np.testing.assert_allclose(np.angle(h), -2 * math.pi * np.array([10.0, 100.0]) * 2e-4)


@pytest.mark.parametrize("channel", [ChannelFilter(200.0, 4, domain="digital", delay_s=2e-4),
                                     ChannelFilter(150.0, 4),
                                     ChannelFilter(150.0, 4, "bessel", "digital")])
def test_undo_takes_the_filter_and_delay_back_out(channel):
    x = _band_noise()
    y = channel.apply(x, FS)
    mid = slice(1000, -1000)
    before = np.std((y - x)[mid]) / np.std(x[mid])
    after = np.std((undo_timing(y, FS, channel) - x)[mid]) / np.std(x[mid])
    assert before > 0.1  # a 30 Hz band signal is visibly shifted by 2-3 ms
    # What stays is the filter's magnitude in the band (and the delay's interpolation): a fraction of a percent.
    assert after < 0.01


def test_undo_keeps_the_static_level_and_the_ends():
    x = _band_noise(n=3000) + np.linspace(0.0, 5e3, 3000)[:, None]  # a drift: the ends differ by 5 kN
    ch = ChannelFilter(200.0, 4, domain="digital", delay_s=2e-4)
    z = undo_timing(ch.apply(x, FS), FS, ch)
    np.testing.assert_allclose(z.mean(axis=0), x.mean(axis=0), rtol=1e-4)
    assert np.max(np.abs(z - x)[50:-50]) < 0.02 * np.std(x - x.mean(axis=0))


def test_digital_apply_is_sosfilt_from_rest():
    x = _band_noise(n=500, k=1)[:, 0]
    sos = signal.butter(4, 200.0, fs=FS, output="sos")
    expected = signal.sosfilt(sos, x, zi=signal.sosfilt_zi(sos) * x[0])[0]
    np.testing.assert_array_equal(ChannelFilter(200.0, 4, domain="digital").apply(x, FS), expected)


def test_nothing_to_undo_returns_the_input():
    x = _band_noise(n=100)
    assert undo_timing(x, FS, ChannelFilter()) is not None
    np.testing.assert_array_equal(undo_timing(x, FS, ChannelFilter()), x)


@pytest.mark.parametrize("kw, word", [({"corner_hz": -1.0}, "corner"), ({"order": 9}, "order"),
                                      ({"kind": "cheby"}, "kind"), ({"domain": "optical"}, "domain"),
                                      ({"delay_s": 0.5}, "delay")])
def test_bad_fields_are_refused(kw, word):
    with pytest.raises(ValueError, match=word):
        ChannelFilter(**kw)


def test_corner_above_nyquist_is_refused():
    with pytest.raises(ValueError, match="half the record's rate"):
        undo_timing(np.zeros((10, 1)), 300.0, ChannelFilter(200.0))


def test_parse():
    assert parse_channel_filter("200") == ChannelFilter(200.0, 4)
    assert parse_channel_filter("150:6:bessel:digital", 2e-4) == ChannelFilter(150.0, 6, "bessel", "digital", 2e-4)
    assert parse_channel_filter("none", 1e-4) == ChannelFilter(None, delay_s=1e-4)
    for bad in ("abc", "200:x", "200:4:elliptic", "none:4", "200:12"):
        with pytest.raises(ValueError, match="--force-filter"):
            parse_channel_filter(bad, option="--force-filter")
