"""Memory of a run: bounded by its records, not by its steps (the drive is made chunk by chunk).

The references are measured peaks (``tracemalloc``) of :func:`rigsim.scenarios.core.run.run`, against
the estimate :func:`rigsim.scenarios.core.memory.check_memory` refuses runs with.
"""

from __future__ import annotations

import tracemalloc

import numpy as np

from rigsim.scenarios.core import memory
from rigsim.scenarios.core.config import parse_scenario
from rigsim.scenarios.core.road_drive import RoadDrive
from rigsim.scenarios.core.rig import Rig
from rigsim.scenarios.core.run import run

DOC = {"name": "m", "speed_kmh": 120.0, "duration_s": 3.0, "seed": 5, "lead_in_s": 0.5,
       "road": {"roughness": "high"}, "vehicle": {"payload_kg": 3640.0}}


def _scenario(duration_s: float, timestep_s: float = 1e-4):
    return parse_scenario({**DOC, "duration_s": duration_s, "vehicle": {**DOC["vehicle"], "timestep_s": timestep_s}})


def _peak(scenario, mode: str = "road") -> tuple[int, object]:
    tracemalloc.start()
    try:
        result = run(scenario, mode)
        return tracemalloc.get_traced_memory()[1], result
    finally:
        tracemalloc.stop()


def test_a_run_does_not_hold_its_drive_at_the_step_rate():
    """Halving the time step doubles the steps (35 000 -> 70 000); a drive held at the step rate
    would add 9 floats (72 B) per step, ~2.5 MB here. The peak may not grow by a tenth of that."""
    coarse, _ = _peak(_scenario(3.0, 1e-4))
    fine, _ = _peak(_scenario(3.0, 5e-5))
    assert fine - coarse < 0.1 * 72 * 35_000, (coarse, fine)


def test_the_memory_estimate_bounds_the_measured_peak_and_is_not_vacuous():
    """check_memory's estimate (BASE_BYTES, BYTES_PER_STEP, BYTES_PER_OUTPUT) is at least the measured peak
    of rig and road runs of 2 and 8 s at 120 km/h, and at most four times it."""
    for mode in ("road", "rig"):
        for d in (2.0, 8.0):
            sc = _scenario(d)
            peak, result = _peak(sc, mode)
            estimate = (memory.BASE_BYTES + result.info["simulated_steps"] * memory.BYTES_PER_STEP
                        + result.t_s.size * memory.BYTES_PER_OUTPUT)
            assert peak <= estimate <= 4 * peak, (mode, d, peak, estimate)


def test_the_chunked_road_drive_is_the_whole_drive_bit_for_bit():
    """RoadDrive.chunk over any split equals the whole drive made at once (the run reads it in
    chunks; the studies that need it whole make it with RoadDrive.drive)."""
    source = Rig(_scenario(2.0), hydraulic=False).road_source()
    whole = source.drive()
    rng = np.random.default_rng(7)
    cuts = np.unique(np.concatenate(([0, source.n_steps], rng.integers(0, source.n_steps, 12))))
    z = np.concatenate([source.chunk(a, b)[0] for a, b in zip(cuts[:-1], cuts[1:])])
    v = np.concatenate([source.chunk(a, b)[1] for a, b in zip(cuts[:-1], cuts[1:])])
    t = np.concatenate([source.times(a, b) for a, b in zip(cuts[:-1], cuts[1:])])
    assert np.array_equal(z, whole.z_m) and np.array_equal(v, whole.v_mps) and np.array_equal(t, whole.t_s)
    assert isinstance(source, RoadDrive)
    for t_s in (-0.5, -1e-5, 0.0, 0.33333, 1.99995):  # first_step as Drive's searchsorted
        assert source.first_step(t_s) == whole.first_step(t_s) == int(np.searchsorted(whole.t_s, t_s))
