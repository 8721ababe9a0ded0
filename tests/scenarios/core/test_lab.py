"""The lab's measurement chain (rigsim.scenarios.core.lab) against what each of its parts must do.

References: the second derivative of a sine (the pan's inertia), the Butterworth definition (-3 dB
at the corner, 0 dB at DC), a ramp's exact shift under a delay, the rms of seeded noise over a
long record (its sampling error ~1/sqrt(n)).
"""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from rigsim.scenarios.core.lab import LAB_BOUNDS, TYPICAL_LAB, LabChain, measure, pan_acceleration

FS = 1000.0


def _run(n: int = 20_000, force=None, pan=None):
    t = np.arange(n) / FS
    force = np.full((n, 4), 30_000.0) if force is None else force
    pan = np.zeros((n, 4)) if pan is None else pan
    return SimpleNamespace(rate_hz=FS, t_s=t, signals={"tire_force_N": force, "pan_m": pan})


def _sine(f_hz: float, amp: float, n: int = 20_000) -> np.ndarray:
    t = np.arange(n) / FS
    return np.repeat((amp * np.sin(2 * np.pi * f_hz * t))[:, None], 4, axis=1)


def test_the_ideal_chain_is_the_white_noise_alone_and_the_exact_lvdt():
    run = _run(pan=_sine(3.0, 0.01))
    m = measure(run, LabChain(), 100.0, 5)
    noise = 100.0 * np.random.default_rng((5, 8)).standard_normal((20_000, 4))
    assert np.array_equal(m.force_N, run.signals["tire_force_N"] + noise)
    assert np.array_equal(m.pan_m, run.signals["pan_m"])


def test_the_pan_inertia_above_the_cell_is_in_the_force():
    """a = -A w^2 sin(w t): the cell reads m a more; central differences are exact to (w dt)^2 / 12."""
    f, amp, m = 8.0, 0.005, 250.0
    run = _run(pan=_sine(f, amp))
    got = measure(run, LabChain(cell_mass_kg=m), 0.0, 0).force_N - 30_000.0
    w = 2 * np.pi * f
    expected = -m * w**2 * run.signals["pan_m"]
    np.testing.assert_allclose(got[1:-1], expected[1:-1], atol=m * w**2 * amp * (w / FS) ** 2 / 12 * 1.01)


def test_an_exact_compensation_cancels_the_inertia_and_a_wrong_one_leaves_the_difference():
    run = _run(pan=_sine(8.0, 0.005))
    exact = measure(run, LabChain(cell_mass_kg=250.0, compensation_kg=250.0), 0.0, 0).force_N
    np.testing.assert_allclose(exact, 30_000.0, atol=1e-9)
    off = measure(run, LabChain(cell_mass_kg=250.0, compensation_kg=260.0), 0.0, 0).force_N - 30_000.0
    acc = pan_acceleration(run.signals["pan_m"], FS)
    np.testing.assert_allclose(off, -10.0 * acc, atol=1e-9)


@pytest.mark.parametrize("corner_hz", [50.0, 200.0])
def test_the_anti_alias_filter_is_minus_3_dB_at_its_corner_and_passes_the_static_load(corner_hz):
    amp = 1000.0
    run = _run(force=30_000.0 + _sine(corner_hz, amp))
    got = measure(run, LabChain(force_filter_hz=corner_hz), 0.0, 0).force_N[10_000:, 0] - 30_000.0
    assert np.sqrt(2) * np.std(got) == pytest.approx(amp / np.sqrt(2), rel=2e-3)
    static = measure(_run(), LabChain(force_filter_hz=corner_hz, lvdt_filter_hz=corner_hz), 0.0, 0)
    np.testing.assert_allclose(static.force_N, 30_000.0, rtol=1e-12)  # at rest from the first sample


def test_a_delay_shifts_a_ramp_by_slope_times_delay():
    n = 2000
    ramp = np.repeat(np.linspace(0.0, 1.0, n)[:, None], 4, axis=1)
    slope = 1.0 / ((n - 1) / FS)
    m = measure(_run(n, force=1000.0 * ramp, pan=0.01 * ramp),
                LabChain(force_delay_s=0.0005, lvdt_delay_s=0.0023), 0.0, 0)
    np.testing.assert_allclose(m.force_N[10:] - 1000.0 * ramp[10:], -1000.0 * slope * 0.0005, atol=1e-9)
    np.testing.assert_allclose(m.pan_m[10:] - 0.01 * ramp[10:], -0.01 * slope * 0.0023, atol=1e-12)


