"""The paper's published numbers, kept as data: one home for them.

"Correction of dynamic wheel forces measured on road simulators": Table 1 (the high-roughness 72 km/h 3640 kg case: road test, DYNTRAC
test, the nonlinear and the linearized model of the rig) and Table 2 (road, DYNTRAC and DYNTRAC
corrected, for the three cases). Every report prints them beside the simulated values.
"""

from __future__ import annotations

from types import MappingProxyType

__all__ = ["PAPER_TABLE1", "PAPER_TABLE2"]

#: Table 2 of the paper: DLC of the road test, of DYNTRAC, and of DYNTRAC corrected, keyed by
#: the shipped scenario names (scenarios/data/paper/*.toml), DLC = std / mean (1).
PAPER_TABLE2 = MappingProxyType({
    "paper-medium-72kmh-6360kg": {"road": 0.0985, "rig": 0.0854, "corrected": 0.0994},
    "paper-high-48kmh-3640kg": {"road": 0.1912, "rig": 0.1497, "corrected": 0.1794},
    "paper-high-72kmh-3640kg": {"road": 0.2105, "rig": 0.1754, "corrected": 0.2139},
})

#: Table 1 of the paper (high roughness, 72 km/h, 3640 kg): road test, DYNTRAC test, the
#: nonlinear model of the rig, the linearized model.
PAPER_TABLE1 = MappingProxyType({"road_test": 0.2105, "rig_test": 0.1754, "nonlinear_model": 0.1748,
                                  "linearized_model": 0.1724})
