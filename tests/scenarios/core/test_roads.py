"""Tests of the road and profile modules (scenarios/core/roads.py, profiles.py) and of sampling a
profile as drives (scenarios/core/drive.py); each states where its expected value comes from."""

import numpy as np
import pytest
from scipy import signal

from rigsim.scenarios.core.drive import Drive
from rigsim.scenarios.core.road_drive import sample_wheels
from rigsim.scenarios.core.profiles import Profile, ProfileError, highpass, read_profile_csv, write_profile_csv
from rigsim.scenarios.core.roads import ISO_CLASSES, ROUGHNESS_WORDS, RoadSpec, generate_profile, iso8608_psd, welch_psd_spatial


def _octave_bands(lo=0.05, hi=5.0):
    edges = [lo]
    while edges[-1] < hi:
        edges.append(min(2 * edges[-1], hi))
    return list(zip(edges[:-1], edges[1:]))


@pytest.mark.parametrize("waviness", [2.0, 2.5])
def test_psd_matches_iso8608_in_octave_bands(waviness):
    # Reference: ISO 8608 Gd(n) = Gd(n0) (n/n0)^-w, class C Gd(n0) = 256e-6 m^3;
    # band average of the Welch estimate vs band average of the formula, same bins.
    spec = RoadSpec.from_class("C", waviness=waviness)
    assert spec.gd_n0_m3 == 256e-6
    p = generate_profile(spec, 2000.0, 0.05, np.random.default_rng(7))
    for z in (p.left_m, p.right_m):
        n, gd = welch_psd_spatial(z, 0.05, nperseg=4096)
        target = iso8608_psd(n[1:], 256e-6, waviness)
        for lo, hi in _octave_bands():
            sel = (n[1:] >= lo) & (n[1:] < hi)
            ratio = gd[1:][sel].mean() / target[sel].mean()
            assert 0.8 < ratio < 1.2, (lo, hi, ratio)


def test_iso_formula_and_classes():
    # Reference: ISO 8608 class geometric means grow by 4x per class from A = 16e-6 m^3;
    # Gd(n0) at n0 = 0.1 cycle/m and Gd(2 n0) = Gd(n0) / 4 for w = 2.
    assert [ISO_CLASSES[c] for c in "ABCDEFGH"] == [16e-6 * 4 ** i for i in range(8)]
    assert iso8608_psd(0.1, 64e-6) == pytest.approx(64e-6)
    assert iso8608_psd(0.2, 64e-6) == pytest.approx(16e-6)
    for word, letter in ROUGHNESS_WORDS.items():
        assert RoadSpec.from_class(word).gd_n0_m3 == ISO_CLASSES[letter]
    assert RoadSpec.from_class("d").gd_n0_m3 == 1024e-6


@pytest.mark.parametrize("kw, field", [
    ({"waviness": -1.0}, "road.waviness"),
    ({"gd_n0_m3": 0.0}, "road.gd_n0_m3"),
    ({"n_min_cyc_per_m": 2.0, "n_max_cyc_per_m": 1.0}, "road.n_max_cyc_per_m"),
    ({"tracks": "mirror"}, "road.tracks"),
    ({"track_width_m": float("nan")}, "road.track_width_m"),
])
def test_roadspec_validation_names_field(kw, field):
    args = {"gd_n0_m3": 1e-4, **kw}
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        RoadSpec(**args)
    with pytest.raises(ValueError, match="unknown"):
        RoadSpec.from_class("Z")


def test_seed_reproducible():
    # Reference: numpy Generator streams are deterministic per seed.
    spec = RoadSpec.from_class("B", tracks="coherent")
    a = generate_profile(spec, 500.0, 0.05, np.random.default_rng(3))
    b = generate_profile(spec, 500.0, 0.05, np.random.default_rng(3))
    c = generate_profile(spec, 500.0, 0.05, np.random.default_rng(4))
    assert np.array_equal(a.left_m, b.left_m) and np.array_equal(a.right_m, b.right_m)
    assert not np.array_equal(a.left_m, c.left_m)
    assert not a.left_m.flags.writeable and a.x_m.size == 10001


def test_fast_for_10_km_at_1_cm():
    p = generate_profile(RoadSpec.from_class("C"), 10_000.0, 0.01, np.random.default_rng(0))
    assert p.x_m.size == 1_000_001 and p.x_m[-1] == pytest.approx(10_000.0)


