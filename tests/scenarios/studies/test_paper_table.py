"""The Table 2 analogue's ceiling column and its over-correction marks, and the paper cases'
two configurations (``rigsim paper --rig dyntrac|design``)."""

from __future__ import annotations

import pytest

from rigsim.scenarios.core.config import PAPER_CONFIGURATIONS, ScenarioError, load_scenario, paper_scenarios
from rigsim.scenarios.studies.paper.compute import PaperResult
from rigsim.scenarios.studies.paper.table import PAPER_TABLE2


def _result(corrected_paper: dict[str, float], ceiling: float) -> PaperResult:
    rows = []
    for name, ref in PAPER_TABLE2.items():
        rows.append({"case": name, "paper": dict(ref), "dlc_road": 0.2, "dlc_rig": 0.17,
                     "dlc_corrected_paper": corrected_paper[name], "dlc_road_lowpassed_paper": ceiling,
                     "dlc_corrected": 0.199, "dlc_road_lowpassed": 0.198, "nrmse_corrected": 0.1})
    result = PaperResult(cases=(), noise_N=100.0)
    object.__setattr__(result, "_rows", rows)
    return result


def _line(table: str, name: str) -> str:
    return next(line for line in table.splitlines() if line.startswith(name))


def test_the_ceiling_is_printed_and_a_value_above_it_is_marked():
    names = list(PAPER_TABLE2)
    table = _result({names[0]: 0.181, names[1]: 0.179, names[2]: 0.18}, ceiling=0.18).table()
    assert "ceiling" in table.splitlines()[0]
    assert "0.1810^(" in _line(table, names[0])  # above the road through T_F: over-corrected
    assert "0.1790 (" in _line(table, names[1])
    assert "0.1800 (" in _line(table, names[2])  # at the ceiling is not above it
    assert all(" 0.1800 " in _line(table, n) for n in names)  # the ceiling column


def test_the_papers_own_over_corrections_are_marked():
    # The paper's Table 2: corrected 0.0994 > road 0.0985 and 0.2139 > 0.2105 (above the road itself,
    # so above any ceiling of a low-pass); 0.1794 < 0.1912.
    names = list(PAPER_TABLE2)
    table = _result(dict.fromkeys(names, 0.1), ceiling=0.2).table()
    assert "(0.0994^)" in _line(table, names[0])
    assert "(0.1794 )" in _line(table, names[1])
    assert "(0.2139^)" in _line(table, names[2])


def test_both_configurations_hold_the_same_three_cases():
    design, fitted = paper_scenarios(), paper_scenarios("dyntrac")
    assert [p.name for p in fitted] == [p.name for p in design]
    for f, d in zip(fitted, design):
        a, b = load_scenario(f), load_scenario(d)
        assert (a.name, a.speed_kmh, a.seed, a.vehicle.payload_kg) == (b.name, b.speed_kmh, b.seed, b.vehicle.payload_kg)
        assert b.actuator == {} and b.road.roughness in ("medium", "high")  # the design rig: defaults, ISO words
        assert a.actuator["kp_per_m"] > 0 and a.road.gd_n0_m3 is not None  # the fitted values
    assert set(PAPER_CONFIGURATIONS) == {"dyntrac", "design"}


def test_an_unknown_configuration_is_refused_naming_the_choices():
    with pytest.raises(ScenarioError, match="configuration must be one of"):
        paper_scenarios("fast")


def test_the_cli_takes_the_configuration():
    from rigsim.scenarios.cli.main import build_parser

    p = build_parser()
    assert p.parse_args(["paper", "--out", "x"]).rig == "dyntrac"  # the rig that gives the paper's Table 2
    assert p.parse_args(["paper", "--out", "x", "--rig", "design"]).rig == "design"


def test_the_commands_offer_exactly_the_shipped_configurations():
    """The CLI lists the choices literally (importing the scenarios for ``rigsim --help`` would load the
    simulator): they must stay those of PAPER_CONFIGURATIONS."""
    from rigsim.scenarios.cli.main import build_parser

    p = build_parser()
    sub = next(a for a in p._actions if a.dest == "command" or a.__class__.__name__ == "_SubParsersAction")
    for command, default in (("paper", "dyntrac"), ("validate", "design")):
        rig = next(a for a in sub.choices[command]._actions if a.dest == "rig")
        assert set(rig.choices) == set(PAPER_CONFIGURATIONS) and rig.default == default
