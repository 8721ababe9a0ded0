"""Output correction (correction/): eq. 4, the filter design, its two applications, actuator files.

Expected values come from outside the code under test: the actuator and the low-passes are
simulated with scipy (``scipy.signal.lsim`` on polynomials written out here from the paper's
eq. 5), frequency-domain references are FFTs with the continuous magnitude computed here, and
eq. 4 is checked against the paper's printed formulas and, fed with the parameters
``rigsim.hydraulics.eq4_parameters`` derives from an ``ActuatorParams``, against its known properties.
"""

from __future__ import annotations

import functools
import math

import control
import numpy as np
import pytest
from scipy import signal

from rigsim.correction.io.actuator_file import ActuatorFileError, parse_actuator, read_actuator_file
from rigsim.correction.output.apply import StreamingCorrector, band_limit, correct, correct_causal, correct_zero_phase
from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.correction.output.filters import actuator_coefficients, design_correction
from rigsim.correction.output.lowpass import paper_lowpass, regularized_lowpass

STATIC_N = 30.0e3  # a truck wheel's static load, N


# ---------------------------------------------------------------- helpers (independent of correction/)


def random_ta(rng):
    """A random stable, minimum-phase T_a shaped like eq. 4 (DC gain 1), arbitrary common scale.

    A zero near 1 rad/s almost cancelled by a slow pole (the PI controller), a real pole at
    8-20 Hz (the position loop) and a complex pair at 40-100 Hz (the oil column).
    """
    z0 = rng.uniform(0.5, 2.0)
    wn, ze = 2 * np.pi * rng.uniform(40, 100), rng.uniform(0.15, 0.5)
    pair = -ze * wn + 1j * wn * math.sqrt(1 - ze ** 2)
    den = np.real(np.poly([-z0 * rng.uniform(0.85, 0.99), -2 * np.pi * rng.uniform(8, 20), pair, np.conj(pair)]))
    num = np.array([1.0, z0]) * den[-1] / z0
    scale = 10.0 ** rng.uniform(-3, 3)
    return num * scale, den * scale


def paper_tf_poly(f1=16.0, f2=24.0, z1=1.0, z2=1.0):
    """Eq. 5 written out: w1^2 w2^2 / ((s^2 + 2 z1 w1 s + w1^2)(s^2 + 2 z2 w2 s + w2^2))."""
    w1, w2 = 2 * np.pi * f1, 2 * np.pi * f2
    return np.array([w1 ** 2 * w2 ** 2]), np.polymul([1, 2 * z1 * w1, w1 ** 2], [1, 2 * z2 * w2, w2 ** 2])


def butter_tf_poly(corner_hz=30.0, order=6):
    return signal.butter(order, 2 * np.pi * corner_hz, analog=True)


def road_force(rng, fs, duration_s, *, hold_s=0.0, dlc=0.15, band=(0.5, 20.0)):
    """Static load plus band-limited random dynamic load, faded in and out over 2 s (N)."""
    n = int(round(fs * duration_s))
    t = np.arange(n) / fs
    dyn = signal.sosfilt(signal.butter(4, band, "bandpass", fs=fs, output="sos"), rng.standard_normal(n))
    t_dyn = t - hold_s
    length = duration_s - 2 * hold_s
    fade = np.clip(t_dyn / 2, 0, 1) * np.clip((length - t_dyn) / 2, 0, 1)
    dyn *= fade
    dyn *= dlc * STATIC_N / dyn.std()
    return t, STATIC_N + dyn


def lsim_from_static(tf, x, t):
    """Continuous response (scipy) of a unit-DC-gain system that sat at x[0] forever before t = 0."""
    _, y, _ = signal.lsim(tf, x - x[0], t)
    return y + x[0]


def rel_rms(a, b, mask):
    d = b[mask] - b[mask].mean()
    return float(np.sqrt(np.mean((a[mask] - b[mask]) ** 2)) / np.sqrt(np.mean(d ** 2)))


EQ4_VALUES = dict(ksv=1.0, kq_m3_s=0.0109, kc_m3_s_Pa=1.26e-11, kp_per_m=50.0, kdp_per_Pa=2.0e-8,
                  piston_area_m2=7.43e-3, fluid_volume_m3=2.13e-3, bulk_modulus_Pa=1.0e9, mass_kg=500.0,
                  damping_N_s_m=5.0e3, tire_N_per_m=1.0e6)


# ---------------------------------------------------------------- eq. 4


