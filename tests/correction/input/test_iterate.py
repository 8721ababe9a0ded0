"""rigsim.correction.input.iterate: iterative drive-file correction (RPC-style / Moran) on a linear simulated rig.

The "rig" here is linear and known exactly: per wheel the paper's eq. 4 (coefficients from the
independent implementation rigsim.hydraulics.linearization.eq4_coefficients at DYNTRAC's default
parameters, 1.8 MN/m tire, 30 kN load), discretized by scipy (bilinear) and simulated with
lfilter, plus a known cross-coupling between wheels (10 % of each neighbour's drive through a
10 Hz, zeta 0.3 resonance: the truck's axle hop seen by the other pans). Expected values come
from linear iteration theory, not from earlier runs: with an exact inverse the error after k
updates is |1 - g|^k of the initial error in the band (g = 1: one step), so a handful of
iterations must reach 1 % NRMSE; g = 2.5 gives |1 - g| = 1.5 > 1, which must be refused up front
and, if run anyway, stopped by the divergence check.
"""

import numpy as np
import pytest
from scipy import signal

from rigsim.correction.input.convergence import IterationStabilityError, dynamic_error, error_map_spectral_radius
from rigsim.correction.input.frf import FRF, identify_frf, inverse_frf
from rigsim.correction.input.iterate import iterate_drive
from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.hydraulics import ActuatorParams, eq4_parameters

FS = 500.0  # Hz: eq. 4's poles are at 0.15, 13.5 and 69 Hz; a 30 Hz band needs little more


def _discrete(num, den):
    return signal.bilinear(num, den, fs=FS)


TA = _discrete(*eq4_coefficients_from(**eq4_parameters(ActuatorParams(), 1.8e6, 30e3)))
W_C = 2 * np.pi * 10.0
TC = _discrete([0.1 * W_C ** 2], [1.0, 2 * 0.3 * W_C, W_C ** 2])
NEIGHBOURS = {0: (1, 2), 1: (0, 3), 2: (0, 3), 3: (1, 2)}  # fl-fr, fl-rl, fr-rr, rl-rr


def linear_rig(d):
    d = np.atleast_2d(np.asarray(d, dtype=float))
    y = np.empty_like(d)
    for i in range(4):
        y[:, i] = signal.lfilter(*TA, d[:, i])
        for j in NEIGHBOURS[i]:
            y[:, i] += signal.lfilter(*TC, d[:, j])
    return y


def true_frf(f_hz):
    z = np.exp(2j * np.pi * np.asarray(f_hz) / FS)
    ta = np.polyval(TA[0], z) / np.polyval(TA[1], z)
    tc = np.polyval(TC[0], z) / np.polyval(TC[1], z)
    h = np.zeros((np.size(f_hz), 4, 4), dtype=complex)
    for i in range(4):
        h[:, i, i] = ta
        for j in NEIGHBOURS[i]:
            h[:, i, j] = tc
    return h


def _road_like(seconds, seed):
    """Four independent road-like tracks: white velocity (1/f^2 displacement) from 0.5 to 20 Hz,
    ~10 mm rms, faded in over 2 s (as a scenario's lead-in)."""
    n = int(seconds * FS)
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n, 1 / FS)
    amp = np.where((f >= 0.5) & (f <= 20.0), 1.0 / np.maximum(f, 0.5), 0.0)
    x = np.fft.irfft(amp[:, None] * np.exp(2j * np.pi * rng.random((f.size, 4))), n=n, axis=0)
    x *= 0.01 / x.std(axis=0)
    t = np.arange(n) / FS
    fade = np.clip(t / 2.0, 0, 1)
    return x * (0.5 - 0.5 * np.cos(np.pi * fade))[:, None]


@pytest.fixture(scope="module")
def frf():
    rng = np.random.default_rng(7)
    u = rng.standard_normal((int(120 * FS), 4)) * 0.01
    u = signal.sosfiltfilt(signal.butter(4, 60.0, fs=FS, output="sos"), u, axis=0)
    return identify_frf(u, linear_rig(u), FS, 1024)


def test_identified_frf_matches_the_known_linear_rig(frf):
    # Expected: the rig's own FRF (eq. 4 on the diagonal, the coupling off it), evaluated exactly.
    band = (frf.f_hz > 0.5) & (frf.f_hz < 30.0)
    h = true_frf(frf.f_hz[band])
    err = np.abs(frf.h[band] - h).max() / np.abs(h).max()
    assert err < 0.02
    assert np.min(frf.coherence[band]) > 0.99  # noise-free linear rig


