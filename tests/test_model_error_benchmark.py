"""benchmarks/model_error.py reads each wheel's model error as the fallback reads it
(Calibration.excess_nrmse: the band residual beyond the band noise), and sets the model correction's
NRMSE beside it only where the model corrected the wheel.

Hand-made run rows (no simulation): 3-4-5 triangles give the errors, sqrt(0.05^2 - 0.03^2) = 0.04.
"""

from __future__ import annotations

import dataclasses
import json
import math

import pytest

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.files import to_json
from rigsim.scenarios.records.model.result import Calibration


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("model_error")


def _cal(band, band_noise=(0.03,) * 4, fit=(0.5,) * 4):
    return Calibration(names=("payload_kg",), units=("kg",), initial=(1.0,), fitted=(1.0,), sigma=(0.0,),
                       sigma_robust=(0.0,), fixed={}, fit_nrmse=tuple(fit), initial_nrmse=(1.0,) * 4,
                       windows_s=((0.0, 1.0),), weighted=True, evaluations=3, converged=True, message="ok",
                       wall_time_s=1.0, noise_nrmse=(0.01,) * 4, band_nrmse=tuple(band),
                       band_noise_nrmse=tuple(band_noise))


def _run(cal):
    per = lambda v: dict(zip(CORNERS, v))  # noqa: E731
    row = {"case": "c", "plant_key": "rigid", "calibration": cal,
           "wheels": {"model": per((0.02, 0.02, 0.02, 0.2)), "floor": per((0.1,) * 4), "linear": per((0.2,) * 4)}}
    return json.loads(to_json({"rows": [row]}))


def test_the_error_is_the_band_residual_beyond_the_band_noise(bench):
    rows = bench.wheels(_run(_cal((0.05, 0.05, 0.05, 0.3))))
    assert [o["error"] for o in rows[:3]] == pytest.approx([0.04] * 3)
    assert rows[3]["error"] == pytest.approx(math.sqrt(0.3 ** 2 - 0.03 ** 2))
    # the whole-band fit (0.5) is not what the fallback reads
    assert all(o["fit"] == pytest.approx(b) for o, b in zip(rows, (0.05, 0.05, 0.05, 0.3)))
    assert [o["over_floor"] for o in rows[:3]] == pytest.approx([0.2] * 3)
    assert math.isnan(rows[3]["model"])  # past HYBRID_LIMIT (0.25): corrected linearly


def test_a_run_without_band_figures_is_refused(bench):
    cal = dataclasses.replace(_cal(()), band_noise_nrmse=())
    with pytest.raises(SystemExit, match="band_nrmse"):
        bench.wheels(_run(cal))