def test_eq4_coefficients_follow_the_printed_formulas():
    v = EQ4_VALUES
    num, den = eq4_coefficients_from(**v)
    # The paper's formulas, typed in from the text (eq. 4 and its coefficient list):
    ke = v["kp_per_m"] / v["piston_area_m2"]
    a0 = v["ksv"] * v["kq_m3_s"] * ke
    kc = v["kc_m3_s_Pa"] + v["kdp_per_Pa"] * v["ksv"] * v["kq_m3_s"]
    ap2 = v["piston_area_m2"] ** 2
    vb = v["fluid_volume_m3"] / (4 * v["bulk_modulus_Pa"] * ap2)
    expected_den = [vb * v["mass_kg"],
                    kc * v["mass_kg"] / ap2 + vb * v["damping_N_s_m"],
                    kc * v["damping_N_s_m"] / ap2 + vb * v["tire_N_per_m"] + 1,
                    a0 + kc * v["tire_N_per_m"] / ap2,
                    a0]
    np.testing.assert_allclose(num, [a0, a0], rtol=1e-14)  # b1 = b0 = a0
    np.testing.assert_allclose(den, expected_den, rtol=1e-14)


@pytest.mark.parametrize("kt, load", [(1.2e6, 0.0), (1.8e6, 34.5e3)])
def test_eq4_properties_with_the_hydraulics_parameters(kt, load):
    """eq. 4 fed by rigsim.hydraulics.eq4_parameters: T_a(0) = 1, b1 = Ksv Kq Kp / Ap, a4 = Vf mp / (4 beta Ap^2)."""
    from rigsim.hydraulics import ActuatorParams, eq4_parameters

    v = eq4_parameters(ActuatorParams(), kt, load)
    num, den = eq4_coefficients_from(**v)
    ap = v["piston_area_m2"]
    assert num[0] == pytest.approx(v["ksv"] * v["kq_m3_s"] * v["kp_per_m"] / ap, rel=1e-14)
    assert den[0] == pytest.approx(v["fluid_volume_m3"] * v["mass_kg"] / (4 * v["bulk_modulus_Pa"] * ap ** 2),
                                   rel=1e-14)
    assert np.polyval(num, 0.0) / np.polyval(den, 0.0) == pytest.approx(1.0, rel=1e-14)


def test_eq4_refuses_a_bad_parameter_by_name():
    with pytest.raises(ValueError, match="mass_kg must be > 0"):
        eq4_coefficients_from(**{**EQ4_VALUES, "mass_kg": 0.0})
    with pytest.raises(ValueError, match="tire_N_per_m must be finite"):
        eq4_coefficients_from(**{**EQ4_VALUES, "tire_N_per_m": math.nan})


# ---------------------------------------------------------------- recovery (the paper's eq. 3)


@functools.lru_cache(maxsize=None)
def _property_case(seed, fs):
    """Seeded draw of T_a and a 12 s road force, and the rig force (scipy lsim); shared by both low-passes."""
    rng = np.random.default_rng(seed)
    num, den = random_ta(rng)
    t, road = road_force(rng, fs, 12.0)
    return num, den, t, road, lsim_from_static((num, den), road, t)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("lowpass", ["paper", "regularized"])
def test_correction_recovers_the_road_force_through_the_lowpass(seed, lowpass):
    """Property: rig force = T_a applied to the road force (scipy lsim); the causal correction
    gives the road force through T_F (scipy lsim of eq. 5 / the analog Butterworth) to 1e-3 of its
    dynamic RMS, after the start-up transient. fs = 2 kHz: bilinear warping stays ~3e-4."""
    fs = 2000.0
    num, den, t, road, rig = _property_case(seed, fs)
    ref = lsim_from_static(paper_tf_poly() if lowpass == "paper" else butter_tf_poly(), road, t)
    filt = design_correction((num, den), fs, lowpass)
    mask = filt.transient_mask(t.size, "causal")
    assert mask.sum() > 0.3 * t.size  # enough settled samples to judge
    assert rel_rms(correct(rig, filt, "causal"), ref, mask) < 1e-3
    # the project's band limit of the road force is that same reference
    assert rel_rms(band_limit(road, fs, lowpass, "causal"), ref, mask) < 1e-3