def _coherence(p, nperseg=2048):
    return signal.coherence(p.left_m, p.right_m, fs=1 / p.dx_m, nperseg=nperseg)


def test_track_modes():
    rng = np.random.default_rng
    band = {"n_max_cyc_per_m": 5.0}  # dx = 0.1 m: Nyquist 5 cycle/m
    same = generate_profile(RoadSpec.from_class("C", tracks="identical", **band), 500.0, 0.1,
                            rng(1))
    assert np.array_equal(same.left_m, same.right_m)
    # Independent: true coherence 0; Welch estimate bias ~ 1/(number of segments ~ 97).
    ind = generate_profile(RoadSpec.from_class("C", **band), 10_000.0, 0.1, rng(1))
    n, coh = _coherence(ind)
    assert coh[(n > 0.02) & (n < 4)].mean() < 0.05
    # Coherent: model gamma^2 = exp(-a n B), a = 6, B = 2 m (RoadSpec docstring).
    spec = RoadSpec.from_class("C", tracks="coherent", **band)
    coh_p = generate_profile(spec, 10_000.0, 0.1, rng(1))
    n, coh = _coherence(coh_p)
    for f in (0.03, 0.06, 0.12, 0.25):
        sel = np.abs(n / f - 1) < 0.2
        assert coh[sel].mean() == pytest.approx(spec.coherence(f), abs=0.08), f
    # The left track does not depend on the track mode (left phases are drawn first).
    assert np.array_equal(ind.left_m, coh_p.left_m)


def test_rear_is_front_delayed_by_wheelbase_over_speed():
    # Exact binary setup: v / fs = 1/8 m per sample, wheelbase 4 m -> 32 samples delay.
    x = np.arange(4001) * 0.125
    rng = np.random.default_rng(5)
    p = Profile(x, rng.normal(size=x.size), rng.normal(size=x.size))
    d = sample_wheels(p, speed_mps=8.0, wheelbase_m=4.0, fs_hz=64.0, duration_s=20.0,
                      start_m=10.0)
    assert d.z_m.shape == (1281, 4) and d.corners == ("fl", "fr", "rl", "rr")
    for front, rear in ((0, 2), (1, 3)):
        assert np.array_equal(d.z_m[32:, rear], d.z_m[:-32, front])
        assert np.array_equal(d.v_mps[32:, rear], d.v_mps[:-32, front])
    assert np.array_equal(d.z_m[:, 0], np.interp(10.0 + d.t_s * 8.0, x, p.left_m))


def test_wheel_velocity_of_a_sine():
    # Reference: z = A sin(2 pi x / L) at speed v -> dz/dt = A (2 pi v / L) cos(2 pi s / L).
    # Centred difference + linear interpolation of the slope err by
    # ((2 pi dx / L)^2 / 6 + (2 pi dx / L)^2 / 8) relative = 3.7e-5 here; allow 1e-4.
    x = np.arange(20001) * 0.01
    lam, amp, v = 5.0, 0.01, 20.0
    z = amp * np.sin(2 * np.pi * x / lam)
    d = sample_wheels(Profile(x, z, z, n_max_cyc_per_m=1.0), v, 5.0, 1000.0, 5.0)
    s = d.t_s * v + 6.0  # default start = x0 + wheelbase + START_MARGIN_M (1 m)
    peak = amp * 2 * np.pi * v / lam
    for col, shift in ((0, 0.0), (2, 5.0)):
        expected = peak * np.cos(2 * np.pi * (s - shift) / lam)
        assert np.max(np.abs(d.v_mps[:, col] - expected)) < 1e-4 * peak
    assert np.max(np.abs(d.z_m[:, 0] - amp * np.sin(2 * np.pi * s / lam))) < 1e-4 * amp


def test_sample_wheels_errors():
    p = generate_profile(RoadSpec.from_class("C"), 200.0, 0.05, np.random.default_rng(0))
    with pytest.raises(ValueError, match="speed_mps"):
        sample_wheels(p, 0.0, 5.0, 1000.0, 1.0)
    with pytest.raises(ValueError, match="too short"):
        sample_wheels(p, 20.0, 5.0, 1000.0, 10.0)
    # 20 m/s x 10 cycle/m = 200 Hz content needs fs >= 400 Hz (Nyquist).
    with pytest.raises(ValueError, match="fs_hz"):
        sample_wheels(p, 20.0, 5.0, 399.0, 1.0)
    sample_wheels(p, 20.0, 5.0, 400.0, 1.0)
    with pytest.raises(ValueError, match="start_m"):
        sample_wheels(p, 20.0, 5.0, 1000.0, 1.0, start_m=4.0)