def test_iteration_converges_to_the_displacement_target_within_one_percent(frf):
    # Moran's target: pan displacement = road profile. Starting from drive = profile, the rig's
    # error is tens of percent (eq. 4 is ~25 % down at 10 Hz); |1 - 0.9|^k makes 1 % in ~3 steps.
    target = _road_like(60.0, 3)
    res = iterate_drive(linear_rig, target, frf, FS, drive0=target, gain=0.9, band_hz=(0.3, 30.0),
                        max_iterations=8, tolerance=0.01)
    assert res.steps[0].nrmse_mean > 0.1  # the rig really distorts the drive
    # Predicted bound |1 - g| + g delta with delta ~ 0 (coherence ~1): just above 0.1.
    assert 0.1 <= res.spectral_radius_bound < 0.2
    assert res.status == "converged", res.message
    assert res.steps[res.best_index].nrmse_mean <= 0.01
    assert res.best_index <= 5  # "a handful"
    assert res.runs == res.best_index + 1
    # The error falls monotonically while the iteration is stable.
    assert all(b < a for a, b in zip(res.errors, res.errors[1:]))
    # Independent check of the final drive: run it again on the rig.
    y = linear_rig(res.drive)
    inner = slice(int(FS), -int(FS))
    assert np.mean(dynamic_error(target[inner], y[inner])) <= 0.012


def test_iteration_converges_to_a_remote_force_like_target(frf):
    # RPC-style: the target is the response of the rig to an unknown "road" drive; the iteration
    # must find a drive reproducing it (it exists: the road drive itself).
    road_drive = _road_like(40.0, 11)
    target = linear_rig(road_drive) * 1.8e6  # as a tire-force-like quantity, N
    scaled = FRF(f_hz=frf.f_hz, h=frf.h * 1.8e6, coherence=frf.coherence, averages=frf.averages)
    res = iterate_drive(linear_rig_scaled, target, scaled, FS, gain=1.0, max_iterations=6, tolerance=0.01)
    assert res.status == "converged", res.message
    assert res.steps[res.best_index].nrmse_mean <= 0.01


def linear_rig_scaled(d):
    return linear_rig(d) * 1.8e6


def test_the_dynamic_error_is_the_nrmse_without_the_errors_mean():
    """The iteration's measure is the one NRMSE with the error's mean left out; a constant target
    column (no NRMSE) scores the error's standard deviation."""
    from rigsim.correction.metrics.dlc import nrmse

    t = np.column_stack([np.sin(np.linspace(0, 20, 500)), np.cos(np.linspace(0, 7, 500))])
    y = 0.9 * t + 0.3
    assert np.array_equal(dynamic_error(t, y), nrmse(y, t, mean_free=True))
    np.testing.assert_allclose(dynamic_error(t, y), [0.1, 0.1], rtol=1e-9)
    flat = np.column_stack([t[:, 0], np.full(500, 2.0)])
    np.testing.assert_allclose(dynamic_error(flat, flat + np.column_stack([0 * t[:, 0], t[:, 1]])),
                               [0.0, t[:, 1].std()], atol=1e-12)


def test_spectral_radius_of_the_error_map_on_the_exact_model(frf):
    # With the exact inverse, I - g H H^-1 = (1 - g) I: radius |1 - g| (0.1 at g = 0.9, 1.5 at 2.5).
    f = frf.f_hz[(frf.f_hz > 0.5) & (frf.f_hz < 30.0)]
    h = true_frf(f)
    inv = inverse_frf(h, regularization=0.0)
    assert np.allclose(error_map_spectral_radius(h, inv, 0.9), 0.1, atol=1e-9)
    assert np.allclose(error_map_spectral_radius(h, inv, 2.5), 1.5, atol=1e-9)


def test_unstable_gain_is_refused_before_any_run(frf):
    # g = 2.5 on an (almost) exact model: |1 - g| = 1.5 >= 1. Expected: refused, no rig run made.
    calls = []

    def rig(d):
        calls.append(1)
        return linear_rig(d)

    with pytest.raises(IterationStabilityError, match=r"gain 2.5 is not stable.*spectral radius"):
        iterate_drive(rig, _road_like(30.0, 5), frf, FS, gain=2.5)
    assert calls == []