@pytest.mark.parametrize("seed", range(3))
def test_zero_phase_correction_recovers_the_road_force_through_the_lowpass_magnitude(seed):
    """Zero-phase: the rig force corrected offline equals the road force through |T_F| (FFT
    with the continuous magnitude of eq. 5 computed here), with no delay, to 1e-3."""
    rng = np.random.default_rng(100 + seed)
    fs = 2000.0
    num, den = random_ta(rng)
    t, road = road_force(rng, fs, 16.0)
    rig = lsim_from_static((num, den), road, t)
    s = 2j * np.pi * np.fft.rfftfreq(t.size, 1 / fs)
    b, a = paper_tf_poly()
    ref = np.fft.irfft(np.fft.rfft(road - STATIC_N) * np.abs(np.polyval(b, s) / np.polyval(a, s)), t.size) + STATIC_N
    filt = design_correction((num, den), fs, "paper")
    mask = filt.transient_mask(t.size, "zerophase")
    assert rel_rms(correct(rig, filt, "zerophase"), ref, mask) < 1e-3
    assert rel_rms(band_limit(road, fs, "paper", "zerophase"), ref, mask) < 1e-3


def test_eq4_rig_corrected_with_eq4_and_the_papers_filter_gives_the_road_force_through_it():
    """The issue's second check: pan displacement = eq. 4 applied to the drive (scipy); the same
    holds for any signal through it, here a wheel force, to 1e-3."""
    rng = np.random.default_rng(7)
    fs = 2000.0
    num, den = eq4_coefficients_from(**EQ4_VALUES)
    t, road = road_force(rng, fs, 16.0, dlc=0.2)
    rig = lsim_from_static((num, den), road, t)
    ref = lsim_from_static(paper_tf_poly(), road, t)
    filt = design_correction((num, den), fs, "paper")
    assert rel_rms(correct(rig, filt), ref, filt.transient_mask(t.size)) < 1e-3


# ---------------------------------------------------------------- static load, streaming, transients


@pytest.fixture(scope="module")
def run_at_rest():
    """A rig run that starts and ends at rest: 8 s static holds around 24 s of driving, 1 kHz."""
    rng = np.random.default_rng(3)
    num, den = random_ta(rng)
    t, road = road_force(rng, 1000.0, 40.0, hold_s=8.0)
    return num, den, road, lsim_from_static((num, den), road, t)


@pytest.mark.parametrize("mode", ["causal", "zerophase"])
@pytest.mark.parametrize("lowpass", ["paper", "regularized"])
def test_mean_force_is_preserved(run_at_rest, mode, lowpass):
    """T_a(0) = 1 and T_F(0) = 1: a constant load passes exactly, and a run that starts and ends
    at rest (as rig runs do) keeps its mean to 1e-6 relative."""
    num, den, road, rig = run_at_rest
    filt = design_correction((num, den), 1000.0, lowpass)
    const = np.full(5000, STATIC_N)
    np.testing.assert_allclose(correct(const, filt, mode), const, rtol=1e-9)
    out = correct(rig, filt, mode)
    assert abs(out.mean() - road.mean()) / road.mean() < 1e-6


def test_streaming_in_chunks_equals_one_shot():
    rng = np.random.default_rng(11)
    fs = 1000.0
    filt = design_correction(random_ta(rng), fs, "paper")
    x = STATIC_N + 3e3 * rng.standard_normal((20000, 3))
    one_shot = correct_causal(x, filt)
    sc = StreamingCorrector(filt)
    cuts = np.sort(rng.choice(np.arange(1, x.shape[0]), size=40, replace=False))
    pieces = [sc.process(c) for c in np.split(x, cuts)]
    np.testing.assert_allclose(np.concatenate(pieces), one_shot, rtol=0, atol=1e-12 * STATIC_N)
    assert sc.samples_done == x.shape[0]


def test_settling_time_bounds_the_start_up_error():
    """Cut a long record: the correction of the cut record differs from that of the whole (which
    saw the true history) by at most the tolerance times the history's deviation after the
    settling time; and by more before it (the transient is real, not a formality)."""
    rng = np.random.default_rng(5)
    fs = 1000.0
    num, den = random_ta(rng)
    filt = design_correction((num, den), fs, "paper")
    t, road = road_force(rng, fs, 30.0)
    rig = lsim_from_static((num, den), road, t)
    full = correct(rig, filt)
    cut = int(12 * fs)
    part = correct(rig[cut:], filt)
    diff = np.abs(part - full[cut:])
    deviation = np.max(np.abs(rig[:cut] - rig[cut]))
    head = filt.transient_samples("causal")[0]
    assert 0.5 < filt.settling_time_s < 30
    assert np.max(diff[head:]) <= filt.settling_tolerance * deviation
    assert np.max(diff[:head]) > filt.settling_tolerance * deviation * 0.01


# ---------------------------------------------------------------- frequency responses


