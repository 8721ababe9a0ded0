"""How the rig test is integrated: RK4 at 1e-3 s with the drive held at mid-step.

The choice itself is measured by ``benchmarks/integrator_study.py`` (docs/integrator_study.md);
these tests pin what the code does with it: the values each step holds (exact where the drive
knows its signal between samples), which integrator and step each test gets, and that a step too
coarse for the rig's fastest mode is refused before a run instead of diverging in it.
"""

from __future__ import annotations

import dataclasses
from types import MappingProxyType

import mujoco
import numpy as np
import pytest
from scipy import signal

from rigsim.scenarios.core.config import ScenarioError, parse_scenario
from rigsim.scenarios.core.drive import Drive, identification_drive, step_drive
from rigsim.scenarios.core.rig import RIG_TIMESTEP_S, Rig, rk4_amplification
from rigsim.scenarios.core.watch import SimulationError

SHORT = {"name": "step-short", "speed_kmh": 72.0, "duration_s": 1.0, "lead_in_s": 1.0, "seed": 3,
         "road": {"roughness": "C"}}


def test_hermite_midpoint_is_exact_for_a_cubic():
    """A plain Drive holds the cubic Hermite interpolant of (z, v) at mid-step: exact for a cubic
    polynomial (its error term is the 4th derivative), and not the sample itself."""
    dt = 1e-3
    t = np.arange(50) * dt
    coef = np.array([[0.3, -2.0, 0.5, 1e-3], [-1.0, 0.2, 0.0, -2e-3], [2.0, 1.0, -0.4, 0.0], [0.0, 0.0, 1.0, 5e-4]])

    def z_of(tt):
        return np.stack([np.polyval(c, tt) for c in coef], axis=1)

    def v_of(tt):
        return np.stack([np.polyval(np.polyder(c), tt) for c in coef], axis=1)

    d = Drive(t, z_of(t), v_of(t))
    held = d.held(3, 40)
    np.testing.assert_allclose(held, z_of(t[3:40] + dt / 2), rtol=0, atol=1e-15)
    assert np.max(np.abs(held - d.z_m[3:40])) > 1e-4
    # The last step has no next sample: z + v dt / 2 (first order), still finite and shaped.
    assert d.held(45, 50).shape == (5, 4) and np.all(np.isfinite(d.held(45, 50)))


def test_identification_drive_holds_its_own_signal_at_mid_step():
    """The band-limited random drive knows its signal between samples: the held values are the
    same periodic band-limited signal half a step later. Reference: FFT resampling to twice the
    rate (scipy.signal.resample, exact for a periodic band-limited signal), odd samples. The fade
    is one step long, so only sample 0 of z is faded; its raw value follows from the empty bins
    above the band (there the faded signal's spectrum is -z_raw[0] exactly)."""
    dt = 1e-3
    d = identification_drive(4.0, dt, seed=7, fade_s=dt)
    n = d.n_steps
    spec = np.fft.rfft(d.z_m, axis=0)
    f = np.fft.rfftfreq(n, dt)
    out_of_band = (f > 100.0) & (f < 400.0)
    raw0 = -spec[out_of_band].real.mean(axis=0)
    assert np.max(np.abs(spec[out_of_band] + raw0)) < 1e-12  # the claim above holds
    raw = d.z_m.copy()
    raw[0] = raw0
    mid = signal.resample(raw, 2 * n, axis=0)[1::2]
    np.testing.assert_allclose(d.held(1, n), mid[1:], rtol=0, atol=1e-12 * np.abs(raw).max())
    # Half a step is not nothing: the held values differ from the samples by ~2 % of the peak.
    assert np.max(np.abs(d.held(1, n) - d.z_m[1:])) > 0.01 * np.abs(raw).max()


def test_step_drive_holds_the_step_at_its_instant():
    d = step_drive(0.1, 1e-3, 2e-3, 0.05)
    held = d.held(0, d.n_steps)
    assert np.all(held[:50] == 0.0) and np.all(held[50:] == 2e-3)


