"""rigsim.correction.output.pipeline.correct_forces (the one correction) and per-corner actuator files.

References: the correction of each column is re-derived from the filter design and application
called directly (rigsim.correction.output.filters.design_correction, rigsim.correction.output.apply.correct, themselves
checked against scipy in test_correction.py); the settled mask from each filter's own transient
mask and the band-limit reference filter's; the files are read back with tomllib.
"""

from __future__ import annotations

import math
import tomllib

import control
import numpy as np
import pytest
from scipy import signal

from rigsim.correction.io.actuator_file import (ActuatorFileError, parse_actuators, read_actuators_file,
                                      write_actuators_file)
from rigsim.correction.identification.actuator_fit import fit_frequency_response
from rigsim.correction.output.apply import correct
from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.correction.output.filters import design_correction, reference_filter
from rigsim.correction.output.pipeline import CorrectedForces, CorrectionError, correct_forces

FS = 1000.0
EQ4 = dict(ksv=1.0, kq_m3_s=0.0109, kc_m3_s_Pa=1.26e-11, kp_per_m=50.0, kdp_per_Pa=2.0e-8,
           piston_area_m2=7.43e-3, fluid_volume_m3=2.13e-3, bulk_modulus_Pa=1.0e9, mass_kg=500.0,
           damping_N_s_m=5.0e3, tire_N_per_m=1.0e6)


def _actuators():
    """Four different T_a: eq. 4 at four tire stiffnesses and pan masses."""
    return [eq4_coefficients_from(**dict(EQ4, tire_N_per_m=kt, mass_kg=m))
            for kt, m in ((1.0e6, 500.0), (1.2e6, 450.0), (0.8e6, 600.0), (1.5e6, 550.0))]


@pytest.fixture(scope="module")
def forces():
    rng = np.random.default_rng(3)
    sos = signal.butter(4, [0.5, 25.0], "bandpass", fs=FS, output="sos")
    return 30e3 + 3e3 * signal.sosfilt(sos, rng.standard_normal((15_000, 4)), axis=0) / 0.2


@pytest.mark.parametrize("mode, lowpass", [("zerophase", "regularized"), ("causal", "paper")])
def test_each_column_with_its_own_filter_and_settled_is_the_and_of_all_transients(forces, mode, lowpass):
    tas = _actuators()
    res = correct_forces(forces, tas, FS, lowpass=lowpass, mode=mode, settling_tolerance=1e-3)
    assert isinstance(res, CorrectedForces) and res.mode == mode and res.lowpass == lowpass
    assert res.corrected_N.shape == forces.shape and len(res.filters) == 4
    n = forces.shape[0]
    expected = reference_filter(FS, lowpass, settling_tolerance=1e-3).transient_mask(n, mode)
    for j, ta in enumerate(tas):
        filt = design_correction(ta, FS, lowpass, settling_tolerance=1e-3)
        np.testing.assert_allclose(res.corrected_N[:, j], correct(forces[:, j], filt, mode), rtol=1e-12)
        np.testing.assert_allclose(res.filters[j].sos, filt.sos)
        expected &= filt.transient_mask(n, mode)
    np.testing.assert_array_equal(res.settled, expected)
    assert 0 < res.settled.sum() < n
    # the columns really differ: each T_a matters
    other = correct(forces[:, 1], design_correction(tas[0], FS, lowpass), mode)
    assert np.max(np.abs(other - res.corrected_N[:, 1])) > 10.0


def test_one_actuator_serves_every_column_and_a_1d_force(forces):
    ta = _actuators()[0]
    res = correct_forces(forces, ta, FS)
    filt = design_correction(ta, FS, "regularized")
    np.testing.assert_allclose(res.corrected_N, correct(forces, filt, "zerophase"), rtol=1e-12)
    assert len(res.filters) == 4 and res.filters[0] is res.filters[3]
    one = correct_forces(forces[:, 2], [ta], FS)
    assert one.corrected_N.shape == (forces.shape[0],)
    np.testing.assert_allclose(one.corrected_N, res.corrected_N[:, 2], rtol=1e-12)
    tf = correct_forces(forces, control.tf(*ta), FS)
    np.testing.assert_allclose(tf.corrected_N, res.corrected_N, rtol=1e-9)


def test_an_actuator_fit_is_accepted(forces):
    ta = _actuators()[0]
    f = np.arange(1, 480) * 0.125
    s = 2j * np.pi * f
    fit = fit_frequency_response(f, np.polyval(ta[0], s) / np.polyval(ta[1], s), np.full(f.size, 0.99))
    res = correct_forces(forces[:, :1], [fit], FS)
    np.testing.assert_allclose(res.corrected_N[:, 0],
                               correct(forces[:, 0], design_correction(fit.as_tf(), FS, "regularized"), "zerophase"))


def test_refusals_name_the_column(forces):
    tas = _actuators()
    tas[2] = ([-1.0, 1.0], [0.001, 0.1, 1.0])  # right-half-plane zero
    with pytest.raises(CorrectionError, match="non-minimum-phase") as exc:
        correct_forces(forces, tas, FS)
    assert exc.value.column == 2
    with pytest.raises(CorrectionError, match=r"T_a\(0\) = 2") as exc:
        correct_forces(forces, ([2.0], [0.001, 0.1, 1.0]), FS)
    assert exc.value.column is None
    res = correct_forces(forces, ([2.0], [0.001, 0.1, 1.0]), FS, normalize_dc=True)
    assert abs(res.corrected_N[res.settled].mean() - forces[res.settled].mean()) < 50.0
    with pytest.raises(ValueError, match="got 3 actuators for 4 force columns"):
        correct_forces(forces, _actuators()[:3], FS)
    with pytest.raises(ValueError, match="unknown mode"):
        correct_forces(forces, _actuators(), FS, mode="acausal")