@pytest.mark.parametrize("order", [1, 2, 4])
def test_highpass_gain(order):
    # Reference: one digital Butterworth pass has |H|^2 = r^(2N) / (1 + r^(2N)) with
    # r = tan(pi n dx) / tan(pi n_c dx) (bilinear transform, prewarped at n_c); the
    # zero-phase forward-backward filter applies |H| twice, so its amplitude gain is
    # |H|^2, i.e. 20 log10(|H|^2) dB. Measured by least-squares sine fit in the
    # middle half, away from the filtfilt edge transients.
    cut, dx = 20.0, 0.05
    x = np.arange(int(2000 / dx) + 1) * dx
    mid = slice(x.size // 4, 3 * x.size // 4)
    for lam in (cut * 10, cut / 10):
        z = np.sin(2 * np.pi * x / lam)
        out = highpass(Profile(x, z, z), cut, order=order).left_m
        phase = 2 * np.pi * x[mid] / lam
        basis = np.column_stack([np.sin(phase), np.cos(phase)])
        gain_db = 20 * np.log10(np.hypot(*np.linalg.lstsq(basis, out[mid], rcond=None)[0]))
        r = np.tan(np.pi * dx / lam) / np.tan(np.pi * dx / cut)
        expected_db = 20 * np.log10(r ** (2 * order) / (1 + r ** (2 * order)))
        assert gain_db == pytest.approx(expected_db, abs=0.01 if lam > cut else 1e-4)
        if order == 2:  # the default: the brief's -40 dB / 0.1 dB requirements
            assert gain_db < -40 if lam > cut else abs(gain_db) < 0.1


def test_highpass_validation():
    p = generate_profile(RoadSpec.from_class("A"), 200.0, 0.05, np.random.default_rng(0))
    with pytest.raises(ValueError, match="Nyquist"):
        highpass(p, 0.1)
    with pytest.raises(ValueError, match="length"):
        highpass(p, 500.0)


def test_csv_round_trip(tmp_path):
    p = generate_profile(RoadSpec.from_class("B"), 100.0, 0.01, np.random.default_rng(2))
    path = tmp_path / "road.csv"
    write_profile_csv(p, path)
    q = read_profile_csv(path)
    assert np.array_equal(p.x_m, q.x_m) and np.array_equal(p.left_m, q.left_m)
    assert np.array_equal(p.right_m, q.right_m)
    two = tmp_path / "two.csv"
    two.write_text("distance_m,elevation_m\n0,0.001\n0.5,0.002\n1.0,-0.001\n")
    r = read_profile_csv(two)
    assert np.array_equal(r.left_m, r.right_m) and r.dx_m == 0.5


GOOD = "distance_m,left_m,right_m\n0.0,0.0,0.0\n0.1,0.001,0.002\n0.2,0.0,0.001\n0.3,0.0,0.0\n"


@pytest.mark.parametrize("text, pattern", [
    (GOOD.replace("0.001,0.002", "0.001,abc"), r"line 3, column right_m: 'abc' is not a number"),
    (GOOD.replace("0.001,0.002", "nan,0.002"), r"line 3, column left_m: .*not finite"),
    (GOOD.replace("0.2,", "0.25,"), r"line 4, column distance_m: .*resample"),
    (GOOD.replace("0.2,", "0.1,"), r"line 4, column distance_m: .*does not increase"),
    (GOOD.replace("left_m", "l"), r"line 1: header"),
    (GOOD.replace("0.001,0.002", "0.001"), r"line 3 has 2 cells, expected 3"),
    ("distance_m,left_m,right_m\n0,0,0\n", r"at least 2"),
])
def test_csv_bad_input(tmp_path, text, pattern):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ProfileError, match=pattern) as info:
        read_profile_csv(path)
    assert "bad.csv" in str(info.value)


def test_csv_missing_file(tmp_path):
    with pytest.raises(ProfileError, match="does not exist"):
        read_profile_csv(tmp_path / "nope.csv")


