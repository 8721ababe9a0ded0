"""Numerics of the actuator model (no MuJoCo): parameters, equations, linearization, events.

Each expected value names its source: an analytic result (Merritt's orifice and compliance
equations, the paper's eq. 4) or a definition, never a number copied from a previous run.
"""

import ast
import dataclasses
import math
import pathlib

import numpy as np
import pytest

from rigsim.correction.output.eq4 import EQ4_PARAMETERS, eq4_coefficients_from
from rigsim.hydraulics import (STATE_NAMES, ActuatorParams, actuator_derivatives, actuator_force,
                               check_design_station, check_stable, eq4_parameters, equilibrium_activation,
                               events, linearization, loop_matrices, pack, unpack)
from rigsim.hydraulics.kernels import derivatives_array, force_array, step_euler
from rigsim.hydraulics.loop import frequency_response
from rigsim.hydraulics.model import (MPA, chamber_flows, orifice_root, orifice_root_slope, soft_clip,
                                     soft_clip_slope)
from rigsim.hydraulics.packing import FIELD_NAMES, NPACK

PKG = pathlib.Path(__file__).resolve().parents[2] / "hydraulics"


def default() -> ActuatorParams:
    """The default parameters, built inside each test (never at import: a construction that raises
    then fails the tests that use it, by name, instead of breaking the collection of the file)."""
    return ActuatorParams()


# --- project rules --------------------------------------------------------------------------
def _top(name: str) -> str:
    """The package a module name is in: rigsim's layers by their own name (``rigsim.scenarios.x``: ``scenarios``)."""
    parts = name.split(".")
    return parts[1] if parts[0] == "rigsim" and len(parts) > 1 else parts[0]