def test_unstable_gain_run_anyway_is_stopped_as_diverged(frf):
    # Forced to run, the error grows by ~1.5x per step in the band; the iteration must stop after two
    # growing steps with status "diverged" and hand back the best (first) drive, not the last.
    target = _road_like(30.0, 5)
    res = iterate_drive(linear_rig, target, frf, FS, drive0=target, gain=2.5, on_unstable="run",
                        max_iterations=10)
    assert res.status == "diverged"
    assert "grew in two consecutive iterations" in res.message
    assert res.spectral_radius_bound >= 1.0
    assert len(res.steps) == 3 and res.errors[2] > res.errors[1] > res.errors[0]
    assert res.best_index == 0


def test_low_coherence_frequencies_get_no_update(frf):
    # Coherence below the threshold everywhere in the band: no frequency may be updated; refused.
    bad = FRF(f_hz=frf.f_hz, h=frf.h, coherence=np.full_like(frf.coherence, 0.3), averages=frf.averages)
    with pytest.raises(ValueError, match="coherence"):
        iterate_drive(linear_rig, _road_like(30.0, 5), bad, FS)


def test_drive_limit_stops_the_iteration(frf):
    # A limit below the target's own amplitude: the first update already exceeds it.
    target = _road_like(30.0, 5)
    res = iterate_drive(linear_rig, target, frf, FS, drive0=0.5 * target, gain=0.9,
                        drive_limit=0.6 * np.abs(target).max())
    assert res.status == "drive_limit" and res.runs == 1


# --- the scenarios side (rigsim.scenarios.studies.iterate): bad input is refused before any run ----------------------

def _parse(argv):
    import argparse

    from rigsim.scenarios.studies.iterate import command as iterate_cmd

    p = argparse.ArgumentParser()
    sub = p.add_subparsers(dest="command", required=True)
    iterate_cmd.add_parser(sub)
    return p.parse_args(argv)


@pytest.mark.parametrize("extra, match", [
    (["--gain", "0"], "--gain"),
    (["--gain", "nan"], "--gain"),
    (["--gain", "2.5"], "not stable even with an exact rig model"),
    (["--band-hz", "30", "1"], "--band-hz"),
    (["--tolerance", "2"], "--tolerance"),
    (["--duration-s", "3"], "--duration-s"),
    (["--coherence-min", "1.5"], "--coherence-min"),
    (["--noise-N", "-1"], "--noise-N"),
    (["--max-iterations", "51"], "--max-iterations"),
])
def test_iterate_command_refuses_bad_options(tmp_path, extra, match):
    from rigsim.scenarios.core.config import ScenarioError

    args = _parse(["iterate", "scenarios/data/paper/high_72kmh_3640kg.toml", "--target", "force",
                   "--out", str(tmp_path / "o"), *extra])
    with pytest.raises(ScenarioError, match=match):
        args.func(args)
    assert not (tmp_path / "o").exists()


def test_iterate_command_refuses_a_missing_scenario(tmp_path):
    from rigsim.scenarios.core.config import ScenarioError

    args = _parse(["iterate", str(tmp_path / "nope.toml"), "--target", "displacement", "--out", str(tmp_path / "o")])
    with pytest.raises(ScenarioError):
        args.func(args)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("target, kw, match", [
    ("velocity", {}, "target must be one of displacement, force"),
    ("force", {"gain": 3.0}, "not stable even with an exact rig model"),
    ("force", {"band_hz": (5.0, 1.0)}, "band_hz"),
])
def test_iterate_scenario_refuses_bad_options_before_building_the_rig(monkeypatch, target, kw, match):
    # Expected: the ScenarioError comes before the rig is built or anything runs.
    from rigsim.scenarios.core.config import ScenarioError, load_scenario
    from rigsim.scenarios.studies.iterate import compute

    def no_work(*a, **k):
        raise AssertionError("a rig was built or run before the options were checked")

    monkeypatch.setattr(compute, "Rig", no_work)
    monkeypatch.setattr(compute, "run", no_work)
    with pytest.raises(ScenarioError, match=match):
        compute.iterate_scenario(load_scenario("scenarios/data/paper/high_72kmh_3640kg.toml"), target, **kw)