def test_the_noises_have_their_rms_and_their_own_streams():
    n = 400_000
    chain = LabChain(lvdt_noise_m=20e-6, drift_noise_N=50.0, drift_corner_hz=1.0)
    m = measure(_run(n), chain, 0.0, 3)
    drift = m.force_N - 30_000.0
    assert np.std(drift[20_000:]) == pytest.approx(50.0, rel=0.08)  # ~400 correlation times of 0.16 s
    low = np.abs(np.fft.rfft(drift[:, 0]))
    f = np.fft.rfftfreq(n, 1 / FS)
    assert np.mean(low[(f > 0.05) & (f < 0.5)]) > 20 * np.mean(low[(f > 50) & (f < 100)])  # coloured, not white
    assert np.std(m.pan_m) == pytest.approx(20e-6, rel=0.01)
    again = measure(_run(n), chain, 0.0, 3)
    assert np.array_equal(again.force_N, m.force_N) and np.array_equal(again.pan_m, m.pan_m)
    white = measure(_run(n), chain, 100.0, 3).force_N - m.force_N
    np.testing.assert_allclose(white, 100.0 * np.random.default_rng((3, 8)).standard_normal((n, 4)), atol=1e-9)


def test_the_typical_lab_changes_every_channel():
    run = _run(pan=_sine(8.0, 0.005))
    m = measure(run, TYPICAL_LAB, 100.0, 0)
    assert not np.allclose(m.pan_m, run.signals["pan_m"])
    assert not TYPICAL_LAB.ideal and LabChain().ideal


@pytest.mark.parametrize("field", list(LAB_BOUNDS))
def test_each_field_is_bounded_and_named(field):
    lo, hi, _, _ = LAB_BOUNDS[field]
    with pytest.raises(ValueError, match=f"lab.{field}"):
        LabChain(**{field: hi + 1})
    with pytest.raises(ValueError, match=f"lab.{field} must be"):
        LabChain(**{field: True})
    if field != "filter_order":
        with pytest.raises(ValueError, match=f"lab.{field} must be a finite number"):
            LabChain(**{field: math.nan})
    assert dataclasses.replace(LabChain(), **{field: lo if field != "filter_order" else 2})


def test_a_filter_corner_above_nyquist_is_refused_before_any_work():
    with pytest.raises(ValueError, match="lab.force_filter_hz = 600 Hz must lie below half the record's rate"):
        measure(_run(), LabChain(force_filter_hz=600.0), 0.0, 0)


def test_a_scenarios_lab_table_is_read_and_checked():
    from rigsim.scenarios.core.config import ScenarioError, parse_scenario

    base = {"name": "x", "speed_kmh": 60, "duration_s": 10, "road": {"roughness": "medium"}}
    assert parse_scenario(base).lab == LabChain()
    sc = parse_scenario(base | {"lab": {"cell_mass_kg": 250, "compensation_kg": 257.5, "force_filter_hz": 200}})
    assert sc.lab == LabChain(cell_mass_kg=250.0, compensation_kg=257.5, force_filter_hz=200.0)
    with pytest.raises(ScenarioError, match="lab.force_filter_hz = 600 Hz must lie below half the record's rate"):
        parse_scenario(base | {"lab": {"force_filter_hz": 600}})
    with pytest.raises(ScenarioError, match="lab"):
        parse_scenario(base | {"lab": {"cell_mas_kg": 250}})


def test_aligned_channels_are_the_chain_without_its_filters_and_skew():
    """A lab that knows its filters and skew (``aligned``) gets back, within the filters' magnitude
    in the band, what the same chain without filters and skew measures: an 8 Hz force and pan."""
    from rigsim.scenarios.core.lab import aligned

    run = _run(force=30_000.0 + _sine(8.0, 3_000.0), pan=_sine(8.0, 0.005))
    lab = dataclasses.replace(TYPICAL_LAB, accelerometer_noise_m_s2=0.0, lvdt_noise_m=0.0, drift_noise_N=0.0)
    plain = dataclasses.replace(lab, force_filter_hz=None, lvdt_filter_hz=None, force_delay_s=0.0)
    want, raw = measure(run, plain, 0.0, 0), measure(run, lab, 0.0, 0)
    got = aligned(raw, FS, lab)
    mid = slice(2000, -2000)
    for w, r, g, scale in ((want.force_N, raw.force_N, got.force_N, 3_000.0), (want.pan_m, raw.pan_m, got.pan_m, 0.005)):
        assert np.max(np.abs(r - w)[mid]) > 0.05 * scale  # 2-3 ms at 8 Hz: 10-15 % of the amplitude
        assert np.max(np.abs(g - w)[mid]) < 0.002 * scale