def test_zero_phase_response_is_the_filters_magnitude_with_the_inverse_phase():
    rng = np.random.default_rng(2)
    fs = 1000.0
    num, den = random_ta(rng)
    filt = design_correction((num, den), fs, "paper")
    f = np.linspace(0.1, 0.49 * fs, 400)
    h_zp = filt.zero_phase_response(f)
    np.testing.assert_allclose(np.abs(h_zp), np.abs(filt.discrete_response(f)), rtol=1e-12)
    # phase of the discretized T_a^-1: bilinear of den/num, computed here with scipy
    wp = 2 * np.pi * filt.prewarp_hz  # prewarped bilinear: s = wp / tan(wp / (2 fs)) (z - 1) / (z + 1)
    bz, az = signal.bilinear(den, num, fs=wp / (2 * math.tan(wp / (2 * fs))))
    _, h_inv = signal.freqz(bz, az, worN=f, fs=fs)
    np.testing.assert_allclose(np.exp(1j * np.angle(h_zp)), np.exp(1j * np.angle(h_inv)), atol=1e-9)
    # and, in the band, the continuous T_a^-1's phase
    band = f < 24.0
    s = 2j * np.pi * f[band]
    np.testing.assert_allclose(np.angle(h_zp[band]), np.angle(np.polyval(den, s) / np.polyval(num, s)), atol=2e-3)
    # not sosfiltfilt's |H|^2 with zero phase
    assert np.max(np.abs(np.abs(h_zp) - np.abs(filt.discrete_response(f)) ** 2)) > 0.05


def test_zero_phase_correction_applies_that_response_to_a_sine():
    fs, n = 1000.0, 40000
    filt = design_correction(eq4_coefficients_from(**EQ4_VALUES), fs, "paper")
    t = np.arange(n) / fs
    for f0 in (2.0, 8.0, 15.0):
        y = correct_zero_phase(STATIC_N + 1e3 * np.sin(2 * np.pi * f0 * t), filt)
        h = filt.zero_phase_response(f0)[0]
        expected = STATIC_N + 1e3 * np.abs(h) * np.sin(2 * np.pi * f0 * t + np.angle(h))
        mask = filt.transient_mask(n, "zerophase")
        np.testing.assert_allclose(y[mask], expected[mask], rtol=0, atol=1e-3 * 1e3)


def test_regularized_inverse_keeps_the_truck_band_and_the_papers_filter_does_not():
    """|correction x T_a| is the band limit: the regularized one within 0.5 % of 1 up to 20 Hz;
    the paper's two critically damped sections are ~3 dB down near 8 Hz."""
    num, den = eq4_coefficients_from(**EQ4_VALUES)
    f = np.linspace(0.05, 20, 400)
    ta = np.polyval(num, 2j * np.pi * f) / np.polyval(den, 2j * np.pi * f)
    reg = design_correction((num, den), 1000.0, "regularized")
    assert np.max(np.abs(np.abs(reg.zero_phase_response(f) * ta) - 1)) < 0.005
    pap = design_correction((num, den), 1000.0, "paper")
    g8 = np.abs(pap.zero_phase_response(8.0) * np.polyval(num, 16j * np.pi) / np.polyval(den, 16j * np.pi))[0]
    assert 0.69 < g8 < 0.74  # -3 dB = 0.708; eq. 5: 1/(1+(8/16)^2) / (1+(8/24)^2) = 0.72
    assert reg.noise_gain() < 1.0 and pap.noise_gain() < 1.0


def test_transfer_function_input_equals_coefficients():
    num, den = eq4_coefficients_from(**EQ4_VALUES)
    a = design_correction((num, den), 1000.0, "paper")
    b = design_correction(control.tf(num, den), 1000.0, "paper")
    np.testing.assert_allclose(a.sos, b.sos, rtol=1e-12)
    prod = a.tf()
    assert len(prod.den[0][0]) >= len(prod.num[0][0])  # one proper rational function
    assert abs(complex(prod(0)) - 1) < 1e-9


# ---------------------------------------------------------------- refusals


def test_refuses_a_sampling_rate_too_low_and_names_one_that_works():
    ta = eq4_coefficients_from(**EQ4_VALUES)
    with pytest.raises(ValueError, match=r"sampling rate 40 Hz is too low.*Nyquist") as e1:
        design_correction(ta, 40.0, "paper")
    with pytest.raises(ValueError, match=r"sampling rate 200 Hz is too low.*resample the forces at >= ") as e2:
        design_correction(ta, 200.0, "paper")
    for exc in (e1, e2):
        need = float(str(exc.value).split(">= ")[1].split(" Hz")[0])
        design_correction(ta, need, "paper")  # the suggested rate is accepted


