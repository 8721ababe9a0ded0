"""The lab's channel timing given to the correction (``force_filter`` / ``lvdt_filter``, ``rigsim
correct --force-filter ... --lvdt-filter ...``, ``rigsim identify --from-file --lvdt-filter``).

Reference: the same record without the lab's filters and delay (the exact channels). A record
whose force passed a 200 Hz and whose LVDT a 150 Hz 4th-order Butterworth (digital, as
:data:`rigsim.scenarios.core.lab.TYPICAL_LAB`'s) with the force 0.2 ms late, corrected with that timing
given, must land on the exact record's correction within a small part of what the timing costs
when it is not given.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from rigsim.correction.io.acquisition import ChannelFilter
from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.scenarios.cli.main import main
from rigsim.scenarios.core.config import ScenarioError
from rigsim import LinearOptions, correct_record, identify_record, read_record

FS = 1000.0
EQ4 = dict(ksv=1.0, kq_m3_s=0.0109, kc_m3_s_Pa=1.26e-11, kp_per_m=50.0, kdp_per_Pa=2.0e-8, piston_area_m2=7.43e-3,
           fluid_volume_m3=2.13e-3, bulk_modulus_Pa=1.0e9, mass_kg=500.0, damping_N_s_m=5.0e3, tire_N_per_m=1.0e6)
FORCE = ChannelFilter(200.0, 4, domain="digital", delay_s=2e-4)
LVDT = ChannelFilter(150.0, 4, domain="digital")
NAMES = ("time", "Fz_FL", "drive_m", "pan_m")


def _write(path, columns) -> None:
    rows = [",".join(NAMES)] + [",".join(repr(float(v)) for v in row) for row in zip(*columns)]
    path.write_text("\n".join(rows) + "\n")


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    """(folder, road force): exact.csv (the rig force, drive and pan as they were) and lab.csv (the
    force and the pan through the lab's filters and delay)."""
    d = tmp_path_factory.mktemp("timing")
    rng = np.random.default_rng(7)
    n = int(30 * FS)
    t = np.arange(n) / FS
    ta = eq4_coefficients_from(**EQ4)
    bp = signal.butter(4, [0.5, 20.0], "bandpass", fs=FS, output="sos")
    road = 29e3 + 4e3 * signal.sosfilt(bp, rng.standard_normal(n)) / 0.3
    rig = signal.lsim(ta, road - road[0], t)[1] + road[0]
    drive = 0.01 * signal.sosfilt(signal.butter(4, [0.3, 40.0], "bandpass", fs=FS, output="sos"), rng.standard_normal(n))
    pan = signal.lsim(ta, drive, t)[1]
    _write(d / "exact.csv", [t, rig, drive, pan])
    _write(d / "lab.csv", [t, FORCE.apply(rig, FS), drive, LVDT.apply(pan, FS)])
    return d, road


def _error(result, road) -> float:
    """NRMSE of the settled corrected force against the road force through the same 30 Hz band."""
    from rigsim.correction.output.apply import band_limit

    ref = band_limit(road[:, None], FS, "regularized", "zerophase")[:, 0]
    keep = result.settled
    y = result.corrected_N[keep, 0]
    return float(np.sqrt(np.mean((y - ref[keep]) ** 2)) / np.std(ref[keep]))


def test_given_timing_lands_on_the_exact_records_correction(records):
    d, road = records
    exact = _error(correct_record(d / "exact.csv", LinearOptions(identify="drive_m,pan_m")), road)
    raw = _error(correct_record(d / "lab.csv", LinearOptions(identify="drive_m,pan_m")), road)
    aligned_result = correct_record(d / "lab.csv", LinearOptions(identify="drive_m,pan_m"), force_filter=FORCE,
                                    lvdt_filter=LVDT)
    aligned = _error(aligned_result, road)
    assert raw - exact > 0.02  # not given, the timing costs a visible error
    assert aligned - exact < 0.1 * (raw - exact)
    assert "channel_timing" in aligned_result.metadata
    assert "200 Hz" in aligned_result.metadata["channel_timing"]


def test_identification_with_the_lvdt_filter_is_the_exact_ones(records):
    d, _ = records
    exact = identify_record(read_record(d / "exact.csv"), pairs="fl=drive_m:pan_m").fits["fl"]
    raw = identify_record(read_record(d / "lab.csv"), pairs="fl=drive_m:pan_m").fits["fl"]
    given = identify_record(read_record(d / "lab.csv"), pairs="fl=drive_m:pan_m", lvdt_filter="150:4:digital")
    f = np.array([2.0, 5.0, 10.0, 20.0])
    # Not given, the LVDT filter's 2.6 ms is what a low-order T_a cannot hold: a worse held-out fit and a
    # phase off by tens of mrad at 20 Hz; given, the exact record's T_a.
    assert raw.held_out_error > 10 * exact.held_out_error
    assert abs(np.angle(raw.frequency_response(f)) - np.angle(exact.frequency_response(f)))[-1] > 0.03
    np.testing.assert_allclose(given.fits["fl"].frequency_response(f), exact.frequency_response(f), atol=2e-3)
    assert given.fits["fl"].held_out_error < 1.5 * exact.held_out_error
    assert "150 Hz" in given.meta()["lvdt_timing"]


def test_cli_writes_the_timing_and_refuses_bad_options(records, tmp_path, capsys):
    d, _ = records
    out = tmp_path / "c.csv"
    assert main(["correct", str(d / "lab.csv"), "--identify", "drive_m,pan_m", "--force-filter", "200:4:digital",
                 "--force-delay", "0.0002", "--lvdt-filter", "150:4:digital", "-o", str(out), "--quiet"]) == 0
    text = out.read_text()
    assert "channel_timing" in text and "0.2 ms delay" in text
    for argv, words in (
            (["--identify", "drive_m,pan_m", "--force-filter", "200:4:elliptic"], "--force-filter"),
            (["--identify", "drive_m,pan_m", "--force-delay", "0.5"], "--force-delay"),
            (["--identify", "drive_m,pan_m", "--force-filter", "600"], "half the record's rate"),
            (["--columns", "Fz_FL", "--actuator", str(d / "missing.toml"), "--lvdt-filter", "150"], "--lvdt-filter")):
        bad = tmp_path / "bad.csv"
        assert main(["correct", str(d / "lab.csv"), *argv, "-o", str(bad)]) == 2
        err = capsys.readouterr().err
        assert words in err and err.count("\n") == 1
        assert not bad.exists()


def test_identify_command_takes_the_lvdt_filter(records, tmp_path):
    d, _ = records
    assert main(["identify", "--from-file", str(d / "lab.csv"), "--pairs", "fl=drive_m:pan_m", "--lvdt-filter",
                 "150:4:digital", "-o", str(tmp_path / "id"), "--quiet"]) == 0
    assert "lvdt_timing" in (tmp_path / "id" / "actuators.toml").read_text()


def test_api_refuses_an_lvdt_filter_nothing_reads(records):
    d, _ = records
    with pytest.raises(ScenarioError, match="lvdt_filter"):
        correct_record(d / "lab.csv", LinearOptions(actuator=(np.array([1.0]), np.array([1.0]))), lvdt_filter="150")