# ---------------------------------------------------------------- per-corner actuator files


def test_actuators_file_round_trip_with_fit_diagnostics_and_meta(tmp_path):
    tas = _actuators()
    f = np.arange(1, 480) * 0.125
    s = 2j * np.pi * f
    fit = fit_frequency_response(f, np.polyval(tas[1][0], s) / np.polyval(tas[1][1], s), np.full(f.size, 0.99))
    path = tmp_path / "sub" / "actuators.toml"
    meta = {"source": 'rig "B"\nrun 7', "rms_m": 0.004, "record_s": 120.0}
    write_actuators_file(path, {"fl": tas[0], "fr": fit, "rear left": tas[2]}, meta=meta)
    back = read_actuators_file(path)
    assert list(back) == ["fl", "fr", "rear left"]
    np.testing.assert_array_equal(back["fl"][0], tas[0][0])
    np.testing.assert_array_equal(back["fl"][1], tas[0][1])  # repr of a float reads back exactly
    np.testing.assert_array_equal(back["fr"][0], fit.num)
    np.testing.assert_array_equal(back["rear left"][1], tas[2][1])
    doc = tomllib.loads(path.read_text())
    assert doc["meta"] == meta
    assert doc["fr"]["fit"]["orders"] == list(fit.orders)
    assert doc["fr"]["fit"]["held_out_error"] == fit.held_out_error
    assert set(doc["fr"]["fit"]["band_errors"]) == set(fit.band_errors)
    assert [p.name for p in path.parent.iterdir()] == ["actuators.toml"]  # no temporary file left


@pytest.mark.parametrize("doc, message", [
    ({"transfer_function": {"num": [1.0], "den": [1.0, 1.0]}}, r"single-actuator file \(\[transfer_function\]\)"),
    ({"meta": {"source": "x"}}, "needs at least one corner table"),
    ({"fl": [1.0]}, r"fl must be a table \[fl\]"),
    ({"fl": {"num": [1.0], "dem": [1.0, 1.0]}}, "unknown key fl.dem; did you mean 'den'"),
    ({"fr": {"num": [1.0]}}, "fr.den is missing"),
    ({"rl": {"num": [1.0], "den": ["a"]}}, r"rl.den\[0\] must be a number"),
    ({"rr": {"num": [1.0], "den": [0.0, 0.0]}}, "rr.den is zero"),
    ({"rr": {"num": [1.0], "den": [1.0, 1.0], "fit": 3}}, "rr.fit must be a table"),
    ({"meta": 3, "fl": {"num": [1.0], "den": [1.0, 1.0]}}, r"meta must be a table"),
])
def test_actuators_file_errors_name_the_table_and_key(doc, message):
    with pytest.raises(ActuatorFileError, match=message) as exc:
        parse_actuators(doc)
    assert "\n" not in str(exc.value)


def test_actuators_file_ignores_fit_and_meta_and_refuses_reserved_names(tmp_path):
    got = parse_actuators({"meta": {"anything": [1, 2]}, "fl": {"num": [1.0], "den": [1.0, 1.0],
                                                               "fit": {"whatever": "x"}}})
    assert list(got) == ["fl"]
    with pytest.raises(ActuatorFileError, match="corner name 'meta'"):
        write_actuators_file(tmp_path / "a.toml", {"meta": ([1.0], [1.0, 1.0])})
    with pytest.raises(ActuatorFileError, match="finite coefficients"):
        write_actuators_file(tmp_path / "a.toml", {"fl": ([math.nan], [1.0, 1.0])})
    assert not list(tmp_path.iterdir())


def test_toml_text_reads_back_with_tomllib(tmp_path):
    from rigsim.correction.io.tomlfile import toml_text, write_toml

    doc = {"top": 1, "a": {"x": math.nan, "y": -math.inf, "flag": True, "name": 'q"\\\x7f\t',
                           "list": [1.5, 2, 1e-300], "rows": [{"re": 1.0, "im": -2.0}],
                           "b c": {"deep": "ok"}, "empty": {}}}
    back = tomllib.loads(toml_text(doc))
    assert back["top"] == 1 and math.isnan(back["a"]["x"]) and back["a"]["y"] == -math.inf
    assert back["a"]["flag"] is True and back["a"]["name"] == 'q"\\\x7f\t'
    assert back["a"]["list"] == [1.5, 2, 1e-300] and back["a"]["rows"] == [{"re": 1.0, "im": -2.0}]
    assert back["a"]["b c"] == {"deep": "ok"} and back["a"]["empty"] == {}
    write_toml(tmp_path / "d.toml", {"k": np.float64(0.1), "n": np.int64(3), "v": np.array([1.0, 2.0])})
    assert tomllib.loads((tmp_path / "d.toml").read_text()) == {"k": 0.1, "n": 3, "v": [1.0, 2.0]}
    with pytest.raises(TypeError, match="cannot write a object"):
        toml_text({"k": object()})
