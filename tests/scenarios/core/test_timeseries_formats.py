"""A run's time series in the formats test labs read: CSV, ASAM MDF4, NI TDMS, MTS RPC III.

Each file ``rigsim run --format`` writes is read back by the toolkit's reader of measured data
(:func:`rigsim.correction.io.measured.read_channels`) and compared with the run's own arrays: MDF4 and TDMS
carry float64 exactly, CSV to its 10 significant digits, RPC III to its int16 quantization (half
a step of the channel's full scale / 32767, the format's definition: MTS RPC III file format; its SCALE
header is text, so the step is known to ~1e-5).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from rigsim.correction.io.measured import read_channels
from rigsim.scenarios.core.config import ScenarioError, parse_scenario
from rigsim.scenarios.core.results import TIMESERIES_FORMATS, check_timeseries_format, write_run
from rigsim.scenarios.core.run import run

DOC = {"name": "f", "speed_kmh": 72.0, "duration_s": 0.5, "seed": 3, "lead_in_s": 0.5,
       "road": {"roughness": "high"}, "vehicle": {"payload_kg": 3640.0}}


@pytest.fixture(scope="module")
def result():
    return run(parse_scenario(DOC), "rig")


@pytest.mark.parametrize("fmt", list(TIMESERIES_FORMATS))
def test_every_format_reads_back_as_the_run(result, fmt, tmp_path):
    pytest.importorskip({"mf4": "asammdf", "tdms": "nptdms"}.get(fmt, "numpy"))
    paths = write_run(result, tmp_path, fmt=fmt)
    assert paths["timeseries"].name == "timeseries" + TIMESERIES_FORMATS[fmt]
    meta = json.loads(paths["result"].read_text())["timeseries"]
    assert meta["file"] == paths["timeseries"].name and meta["format"] == fmt
    back = read_channels(paths["timeseries"])
    names = result.column_names()
    assert list(back.data) == names[1:], list(back.data)[:5]
    np.testing.assert_allclose(back.time_s, result.t_s, rtol=0, atol=1e-9)
    col = iter(names[1:])
    for key, arr in result.signals.items():
        for i in range(arr.shape[1]):
            got, want = np.asarray(back.data[next(col)]), np.asarray(arr[:, i])
            if fmt in ("mf4", "tdms"):
                assert np.array_equal(got, want), key
            elif fmt == "csv":
                np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-300)
            else:  # int16 over each channel's full scale: half a step
                step = max(np.max(np.abs(want)), 1e-30) / 32767
                assert np.max(np.abs(got - want)) <= 0.5 * step * (1 + 1e-3), key  # the header's SCALE in text


def test_an_unknown_format_is_refused_before_any_run():
    with pytest.raises(ScenarioError, match="--format must be one of csv, mf4, tdms, rsp"):
        check_timeseries_format("parquet")