def test_splice_drive_keeps_the_lead_in_and_interpolates_the_new_drive():
    # A 1 s lead-in and 2 s record at 10 kHz; the new drive at 1 kHz is a ramp per corner, which
    # linear interpolation reproduces exactly; the lead-in must be the base drive's, bit for bit.
    from rigsim.scenarios.core.drive import Drive
    from rigsim.scenarios.studies.iterate.compute import splice_drive

    dt = 1e-4
    t = np.arange(-10000, 20001) * dt
    base = Drive.from_positions(t, 0.01 * np.sin(2 * np.pi * np.outer(t, [1.0, 2.0, 3.0, 4.0])))
    t_out = t[10000::10]
    slopes = np.array([1e-3, -2e-3, 3e-3, 0.0])  # m/s
    out = splice_drive(base, t_out, np.outer(t_out, slopes))
    assert np.array_equal(out.t_s, base.t_s)
    assert np.array_equal(out.z_m[:10000], base.z_m[:10000])
    assert np.allclose(out.z_m[10000:], np.outer(t[10000:], slopes), rtol=0, atol=1e-15)
    assert np.allclose(out.v_mps[10001:-1], slopes, rtol=0, atol=1e-12)


def test_rigsim_iterate_end_to_end_on_the_simulated_rig(tmp_path, capsys):
    """The command on the nonlinear MuJoCo rig (12 s, 2 updates): the displacement error falls
    at every update, the iterated drive restores most of the DLC the rig loses, and the files
    exist. References: the road run's own DLC and the rig run with the original drive."""
    import json

    from rigsim.scenarios.cli.main import main

    scenario = tmp_path / "s.toml"
    scenario.write_text('name = "it"\nspeed_kmh = 72.0\nduration_s = 12.0\nseed = 5\n[road]\nroughness = "C"\n')
    out = tmp_path / "out"
    assert main(["iterate", str(scenario), "--target", "displacement", "--out", str(out),
                 "--max-iterations", "2", "--quiet"]) == 0
    doc = json.loads((out / "iteration.json").read_text())
    errors = [s["nrmse_mean"] for s in doc["iteration"]["steps"]]
    assert errors[1] < 0.5 * errors[0] and errors[2] < errors[1]
    comp = doc["comparison"]
    lost = comp["rig_original_drive"]["dlc"] - comp["road"]["dlc"]
    remaining = comp["rig_iterated_drive"]["dlc"] - comp["road"]["dlc"]
    assert lost < 0 and abs(remaining) < 0.3 * abs(lost)
    assert comp["rig_iterated_drive"]["rig_runs"] == 2 + doc["iteration"]["runs"] == 4
    # Every row on the same samples: outside the iteration's 0.5 s tapers and within the best
    # output correction's settled samples (the shared scoring's), so at most those.
    best = doc["scoring"]["methods"]["best"]
    assert 0 < doc["compared_samples"]["seconds"] <= best["scored_s"] + 1e-9
    assert 0.5 <= doc["compared_samples"]["first_s"] < doc["compared_samples"]["last_s"] <= 12.0 - 0.5
    assert comp["output_corrected"]["nrmse_vs_road_lowpassed"] == pytest.approx(
        doc["scoring"]["mean"]["nrmse_corrected_best"], rel=1e-12)
    drive = np.loadtxt(out / "drive.csv", delimiter=",", skiprows=1)
    assert drive.shape == (12001, 5) and np.allclose(np.diff(drive[:, 0]), 1e-3)
    assert np.abs(drive[:, 1:]).max() <= 0.076  # within DYNTRAC's half stroke
    # the same drive as an RPC III drive file: int16, so within half a step (max|x| / 32752 / 2) of
    # the CSV's numbers (themselves written to 10 significant digits)
    from rigsim.correction.io.measured import read_channels

    drv = read_channels(out / "drive.drv")
    assert drv.names == ("drive_fl", "drive_fr", "drive_rl", "drive_rr") and set(drv.units.values()) == {"m"}
    np.testing.assert_allclose(drv.time_s, drive[:, 0], rtol=0, atol=1e-9)
    for i, name in enumerate(drv.names):
        half_step = 0.5 * np.abs(drive[:, 1 + i]).max() / 32752
        assert 0 < np.abs(drv.data[name] - drive[:, 1 + i]).max() <= half_step * (1 + 1e-6) + 1e-12
    assert drv.metadata["TIME_TYPE"] == "DRIVE"
    assert (drv.metadata["scenario"], drv.metadata["target"]) == ("it", "displacement")
    assert drv.metadata["iterations"] == str(doc["iteration"]["best_index"])
    assert (out / "iteration.png").stat().st_size > 0
    printed = capsys.readouterr().out
    assert "rig_iterated_drive" in printed and "output_corrected" in printed