def test_refuses_unstable_and_non_minimum_phase_actuators():
    with pytest.raises(ValueError, match="T_a is unstable: it has a pole at 3"):
        design_correction(([3.0], np.poly([3.0, -100.0]) * (-1) / 100), 1000.0, "paper")
    num = np.array([-1.0, 2.0])  # zero at +2 rad/s
    den = np.real(np.poly([-2.0, -50.0, -300.0, -400.0]))
    num = num * den[-1] / num[-1]
    with pytest.raises(ValueError, match=r"non-minimum-phase: its zero at 2 rad/s would be an unstable pole"):
        design_correction((num, den), 1000.0, "paper")


def test_refuses_a_missing_or_insufficient_lowpass():
    ta = eq4_coefficients_from(**EQ4_VALUES)
    with pytest.raises(ValueError, match="no low-pass given: T_a\\^-1 alone is improper"):
        design_correction(ta, 1000.0, None)
    with pytest.raises(ValueError, match="relative degree 2\\) is too weak .* order >= 3"):
        design_correction(ta, 1000.0, regularized_lowpass(30.0, order=2))


def test_refuses_a_static_gain_other_than_one_unless_asked_to_normalize():
    num, den = eq4_coefficients_from(**EQ4_VALUES)
    with pytest.raises(ValueError, match=r"T_a\(0\) = 0.98"):
        design_correction((0.98 * num, den), 1000.0, "paper")
    filt = design_correction((0.98 * num, den), 1000.0, "paper", normalize_dc=True)
    np.testing.assert_allclose(filt.ta_num, num, rtol=1e-12)


def test_actuator_coefficients_cancel_a_common_s_and_refuse_garbage():
    num, den = actuator_coefficients(([0.0, 2.0, 0.0], [1.0, 3.0, 2.0, 0.0]))
    np.testing.assert_array_equal(num, [2.0])
    np.testing.assert_array_equal(den, [1.0, 3.0, 2.0])
    with pytest.raises(ValueError, match="finite"):
        actuator_coefficients(([1.0, math.nan], [1.0, 1.0]))
    with pytest.raises(ValueError, match="continuous"):
        actuator_coefficients(control.tf([1.0], [1.0, -0.5], 0.001))


def test_lowpass_parameters_are_checked():
    with pytest.raises(ValueError, match="f1_hz must be finite and > 0"):
        paper_lowpass(f1_hz=-1.0)
    lp = paper_lowpass()
    assert abs(lp.response(0.0) - 1) < 1e-12 and lp.relative_degree == 4
    with pytest.raises(ValueError, match="unknown low-pass 'butter'"):
        design_correction(eq4_coefficients_from(**EQ4_VALUES), 1000.0, "butter")


# ---------------------------------------------------------------- actuator files


def test_actuator_file_transfer_function_and_parameters(tmp_path):
    p = tmp_path / "tf.toml"
    p.write_text("[transfer_function]\nnum = [2.0, 2.0]\nden = [1.0, 3.0, 2.0]\n")
    num, den = read_actuator_file(p)
    np.testing.assert_array_equal(num, [2.0, 2.0])
    np.testing.assert_array_equal(den, [1.0, 3.0, 2.0])
    q = tmp_path / "par.toml"
    q.write_text("[parameters]\n" + "".join(f"{k} = {v!r}\n" for k, v in EQ4_VALUES.items()))
    num, den = read_actuator_file(q)
    n2, d2 = eq4_coefficients_from(**EQ4_VALUES)
    np.testing.assert_allclose(num, n2, rtol=1e-15)
    np.testing.assert_allclose(den, d2, rtol=1e-15)


@pytest.mark.parametrize("doc, message", [
    ({"transfer_function": {"num": [1.0], "dem": [1.0, 1.0]}}, "unknown key transfer_function.dem; did you mean 'den'"),
    ({"transfer_function": {"num": [1.0], "den": [1.0, 1.0]}, "parameters": {}}, "exactly one of the tables"),
    ({}, "exactly one of the tables"),
    ({"transfer_function": {"num": [1.0]}}, "transfer_function.den is missing"),
    ({"transfer_function": {"num": ["a"], "den": [1.0]}}, r"transfer_function.num\[0\] must be a number"),
    ({"parameters": {k: v for k, v in EQ4_VALUES.items() if k != "mass_kg"}}, "parameters.mass_kg is missing"),
    ({"parameters": {**EQ4_VALUES, "mass_kg": -1.0}}, "parameters.mass_kg must be > 0"),
    ({"parameters": {**EQ4_VALUES, "tyre_N_per_m": 1.0}}, "did you mean 'tire_N_per_m'"),
    ({"actuator": {}}, "unknown key actuator"),
])
def test_actuator_file_errors_name_the_key(doc, message):
    with pytest.raises(ActuatorFileError, match=message):
        parse_actuator(doc)
