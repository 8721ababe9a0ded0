"""Tests of the digressive dampers (:func:`rigsim.mjcf.dampers.add_digressive_damping`), a plant feature
the calibrated model family (linear dampers) lacks.

Reference, independent of the code under test: the piecewise force law of a digressive damper,
written out here, F(v) = -c_s v for |v| <= knee and -sign(v) c_s (knee + ratio (|v| - knee)) beyond,
with the side's slope c_s from the XML's damper (truck_rig.xml: front 6 kN s/m, rear 10 kN s/m)
and, with a rebound ratio r, its definition: bump c_b = 2 c / (1 + r), rebound r c_b (mean c).
The force MuJoCo applies is read after ``mj_forward`` with the spring moving at a set rate: the
actuator forces on the spring tendon plus the tendon's own damping, -c_tendon dL/dt.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rigsim.mjcf import names
from rigsim.mjcf.build import build_spec
from rigsim.mjcf.dampers import BOUNDS, add_digressive_damping
from rigsim.mjcf.physics import static_equilibrium, tire_forces
from rigsim.mjcf.modes import modal_analysis
from rigsim.mjcf.stations import add_rebound_damping
from rigsim.mjcf.variant import TruckVariant

OBJ = mujoco.mjtObj
XML_DAMPING = {"fl": 6e3, "fr": 6e3, "rl": 1e4, "rr": 1e4}  # N s/m, truck_rig.xml
RATES = (-0.6, -0.3, -0.2, -0.15, -0.05, 0.0, 0.05, 0.15, 0.2, 0.3, 0.6)  # m/s, both sides of the 0.2 m/s knee


def _law(v: float, c_rebound: float, c_bump: float, knee: float, ratio: float) -> float:
    c = c_rebound if v > 0 else c_bump
    if abs(v) <= knee:
        return -c * v
    return -np.sign(v) * c * (knee + ratio * (abs(v) - knee))


def _spring_force(model, data, corner: str, rate: float) -> float:
    """The damper's force (N, + extending) with ``corner``'s spring extending at ``rate`` (m/s): the
    truck at its design pose, only the axle moving (down at ``rate``: the spring tendon is vertical)."""
    tendon = mujoco.mj_name2id(model, OBJ.mjOBJ_TENDON, names.spring_tendon(corner))
    axle = mujoco.mj_name2id(model, OBJ.mjOBJ_JOINT, names.axle_body(corner) + "_z")
    data.qpos[:] = model.qpos0
    data.qvel[:] = 0.0
    data.qvel[model.jnt_dofadr[axle]] = -rate
    mujoco.mj_forward(model, data)
    assert data.ten_velocity[tendon] == pytest.approx(rate, abs=1e-12)
    on = [a for a in range(model.nu)
          if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_TENDON and model.actuator_trnid[a, 0] == tendon]
    return float(data.actuator_force[on].sum() - model.tendon_damping[tendon] * data.ten_velocity[tendon])


@pytest.mark.parametrize("field,value", [("damper_digressive_knee_m_per_s", 0.04),
                                         ("damper_digressive_knee_m_per_s", 0.6),
                                         ("damper_digressive_ratio", 0.1), ("damper_digressive_ratio", 1.2),
                                         ("damper_digressive_ratio", float("nan"))])
def test_bad_values_name_the_field(field, value):
    spec = build_spec(TruckVariant(), pans="fixed")
    args = {"knee_m_per_s": 0.2, "ratio": 0.4,
            {"damper_digressive_knee_m_per_s": "knee_m_per_s", "damper_digressive_ratio": "ratio"}[field]: value}
    with pytest.raises(ValueError, match=f"vehicle.{field}") as err:
        add_digressive_damping(spec, "fl", **args)
    assert "\n" not in str(err.value)
    assert BOUNDS["damper_digressive_knee_m_per_s"][:3] == (0.05, 0.5, "m/s")
    assert BOUNDS["damper_digressive_ratio"][:3] == (0.2, 1.0, "1")


def test_corner_side_and_once():
    spec = build_spec(TruckVariant(), pans="fixed")
    with pytest.raises(ValueError, match="corner"):
        add_digressive_damping(spec, "front", 0.2, 0.4)
    add_digressive_damping(spec, "rr", 0.2, 0.4)
    with pytest.raises(ValueError, match="already digressive"):
        add_digressive_damping(spec, "rr", 0.2, 0.4)
    assert names.spring_digressive_actuator("rr", "cmp") == "spring_digressive_rr_cmp"
    with pytest.raises(ValueError, match="side"):
        names.spring_digressive_actuator("rr", "up")


@pytest.mark.parametrize("corner", names.CORNERS)
@pytest.mark.parametrize("rebound", [None, 3.0])
@pytest.mark.parametrize("knee,ratio", [(0.2, 0.4), (0.05, 0.2), (0.5, 1.0)])
def test_force_velocity_law(corner, rebound, knee, ratio):
    """The damper's force at rates on both sides of the knee, both directions, is the piecewise law,
    with the rebound damper's two slopes when it has one (applied first, as the module asks)."""
    spec = build_spec(TruckVariant(), pans="fixed")
    if rebound is not None:
        add_rebound_damping(spec, corner, rebound)
    add_digressive_damping(spec, corner, knee, ratio)
    model = spec.compile()
    data = mujoco.MjData(model)
    c = XML_DAMPING[corner]
    c_bump = c if rebound is None else 2 * c / (1 + rebound)
    c_rebound = c if rebound is None else rebound * c_bump
    for rate in RATES:
        expected = _law(rate, c_rebound, c_bump, knee, ratio)
        assert _spring_force(model, data, corner, rate) == pytest.approx(expected, rel=1e-12, abs=1e-9), rate


def test_other_corners_keep_their_linear_damper():
    spec = build_spec(TruckVariant(), pans="fixed")
    add_digressive_damping(spec, "fl", 0.1, 0.3)
    model = spec.compile()
    data = mujoco.MjData(model)
    for corner in ("fr", "rl", "rr"):
        assert _spring_force(model, data, corner, 0.5) == pytest.approx(-XML_DAMPING[corner] * 0.5, rel=1e-12)


@pytest.mark.parametrize("pans", ["slide", "mocap", "fixed"])
def test_rest_and_linearization_are_the_linear_dampers(pans):
    """At rest a damper does nothing: the truck rests as with linear dampers (all four tires loaded,
    same forces). The linearization about rest (centred differences through v = 0, where each
    one-sided element is at its kink and contributes half its slope, the two sides adding to the
    full one) gives the linear truck's modes and damping ratios."""
    linear = build_spec(TruckVariant(payload_kg=3640.0), pans=pans).compile()
    spec = build_spec(TruckVariant(payload_kg=3640.0), pans=pans)
    for corner in names.CORNERS:
        add_digressive_damping(spec, corner, 0.15, 0.3)
    model = spec.compile()
    data, d_linear = mujoco.MjData(model), mujoco.MjData(linear)
    static_equilibrium(model, data, pan_z_m=np.zeros(4))
    static_equilibrium(linear, d_linear, pan_z_m=np.zeros(4))
    loads = tire_forces(model, data)
    assert np.all(loads > 0) and loads == pytest.approx(tire_forces(linear, d_linear), rel=1e-12)
    if pans != "fixed":
        return
    for got, ref in zip(modal_analysis(model, data), modal_analysis(linear, d_linear)):
        assert got.name == ref.name
        assert got.frequency_hz == pytest.approx(ref.frequency_hz, rel=1e-4)
        assert got.damping_ratio == pytest.approx(ref.damping_ratio, rel=1e-3)