def test_road_drive_holds_the_road_at_mid_step():
    """A road drive's held values are the road itself at t_k + dt / 2: the same road sampled at
    twice the rate, odd samples (fade-in included)."""
    sc = parse_scenario(SHORT)
    rig = Rig(sc, hydraulic=False)
    src = rig.road_source()
    twice = dataclasses.replace(src, fs_hz=2 * src.fs_hz, n_steps=2 * src.n_steps)
    k0, k1 = 0, src.n_steps  # the whole lead-in and record
    np.testing.assert_array_equal(src.held(k0, k1), twice.chunk(2 * k0 + 1, 2 * k1 + 1)[0][::2])
    np.testing.assert_array_equal(src.drive().held(5, 900), src.held(5, 900))


def test_each_test_gets_its_integrator_and_step():
    sc = parse_scenario(SHORT)
    road, rig = Rig(sc, hydraulic=False), Rig(sc)
    for opt in (road.model.opt, rig.model.opt):  # both tests: RK4 at 1e-3 s
        assert (opt.integrator, opt.timestep) == (mujoco.mjtIntegrator.mjINT_RK4, RIG_TIMESTEP_S)
    assert rig.linear_dt_s == road.linear_dt_s == 1e-4  # the XML's Euler step: the linear models'
    fast = Rig(dataclasses.replace(sc, output_rate_hz=4000.0)).model.opt  # an output faster than 1 kHz
    assert fast.timestep == pytest.approx(2.5e-4)
    fine = Rig(parse_scenario({**SHORT, "vehicle": {"timestep_s": 2e-4}}))
    assert fine.dt_s == 2e-4 and fine.linear_dt_s == 2e-4 and fine.linearize().dt_s == 2e-4


def test_rk4_growth_factor_matches_its_published_stability_boundary():
    """R(z) of classical RK4: about e^z for small z; the stability interval on the negative real
    axis is [-2.785, 0] and on the imaginary axis |y| <= 2 sqrt(2) (Hairer & Wanner, Solving
    Ordinary Differential Equations II, section IV.2, Fig. 2.1)."""
    z = np.array([1e-2, -3e-2 + 2e-2j])
    np.testing.assert_allclose(rk4_amplification(z), np.exp(z), rtol=1e-9)
    assert abs(rk4_amplification(-2.78)) < 1 < abs(rk4_amplification(-2.79))
    assert abs(rk4_amplification(2.82j)) < 1 < abs(rk4_amplification(2.84j))


def test_a_step_too_coarse_for_rk4_is_refused_before_the_run():
    """A 600 Hz servovalve puts a mode at ~3.9e3 rad/s, outside RK4's region at 1e-3 s: refused
    by name, the fix (a finer vehicle.timestep_s) accepted; unchecked, the run does diverge."""
    fast_valve = MappingProxyType({"spool_hz": 600.0})
    sc = dataclasses.replace(parse_scenario(SHORT), actuator=fast_valve)
    with pytest.raises(ScenarioError, match=r"vehicle.timestep_s = 0.001 s is too coarse for RK4.*lower vehicle.timestep_s"):
        Rig(sc)
    Rig(dataclasses.replace(sc, vehicle=dataclasses.replace(sc.vehicle, timestep_s=2e-4)))
    unchecked = Rig(sc, check_stability=False)
    with pytest.raises(SimulationError):
        unchecked.run(unchecked.road_source(), rate_hz=sc.output_rate_hz)


def test_the_rig_test_steps_on_the_held_values_and_records_the_samples():
    """Samples at rest, held values 1 mm up: the pans go to 1 mm (the integral action removes the
    offset within ~1 s), while the record's x_ref is the samples."""
    rig = Rig(parse_scenario(SHORT))
    n = int(round(2.0 / rig.dt_s)) + 1
    z = np.zeros((n, 4))
    d = Drive(np.arange(n) * rig.dt_s, z, z, held_m=np.full((n, 4), 1e-3))
    rec = rig.run(d, rate_hz=1000.0)
    assert np.all(rec.x_ref_m == 0.0)
    np.testing.assert_allclose(rec.pan_m[-1], 1e-3, rtol=0.02)