def test_profile_validation_names_track_and_distance():
    x = np.arange(10) * 0.5
    right = np.zeros(10)
    right[6] = np.nan
    with pytest.raises(ValueError, match=r"right_m is not finite at x = 3 m"):
        Profile(x, np.zeros(10), right)
    with pytest.raises(ValueError, match=r"x_m at index 5: step 0.51 m differs"):
        Profile(np.r_[x[:5], x[5:] + 0.01], np.zeros(10), np.zeros(10))


def test_check_stroke_names_corner_and_time():
    # Hand-built drive: rl reaches -80 mm at t = 0.25 s, stroke +-76 mm -> 4.0 mm beyond.
    t = np.arange(101) / 100
    z = np.zeros((101, 4))
    z[25, 2] = -0.080
    z[60, 0] = 0.070
    d = Drive(t, z, np.zeros_like(z))
    d.check_stroke(0.081)
    with pytest.raises(ValueError, match=r"drive rl reaches -80.0 mm at t = 0.250 s, 4.0 mm "
                                         r"beyond the \+-76.0 mm stroke"):
        d.check_stroke(0.076)


def test_envelope_is_a_moving_average_with_sinc_response():
    """Reference: a moving average of length L passes a sine of wavelength lambda with gain
    sin(pi L / lambda) / (pi L / lambda) (the Fourier transform of a box); L = 0.25 m is the
    IRI's tire model (Sayers 1995)."""
    from rigsim.scenarios.core.profiles import envelope

    dx = 0.01
    x = np.arange(0, 200.0, dx)
    for lam in (2.0, 0.5, 0.4):
        z = np.sin(2 * np.pi * x / lam)
        p = envelope(Profile(x, z, z), 0.25)
        core = slice(2000, -2000)
        gain = np.std(p.left_m[core]) / np.std(z[core])
        u = np.pi * 0.25 / lam
        assert gain == pytest.approx(abs(np.sin(u) / u), abs=2e-3)
    # A wavelength equal to the averaging length is removed; zero length changes nothing.
    z = np.sin(2 * np.pi * x / 0.25)
    assert np.max(np.abs(envelope(Profile(x, z, z), 0.25).left_m[2000:-2000])) < 1e-9
    q = Profile(x, z, z)
    assert envelope(q, 0.0) is q


def test_road_drive_reads_only_the_profile_points_it_needs_and_gets_the_same_bits():
    """RoadDrive interpolates each chunk on a slice of the profile and makes the slopes of that
    slice only (memory: a 600 s drive holds no profile-long slope arrays); the values
    are bit for bit those of numpy.gradient and numpy.interp on the whole profile."""
    import numpy as np

    from rigsim.scenarios.core import road_drive as rd
    from rigsim.scenarios.core.config import parse_scenario
    from rigsim.scenarios.core.rig import Rig

    rng = np.random.default_rng(5)
    track = rng.normal(size=200)
    for i0, i1 in ((0, 200), (0, 7), (193, 200), (50, 51), (10, 120)):
        assert np.array_equal(rd._slope(track, i0, i1, 0.02), np.gradient(track, 0.02)[i0:i1])
    sc = parse_scenario({"name": "slice", "speed_kmh": 72.0, "duration_s": 2.0, "lead_in_s": 1.0, "seed": 4,
                         "road": {"roughness": "C"}})
    src = Rig(sc, hydraulic=False).road_source()
    p, v = src.profile, src.speed_mps
    for k0, k1 in ((0, 1), (0, 1000), (12345, 13999), (src.n_steps - 5, src.n_steps)):
        t = np.arange(k0, k1) / src.fs_hz
        s = np.minimum(src.start_m + v * t, p.x_m[-1])
        z, vz = src.chunk(k0, k1)
        fade = src.lead_in_s > 0 and k0 < src.lead_in_s * src.fs_hz
        for col, (track, pos) in enumerate(((p.left_m, s), (p.right_m, s), (p.left_m, s - src.wheelbase_m),
                                            (p.right_m, s - src.wheelbase_m))):
            ref_z = np.interp(pos, p.x_m, track)
            ref_v = v * np.interp(pos, p.x_m, np.gradient(track, p.dx_m))
            if not fade:
                assert np.array_equal(z[:, col], ref_z) and np.array_equal(vz[:, col], ref_v)