def _imported_modules(path):
    tree = ast.parse(path.read_text())
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(_top(a.name) for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(_top(node.module))
    return names


def test_only_the_bridge_imports_mujoco_and_nothing_imports_scenarios():
    # Project rule: exactly one thin bridge module imports mujoco; never import scenarios.
    sources = sorted(PKG.glob("*.py"))
    assert (PKG / "bridge.py") in sources
    for path in sources:
        mods = _imported_modules(path)
        assert "scenarios" not in mods, path.name
        assert ("mujoco" in mods) == (path.name == "bridge.py"), path.name


# --- parameters -------------------------------------------------------------------------------
def test_defaults_follow_dyntrac():
    # Paper: 156 kN actuators at 21 MPa, 380 lpm valves rated at 7 MPa drop, 15.2 cm stroke.
    p = default()
    assert p.piston_area_m2 * p.supply_pressure_Pa == pytest.approx(156e3, rel=1e-12)
    assert p.rated_flow_m3_s * 60e3 == pytest.approx(380.0, rel=1e-12)
    assert p.rated_valve_drop_Pa == 7e6
    assert p.stroke_m == pytest.approx(0.152)
    assert p.ti_s == 1.0
    assert 0.7e9 <= p.bulk_modulus_Pa <= 1.4e9


@pytest.mark.parametrize("field, value, needle", [
    ("kdp_per_Pa", -1e-9, "actuator.kdp_per_Pa must be >= 0, got -1e-09"),
    ("bulk_modulus_Pa", 0.0, "actuator.bulk_modulus_Pa must be > 0"),
    ("return_pressure_Pa", 22e6, "actuator.return_pressure_Pa must be below supply_pressure_Pa"),
    ("relief_pressure_Pa", 20e6, "actuator.relief_pressure_Pa must exceed supply_pressure_Pa"),
    ("stroke_m", math.nan, "actuator.stroke_m must be a number"),
    ("cavitation_min_fraction", 1.5, "actuator.cavitation_min_fraction must lie in [0, 1]"),
])
def test_validation_names_the_field(field, value, needle):
    with pytest.raises(ValueError) as err:
        default().replace(**{field: value})
    assert needle in str(err.value)


def test_params_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        default().kp_per_m = 1.0


def test_pack_roundtrip_and_slots():
    v = pack(default())
    assert v.shape == (NPACK,) and v.dtype == np.float64
    assert unpack(v) == default()
    # Every P_* slot constant points at the field of the same declaration position.
    import rigsim.hydraulics.packing as pk
    slots = sorted((getattr(pk, n), n) for n in dir(pk) if n.startswith("P_") and n not in
                   ("P_TAG", "P_NSTATE", "P_NPACK"))
    assert [s for s, _ in slots] == list(range(3, NPACK))
    assert v[pk.P_KDP] == default().kdp_per_Pa and v[pk.P_SUPPLY] == default().supply_pressure_Pa
    assert len(FIELD_NAMES) == NPACK - 3
    with pytest.raises(ValueError, match="not a packed ActuatorParams"):
        unpack(np.zeros(NPACK))


# --- valve and orifice ------------------------------------------------------------------------
def test_rated_flow_at_rated_drop():
    # Definition of the rating: full opening, 7 MPa across the valve = 3.5 MPa per land -> 380 lpm.
    p = default().replace(null_opening=0.0)
    prm = pack(p)
    p1 = p.supply_pressure_Pa - 3.5e6
    p2 = p.return_pressure_Pa + 3.5e6
    q1, q2 = chamber_flows(1.0, p1, p2, prm)
    assert q1 == pytest.approx(p.rated_flow_m3_s, rel=1e-12)
    assert -q2 == pytest.approx(p.rated_flow_m3_s, rel=1e-12)


def test_orifice_law_square_root_and_smooth_laminar_core():
    lam = 2e6
    # Exact square root outside the laminar core (Merritt's orifice equation).
    for dp in (2e6, 5e6, 2e7):
        assert orifice_root(dp, lam) == pytest.approx(math.sqrt(dp), rel=1e-15)
        assert orifice_root(-dp, lam) == pytest.approx(-math.sqrt(dp), rel=1e-15)
    # Value and slope continuous at the joint; finite slope 1.25/sqrt(lam) at zero drop.
    for side in (1.0, -1.0):
        a, b = orifice_root(side * lam * (1 - 1e-12), lam), orifice_root(side * lam * (1 + 1e-12), lam)
        assert a == pytest.approx(b, rel=1e-9)
    assert orifice_root_slope(lam * (1 - 1e-12), lam) == pytest.approx(0.5 / math.sqrt(lam), rel=1e-9)
    assert orifice_root_slope(0.0, lam) == pytest.approx(1.25 / math.sqrt(lam), rel=1e-15)


def test_command_clip_is_linear_then_bounded():
    assert soft_clip(0.5, 1.0) == 0.5 and soft_clip_slope(0.5, 1.0) == 1.0
    for u in (0.81, 1.0, 3.0, 100.0):
        assert 0.8 < soft_clip(u, 1.0) <= 1.0
        assert soft_clip(-u, 1.0) == -soft_clip(u, 1.0)
    assert soft_clip(0.8 + 1e-12, 1.0) == pytest.approx(0.8, abs=1e-11)


def test_merritt_coefficients_at_null():
    # Merritt ch. 5, critical-centre valve at null: Kq0 = kv sqrt((Ps - Pr)/2) per unit opening;
    # the smoothed null region of width w adds Kc0 = kv w / (4 sqrt((Ps - Pr)/2)).
    for w in (0.0, 0.01):
        p = default().replace(null_opening=w)
        lin = linearization(p, 0.0)
        kv = p.rated_flow_m3_s / math.sqrt(0.5 * p.rated_valve_drop_Pa)
        half = 0.5 * (p.supply_pressure_Pa - p.return_pressure_Pa)
        assert lin.spool == pytest.approx(0.0, abs=1e-12)
        assert lin.p1_Pa == pytest.approx(lin.p2_Pa, rel=1e-12)
        assert lin.kq_m3_s == pytest.approx(kv * math.sqrt(half), rel=1e-9)
        assert lin.kc_m3_s_Pa == pytest.approx(kv * w / (4 * math.sqrt(half)), rel=1e-9, abs=1e-20)
        assert lin.kce_m3_s_Pa == pytest.approx(lin.kc_m3_s_Pa + p.leakage_m3_s_Pa, rel=1e-12)


# --- chambers -------------------------------------------------------------------------------------
def test_continuity_with_closed_valve_matches_compliance_law():
    # Merritt ch. 2: dP/dt = beta/V (Q - A dx/dt). Closed valve (no null flow, no leakage, no
    # controller), pan moved 0.5 mm at constant speed: P1 - P10 = -beta ln(V1/V10) exactly, about
    # -beta A dx / V0 (the displaced volume over the chamber volume) for small dx.
    p = default().replace(null_opening=0.0, leakage_m3_s_Pa=0.0, kp_per_m=0.0, kdp_per_Pa=0.0)
    x = np.array([0.0, 0.0, 10.0, 10.0, 0.0])
    speed, dt, n = 0.05, 1e-6, 10_000
    for k in range(n):  # explicit midpoint (RK2) of the prescribed motion x_a = speed * t
        xa = speed * k * dt
        k1 = actuator_derivatives(0.0, x, (0.0, xa, speed), p)
        k2 = actuator_derivatives(0.0, x + 0.5 * dt * k1, (0.0, xa + 0.5 * dt * speed, speed), p)
        x = x + dt * k2
    dx = speed * n * dt
    v0 = p.mid_volume_m3
    beta, area = p.bulk_modulus_Pa, p.piston_area_m2
    exact1 = -beta * math.log((v0 + area * dx) / v0)
    exact2 = -beta * math.log((v0 - area * dx) / v0)
    assert (x[2] - 10.0) * MPA == pytest.approx(exact1, rel=1e-6)
    assert (x[3] - 10.0) * MPA == pytest.approx(exact2, rel=1e-6)
    linear = beta * area * dx / v0
    assert -(x[2] - 10.0) * MPA == pytest.approx(linear, rel=2 * area * dx / v0)
    assert x[0] == 0.0  # the spool never moved


def test_bulk_modulus_falls_near_cavitation_so_pressure_stays_above_floor():
    # Pull the pan hard (1 m/s) against a closed valve: the chamber that expands must approach
    # the cavitation floor without crossing it far (Euler at the simulator's dt = 1e-4 s).
    p = default().replace(null_opening=0.0, kp_per_m=0.0, kdp_per_Pa=0.0)
    prm = pack(p)
    x = np.array([0.0, 0.0, 10.0, 10.0, 0.0])
    lowest = 10.0
    for k in range(600):
        step_euler(x, 0.0, -0.0 - 1.0 * k * 1e-4, -1.0, prm, 1e-4, 1)
        lowest = min(lowest, x[3], x[2])
    # Hard floor (params docstring): cavitation pressure minus 1 % of the band, ~ absolute vacuum.
    hard_floor = (p.cavitation_pressure_Pa - 0.01 * p.cavitation_band_Pa) / MPA
    assert hard_floor <= lowest < p.cavitation_pressure_Pa / MPA
    assert lowest > -0.101325  # never below absolute vacuum
    assert events(x, p)["cavitation"]
    # ... and it recovers once the pan stops and the valve opens towards that chamber.
    q = p.replace(null_opening=0.05)
    step_euler(x, 0.0, -0.06, 0.0, pack(q), 1e-4, 2000)
    assert x[3] > 1.0


def test_force_is_area_times_pressure_difference_minus_friction():
    x = np.array([0.0, 0.0, 12.0, 5.0, 0.0])
    f = actuator_force(x, 0.1, default())
    assert f == pytest.approx(default().piston_area_m2 * 7e6 - default().friction_N_s_m * 0.1, rel=1e-14)


# --- equilibrium -----------------------------------------------------------------------------------
@pytest.mark.parametrize("load", [0.0, 15e3, 35e3, 45e3 + 500 * 9.81, -5e3])
def test_equilibrium_balances_load_and_is_a_rest_point(load):
    p = default()
    a = equilibrium_activation(p, load)
    assert (a[2] - a[3]) * MPA * p.piston_area_m2 == pytest.approx(load, rel=1e-9, abs=1e-6)
    dx = actuator_derivatives(0.0, a, (0.0, 0.0, 0.0), p)
    scale = np.array([1.0, 1.0, 1.0, 1.0, 1.0])
    assert np.all(np.abs(dx) < 1e-9 * scale)
    assert actuator_force(a, 0.0, p) == pytest.approx(load, rel=1e-9, abs=1e-6)


def test_equilibrium_refuses_a_load_beyond_stall():
    with pytest.raises(ValueError, match="load_N"):
        equilibrium_activation(default(), 1.01 * default().stall_force_N)


# --- reference vs compiled kernels ---------------------------------------------------------------
def test_compiled_kernels_match_reference():
    rng = np.random.default_rng(3)
    for p in (default(), default().replace(spool_hz=math.inf), default().replace(ti_s=math.inf)):
        prm = pack(p)
        for _ in range(200):
            x = np.array([rng.uniform(-1.2, 1.2), rng.uniform(-500, 500), rng.uniform(-0.5, 27),
                          rng.uniform(-0.5, 27), rng.uniform(-0.01, 0.01)])
            u = np.array([rng.uniform(-0.08, 0.08), rng.uniform(-0.08, 0.08), rng.uniform(-1, 1)])
            out = np.empty(5)
            derivatives_array(x, u, prm, out)
            ref = actuator_derivatives(0.0, x, u, p)
            np.testing.assert_allclose(out, ref, rtol=1e-13, atol=1e-300)
            assert force_array(x, u[2], prm) == pytest.approx(actuator_force(x, u[2], p), rel=1e-14)


# --- linearization and eq. 4 ------------------------------------------------------------------------
def test_eq4_structure_matches_the_paper():
    # Paper eq. 4: b0 = b1 = a0 = Ksv Kq Ke with Ke = Kp/Ap (Ti = 1 s), unit static gain.
    p = default()
    kt = 1.2e6
    num, den = eq4_coefficients_from(**eq4_parameters(p, kt))
    lin = linearization(p)
    k = lin.ksv * lin.kq_m3_s * p.kp_per_m / p.piston_area_m2
    assert num[0] == num[1] == den[4] == pytest.approx(k, rel=1e-15)
    kc = lin.kce_m3_s_Pa + p.kdp_per_Pa * lin.ksv * lin.kq_m3_s
    ap2, vf, beta = p.piston_area_m2 ** 2, 2 * p.mid_volume_m3, p.bulk_modulus_Pa
    assert den[3] == pytest.approx(den[4] + kc * kt / ap2, rel=1e-15)
    assert den[2] == pytest.approx(kc * p.friction_N_s_m / ap2 + vf * kt / (4 * beta * ap2) + 1, rel=1e-15)
    assert den[1] == pytest.approx(kc * p.pan_mass_kg / ap2 + vf * p.friction_N_s_m / (4 * beta * ap2), rel=1e-15)
    assert den[0] == pytest.approx(vf * p.pan_mass_kg / (4 * beta * ap2), rel=1e-15)
    assert np.polyval(num, 0.0) / np.polyval(den, 0.0) == 1.0


def test_two_chamber_linearization_reproduces_eq4_at_null():
    # Independent route: central-difference Jacobian of the nonlinear two-chamber equations
    # (static valve, tire to ground, unloaded so the valve sits at null) must give eq. 4's
    # frequency response; the mean-pressure mode decouples there.
    p = default().replace(spool_hz=math.inf)
    kt = 1e6
    a, b, c, _ = loop_matrices(p, kt, math.inf, load_N=0.0)
    num, den = eq4_coefficients_from(**eq4_parameters(p, kt))
    hz = np.geomspace(0.1, 200.0, 25)
    s = 2j * np.pi * hz
    h_eq4 = np.polyval(num, s) / np.polyval(den, s)
    h = frequency_response(a, b, c, hz)
    assert np.max(np.abs(h / h_eq4 - 1)) < 1e-6


# --- events --------------------------------------------------------------------------------------
def test_events_from_states():
    p = default()
    states = np.array([
        [0.0, 0.0, 10.0, 10.0, 0.0],   # nothing
        [0.95, 0.0, 10.0, 10.0, 0.0],  # spool beyond the clip's linear range
        [0.0, 0.0, 10.0, -0.08, 0.0],  # chamber 2 at the cavitation floor
        [0.0, 0.0, 25.5, 10.0, 0.0],   # chamber 1 above relief
    ])
    ev = events(states, p)
    assert ev["spool_saturation"].tolist() == [False, True, False, False]
    assert ev["cavitation"].tolist() == [False, False, True, False]
    assert ev["overpressure"].tolist() == [False, False, False, True]
    four = events(np.stack([states] * 4, axis=1), p)  # (samples, corners, 5)
    assert four["cavitation"].shape == (4, 4)
    assert STATE_NAMES[2] == "p1_MPa"


# --- design requirements of the defaults ---------------------------------------------------------
@pytest.mark.parametrize("kt", [0.9e6, 1.8e6])
@pytest.mark.parametrize("mass", [300.0, 600.0, math.inf])
def test_default_loop_meets_the_design_brief(kt, mass):
    # The design brief: stable with margin (here: 6 dB gain margin, and the explicit-Euler map at the
    # simulator's 1e-4 s) under a truck wheel (tire 0.9-1.8 MN/m, unsprung 300-600 kg), and a
    # -3 dB bandwidth of about 10-20 Hz (envelope: ignoring the narrow wheel-hop notch).
    report = check_stable(default(), kt, mass, gain_margin=2.0, dt_s=1e-4)
    assert 10.0 <= report.envelope_bandwidth_hz <= 20.0
    assert np.all(report.poles.real < 0)


def test_check_stable_explains_the_fix():
    p = default().replace(kdp_per_Pa=0.0)  # plain data: constructing an unstable set is allowed
    with pytest.raises(ValueError) as err:
        check_stable(p, 1e6, 450.0)
    msg = str(err.value)
    assert "unstable" in msg and "raise kdp_per_Pa" in msg and msg.count(". ") == 0



def test_check_design_station_checks_the_reference_wheel_station():
    # The defaults pass on their own station; an unstable set (no pressure feedback) is built
    # without complaint and refused by the check, with the same one-sentence explanation.
    check_design_station(default())
    p = default().replace(kdp_per_Pa=0.0)
    with pytest.raises(ValueError) as err:
        check_design_station(p)
    msg = str(err.value)
    assert f"{p.design_tire_N_per_m:.3g} N/m tire on a {p.design_load_mass_kg:.4g} kg" in msg
    assert "raise kdp_per_Pa" in msg and msg.count(". ") == 0 and "check_loop_on_init" not in msg


@pytest.mark.parametrize("kt, load, mass", [(1.2e6, 0.0, None), (1.8e6, 34.5e3, 700.0), (0.0, 0.0, None)])
@pytest.mark.parametrize("ti", [1.0, 0.25])
def test_eq4_parameters_feed_the_one_formula(kt, load, mass, ti):
    # eq4_parameters supplies exactly eq4_coefficients_from's keywords, from the linearization
    # at the load, and the formula keeps eq. 4's properties: T_a(0) = b0/a0 = 1,
    # b1 = Ksv Kq Kp / Ap, b0 = b1 / Ti, a4 = Vf mp / (4 beta_e Ap^2) (paper's eq. 4, Ti = 1 s).
    p = default().replace(ti_s=ti)
    args = eq4_parameters(p, kt, load, mass_kg=mass)
    assert set(args) == set(EQ4_PARAMETERS)
    lin = linearization(p, load)
    mp = p.pan_mass_kg if mass is None else mass
    assert args["mass_kg"] == mp and args["tire_N_per_m"] == kt and args["ti_s"] == ti
    assert args["kc_m3_s_Pa"] == lin.kce_m3_s_Pa and args["bulk_modulus_Pa"] == lin.beta_e_Pa
    num, den = eq4_coefficients_from(**args)
    ap = p.piston_area_m2
    assert num[0] == pytest.approx(lin.ksv * lin.kq_m3_s * p.kp_per_m / ap, rel=1e-14)
    assert num[1] == pytest.approx(num[0] / ti, rel=1e-14)
    assert den[0] == pytest.approx(lin.vf_m3 * mp / (4 * lin.beta_e_Pa * ap ** 2), rel=1e-14)
    assert np.polyval(num, 0.0) / np.polyval(den, 0.0) == pytest.approx(1.0, rel=1e-14)


def test_tire_stiffness_is_checked_by_the_formula_only():
    # One rule (rigsim.correction.output.eq4): tire_N_per_m >= 0; eq4_parameters passes the value through.
    with pytest.raises(ValueError, match="tire_N_per_m must be >= 0"):
        eq4_coefficients_from(**eq4_parameters(default(), -1.0))


def test_params_are_plain_data_and_the_stability_check_is_separate():
    # ActuatorParams only validates values: a set without pressure feedback constructs (no
    # stability check runs on construction); rigsim.hydraulics.loop.check_design_station refuses it,
    # naming the gain to change. (Import circles are tested project-wide in tests/test_layers.py.)
    from rigsim.hydraulics.loop import check_design_station

    p = default().replace(kdp_per_Pa=0.0)
    assert p.kdp_per_Pa == 0.0
    with pytest.raises(ValueError, match="raise kdp_per_Pa"):
        check_design_station(p)
    check_design_station(default())  # the defaults pass
