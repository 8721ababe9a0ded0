"""``benchmarks/dyntrac_fit.py``: the fit's pieces, and the shipped DYNTRAC configuration inside the
physical ranges the fit declares (the fit itself runs minutes: ``--check`` re-measures it)."""

from __future__ import annotations


import numpy as np
import pytest

from rigsim.scenarios.core.config import load_scenario, paper_scenarios
from rigsim.scenarios.studies.paper.table import PAPER_TABLE2



@pytest.fixture(scope="module")
def fit(load_benchmark):
    return load_benchmark("dyntrac_fit")


def test_every_shipped_value_lies_in_its_range(fit):
    x = fit.shipped_values(paper_scenarios("dyntrac"))
    assert len(x) == len(fit.UNKNOWNS)
    for u, v in zip(fit.UNKNOWNS, x):
        assert u.lo <= v <= u.hi, u.name  # at a bound: the results page warns
        assert u.source  # every range names where it comes from


def test_the_shipped_cases_share_one_value_per_unknown(fit):
    """One rig, one waviness, one friction for the three cases; one level per roughness word."""
    cases = [load_scenario(p) for p in paper_scenarios("dyntrac")]
    assert len({(c.actuator["kp_per_m"], c.actuator["kdp_per_Pa"], c.road.waviness,
                 c.vehicle.spring_friction_rear_N, c.vehicle.spring_friction_front_N) for c in cases}) == 1
    assert cases[1].road.gd_n0_m3 == cases[2].road.gd_n0_m3  # both "high": the same road section
    assert cases[1].seed == cases[2].seed


def test_configured_puts_each_value_where_it_belongs(fit):
    path = paper_scenarios()[0]  # the medium case of the design rig
    x = np.array([30.0, 2e-8, 2.5, 5e-5, 3e-4, 4000.0, 650.0, 1300.0])
    sc = fit.configured(load_scenario(path), x, 20.0)
    assert sc.actuator["kp_per_m"] == 30.0 and sc.actuator["kdp_per_Pa"] == 2e-8
    assert sc.road.waviness == 2.5 and sc.road.gd_n0_m3 == 5e-5 and sc.road.roughness is None  # medium's level
    assert sc.vehicle.spring_friction_rear_N == 4000.0 and sc.vehicle.spring_friction_front_N == 2000.0
    assert sc.vehicle.axle_mass_front_kg == 650.0 and sc.vehicle.axle_mass_rear_kg == 1300.0
    assert sc.duration_s == 20.0
    high = fit.configured(load_scenario(paper_scenarios()[2]), x, 20.0)
    assert high.road.gd_n0_m3 == 3e-4


def test_targets_are_table_2_and_a_failed_run_counts_as_far_off(fit):
    paths = paper_scenarios("dyntrac")
    t = fit.targets(paths)
    assert t.tolist() == [PAPER_TABLE2[load_scenario(p).name][k] for p in paths for k in ("road", "rig", "corrected")]
    r = fit.relative_error(np.array([t[0] * 1.05, np.nan, *t[2:]]), t)
    assert r[0] == pytest.approx(np.log(1.05)) and r[1] == 1.0 and np.all(r[2:] == 0)


def _sim(fit, paths, scale=None, linear=None):
    """A :func:`simulate` vector: Table 2's numbers (times ``scale``), the linear correction at
    ``linear`` times a road-through-low-pass of 0.1."""
    nine = fit.targets(paths) * (1.0 if scale is None else scale)
    lin = np.ones(3) if linear is None else np.asarray(linear)
    return np.concatenate([[*nine[3 * i:3 * i + 3], 0.1 * lin[i], 0.1] for i in range(3)])


def test_table_1_asks_the_high_72_kmh_road_and_rig_within_3_percent(fit):
    paths = paper_scenarios("dyntrac")
    names = [load_scenario(p).name for p in paths]
    tol = fit.tolerances(paths)
    for i, name in enumerate(names):
        for j, col in enumerate(("road", "rig", "paper")):
            tight = name == "paper-high-72kmh-3640kg" and col != "paper"
            assert tol[3 * i + j] == (fit.TABLE1_GOAL if tight else fit.GOAL)


def test_residuals_are_in_units_of_each_goal(fit):
    paths = paper_scenarios("dyntrac")
    target, tol = fit.targets(paths), fit.tolerances(paths)
    assert np.allclose(fit.residuals(_sim(fit, paths), target, tol, 1.0), 0.0)
    scale = np.ones(9)
    scale[0], scale[7] = 1.05, 1.03  # medium road +5 %, high-72 rig +3 %: each at its goal
    r = fit.residuals(_sim(fit, paths, scale, linear=[1.02, 1.0, 0.98]), target, tol, 1.0)
    assert r[0] == pytest.approx(1.0) and r[7] == pytest.approx(1.0) and np.allclose(np.delete(r[:9], [0, 7]), 0)
    assert r[9] == pytest.approx(1.0) and r[10] == 0 and r[11] == pytest.approx(np.log(0.98) / np.log(1.02))
    assert np.all(fit.residuals(_sim(fit, paths, scale, linear=[1.5, 1, 1]), target, tol, 0.0)[9:] == 0)
    assert fit.linear_errors(_sim(fit, paths, linear=[1.02, 1.0, 0.98])) == pytest.approx([0.02, 0.0, -0.02])


def test_a_value_at_its_bound_is_flagged(fit):
    paths = paper_scenarios("dyntrac")
    x = fit.shipped_values(paths)
    x[0] = fit.UNKNOWNS[0].hi
    numbers, linear, values = fit.tables(paths, x, _sim(fit, paths, linear=[1.0, 1.1, 1.0]))
    assert values[0][3] == "at its bound" and values[2][3] == "inside"
    assert linear[1][3] == "+10.0 %" and numbers[7][5] == "+-3 % (Table 1 too)"
