"""rigsim.correction.identification.plausibility: a drive/LVDT pair wired wrongly is refused by
``fit_actuator`` naming its likely cause; a drive and its own LVDT pass.

Reference: eq. 4 (rigsim.correction.output.eq4) and second-order position loops, simulated by scipy
(first-order hold) from random drives, stand in for a rig's actuators: the pan's response to its
own drive is known, so each miswiring is made from it exactly (the LVDT given as the drive, the
LVDT inverted or in mm, another post's LVDT with an independent or a delayed drive). The limits'
sources are the constants' notes in the module; the numbers pinned here are those the notes quote.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy import signal

from rigsim.correction.identification.actuator_fit import (ActuatorFitError, default_nperseg, fit_actuator,
                                                           fit_frequency_response)
from rigsim.correction.identification.identify import h1_estimate
from rigsim.correction.identification.plausibility import (HELD_OUT_LIMIT, LEAD_LIMIT_DEG, PHASE_RESULTANT_MIN,
                                                           WiringError, check_signals, plausibility)
from rigsim.correction.output.eq4 import eq4_coefficients_from

FS = 1000.0
EQ4 = dict(ksv=1.0, kq_m3_s=0.0111, kc_m3_s_Pa=2.0e-12, kp_per_m=50.0, kdp_per_Pa=2.0e-8, piston_area_m2=7.43e-3,
           fluid_volume_m3=2.13e-3, bulk_modulus_Pa=1.0e9, mass_kg=500.0, damping_N_s_m=5.0e3,
           tire_N_per_m=1.0e6, ti_s=1.0)


def _drive(seconds, seed):
    """A random drive (0.05-60 Hz, 5 mm rms), m."""
    rng = np.random.default_rng(seed)
    u = signal.sosfilt(signal.butter(2, [0.05, 60.0], "bandpass", fs=FS, output="sos"),
                       rng.standard_normal(int(seconds * FS)))
    return u * (0.005 / u.std())


def _pan(u, tf=None, seed=1):
    """The pan's displacement under drive ``u`` through ``tf`` (default eq. 4), 0.1 % noise, m."""
    num, den = eq4_coefficients_from(**EQ4) if tf is None else tf
    bd, ad, _ = signal.cont2discrete((num, den), 1.0 / FS, method="foh")
    y = signal.lfilter(np.ravel(bd), ad, u)
    return y + 1e-3 * y.std() * np.random.default_rng(seed).standard_normal(y.size)


def _loop(f_hz, zeta=0.7):
    w = 2 * math.pi * f_hz
    return [w * w], [1.0, 2 * zeta * w, w * w]


def _plausibility_of(u, y):
    """The numbers of the fit of ``y`` against ``u``, made without the refusal."""
    f, h, coh = h1_estimate(u, y, FS, default_nperseg(u.size, FS))
    return plausibility(fit_frequency_response(f, h, coh))


def _refusal(u, y) -> WiringError:
    with pytest.raises(WiringError) as exc:
        fit_actuator(u, y, FS)
    msg = str(exc.value)
    assert "\n" not in msg and ". " not in msg, msg  # one sentence
    return exc.value


def test_a_drive_and_its_own_lvdt_pass_with_the_numbers_the_notes_quote():
    u = _drive(60.0, 1)
    p = plausibility(fit_actuator(u, _pan(u), FS))
    assert 0.9 < p.gain < 1.0 and -15.0 < p.phase_deg < -10.0 and p.phase_resultant > 0.98
    assert p.points >= 30 and p.held_out_error < 0.01
    for f_hz, zeta in ((5.0, 0.7), (10.0, 0.3), (60.0, 0.7)):  # slow, resonant, fast loops
        p = plausibility(fit_actuator(u, _pan(u, _loop(f_hz, zeta)), FS))
        assert p.phase_deg < 0 and p.phase_resultant > 0.85 and p.held_out_error < 0.2, (f_hz, p)


def test_an_lvdt_filter_and_skew_left_in_pass():
    # A lab's 150 Hz 4th-order LVDT anti-alias filter and 10 ms of skew, not declared: the fit is not
    # minimum phase (its usable held-out error is large) but the pair is an actuator's.
    u = _drive(60.0, 2)
    y = signal.sosfilt(signal.butter(4, 150.0, fs=FS, output="sos"), _pan(u))
    y = np.concatenate([np.zeros(10), y[:-10]])
    fit = fit_actuator(u, y, FS)
    assert fit.non_minimum_phase and fit.held_out_error > 1.0
    assert plausibility(fit).held_out_error < 0.1


def test_swapped_is_refused_by_its_lead():
    u = _drive(60.0, 3)
    err = _refusal(_pan(u), u)
    assert err.cause == "swapped" and re.search(r"leads the drive by 1\d\.\d deg in 0\.1-5 Hz", str(err)), err
    assert _plausibility_of(_pan(u), u).phase_deg > LEAD_LIMIT_DEG


def test_swapped_fast_actuator_leads_little_and_is_refused_by_its_held_out_error():
    u = _drive(60.0, 4)
    y = _pan(u, _loop(100.0))
    p = _plausibility_of(y, u)
    assert 0 < p.phase_deg < LEAD_LIMIT_DEG and p.held_out_error > HELD_OUT_LIMIT
    assert _refusal(y, u).cause == "swapped"


def test_the_same_samples_twice_are_refused_before_any_fit():
    u = _drive(20.0, 5)
    with pytest.raises(WiringError, match=r"same samples \(the same channel twice\)") as exc:
        check_signals(u, u.copy())
    assert exc.value.cause == "same channel"
    assert _refusal(u, u).cause == "same channel"


def test_an_inverted_lvdt_and_one_in_another_unit_are_refused():
    u = _drive(30.0, 6)
    y = _pan(u)
    err = _refusal(u, -y)
    assert err.cause == "inverted" and "antiphase" in str(err)
    err = _refusal(u, 1e3 * y)  # an LVDT in mm read as m
    assert err.cause == "scale" and "times the drive" in str(err)


def test_another_posts_lvdt_is_refused_as_the_wrong_corner():
    # independent tracks: the other post's LVDT does not follow this drive at all
    u, other = _drive(30.0, 7), _drive(30.0, 8)
    err = _refusal(u, _pan(other))
    assert err.cause == "wrong corner" and "what unrelated channels give" in str(err)
    # the same track on the other axle: that post's drive is this one 0.25 s later
    lag = 250
    road = _drive(60.0 + lag / FS, 9)
    front, rear = road[lag:], road[:-lag]
    for u, y in ((front, _pan(rear)), (rear, _pan(front))):
        assert _plausibility_of(u, y).phase_resultant < PHASE_RESULTANT_MIN
        err = _refusal(u, y)
        assert err.cause == "wrong corner" and "delay" in str(err)


def test_a_noisy_own_lvdt_keeps_the_record_advice():
    u = _drive(60.0, 10)
    y = _pan(u)
    y = y + 3.0 * y.std() * np.random.default_rng(11).standard_normal(y.size)
    with pytest.raises(ActuatorFitError) as exc:
        fit_actuator(u, y, FS)
    assert not isinstance(exc.value, WiringError) and "record at least" in str(exc.value)
