"""Rig-test mode: the full truck on four hydraulic actuators (scenarios/core/rig.py).

References: static force balance (weight of truck and pans), the paper's finding that the
rig's DLC lies below the road's (Table 1 and 2: 13-22 % below), determinism, and MuJoCo's
callback registry being empty outside a run.
"""

from __future__ import annotations

import dataclasses
from types import MappingProxyType

import mujoco
import numpy as np
import pytest

from rigsim.hydraulics.bridge import hydraulic_callbacks
from rigsim.hydraulics.params import STATE_NAMES
from rigsim.mjcf.names import CORNERS
from rigsim.mjcf.physics import RigIndex
from rigsim.scenarios.cli.main import main
from rigsim.scenarios.core.config import ScenarioError, load_scenario, paper_scenarios, parse_scenario
from rigsim.scenarios.core.rig import Rig
from rigsim.scenarios.core.run import run
from rigsim.scenarios.core.watch import SimulationError

SHORT = {
    "name": "rig-short",
    "speed_kmh": 72.0,
    "duration_s": 2.0,
    "lead_in_s": 1.0,
    "seed": 3,
    "road": {"roughness": "C"},
}


def _callbacks_clear() -> bool:
    return all(
        getter() is None for getter in (mujoco.get_mjcb_act_dyn, mujoco.get_mjcb_act_gain, mujoco.get_mjcb_act_bias)
    )


def _p_index(name):
    return STATE_NAMES.index(name)


def test_rest_pressures_carry_tire_load_and_pan_weight_and_stay():
    rig = Rig(parse_scenario(SHORT))
    params, model = rig.params, rig.model
    data = rig.rest_state()
    idx = RigIndex.of(model)
    tire = data.actuator_force[idx.tire_actuator].copy()
    g = 9.81
    # Reference: the pan's free-body balance, A (P1 - P2) = tire force + pan weight.
    expected = tire + params.pan_mass_kg * g
    hyd = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"hyd_{c}") for c in CORNERS]

    def pressure_force():
        out = []
        for a in hyd:
            adr = model.actuator_actadr[a]
            p1 = data.act[adr + _p_index("p1_MPa")] * 1e6
            p2 = data.act[adr + _p_index("p2_MPa")] * 1e6
            out.append(params.piston_area_m2 * (p1 - p2))
        return np.array(out)

    np.testing.assert_allclose(pressure_force(), expected, rtol=5e-3)
    # One second at rest with the drive at zero: the pans stay at mid-stroke.
    with hydraulic_callbacks(model):
        mujoco.mj_step(model, data, 10_000)
    assert np.max(np.abs(data.qpos[idx.pan_qpos])) < 1e-5
    np.testing.assert_allclose(pressure_force(), expected, rtol=5e-3)
    assert _callbacks_clear()


@pytest.fixture(scope="module")
def paper_runs():
    """The three paper cases, 12 s each (road and rig), to keep the suite quick."""
    out = {}
    for path in paper_scenarios():
        s = dataclasses.replace(load_scenario(path), duration_s=12.0)
        out[s.name] = (run(s, "road"), run(s, "rig"))
    return out


def test_rig_dlc_below_road_dlc_in_all_paper_cases(paper_runs):
    """The paper's DYNTRAC DLCs were 13-22 % below the road's (Tables 1-2); the simulated
    rig must attenuate too, and not absurdly (between 5 % and 40 % below)."""
    for name, (road, rig) in paper_runs.items():
        d_road = road.summary()["dlc_mean"]
        d_rig = rig.summary()["dlc_mean"]
        print(f"{name}: road DLC {d_road:.4f}, rig DLC {d_rig:.4f} ({100 * (d_rig / d_road - 1):+.1f} %)")
        assert 0.60 * d_road < d_rig < 0.95 * d_road
        # The static load is the same on the road and on the rig.
        for c in CORNERS:
            assert rig.statistics()[c]["mean_force_N"] == pytest.approx(road.statistics()[c]["mean_force_N"], rel=2e-3)


def test_rig_run_carries_hydraulic_signals(paper_runs):
    road, rig = next(iter(paper_runs.values()))
    for key in ("spool", "p1_Pa", "p2_Pa", "pan_m", "tire_force_N", "profile_m"):
        assert rig.signals[key].shape == (rig.t_s.size, 4), key
    # The pan follows the drive with a lag: close but not equal (road mode: equal).
    err = rig.signals["pan_m"] - rig.signals["profile_m"]
    assert 0 < np.sqrt(np.mean(err**2)) < 0.5 * np.std(rig.signals["profile_m"])
    # Pressures physical: above the cavitation floor, below the relief.
    assert rig.signals["p1_Pa"].min() > -0.1e6 and rig.signals["p1_Pa"].max() < 25e6
    assert _callbacks_clear()


def test_two_rig_runs_in_one_process_are_bit_identical():
    s = parse_scenario(SHORT)
    a = run(s, "rig")
    b = run(s, "rig")
    for key in a.signals:
        assert np.array_equal(a.signals[key], b.signals[key]), key
    assert _callbacks_clear()


def test_unstable_parameters_refused_before_the_run(tmp_path, capsys):
    """Actuator parameters are plain data (parse_scenario accepts them); the rig refuses
    them when it is built, before any step, naming the parameter to change."""
    scenario = parse_scenario(dict(SHORT, actuator={"kdp_per_Pa": 0.0}))
    with pytest.raises(ScenarioError, match="kdp_per_Pa"):
        Rig(scenario)
    path = tmp_path / "bad.toml"
    path.write_text(
        'name = "bad"\nspeed_kmh = 72.0\nduration_s = 2.0\n[road]\nroughness = "C"\n[actuator]\nkdp_per_Pa = 0.0\n'
    )
    out = tmp_path / "out"
    assert main(["run", str(path), "--mode", "rig", "--out", str(out), "--quiet"]) == 2
    assert "kdp_per_Pa" in capsys.readouterr().err
    assert not out.exists()


def test_unstable_plant_caught_by_the_plant_check_and_callbacks_removed():
    """Parameters that pass the design-station check (here it is skipped) are refused by the
    linearization of the whole plant before any step is taken."""
    s = dataclasses.replace(parse_scenario(SHORT), actuator=MappingProxyType({"kdp_per_Pa": 0.0}))
    rig = Rig(s, check_stability=False)
    with pytest.raises(ScenarioError, match=r"unstable: pole .* Hz"):
        rig.check_stable()
    assert _callbacks_clear()


@pytest.mark.parametrize("change", [{"kdp_per_Pa": 0.0}, {"spool_hz": 40.0}])
def test_plant_check_catches_known_unstable_loops(change):
    """Both instabilities the issue names: no pressure feedback, and a servovalve much slower
    than the hydraulic mode (40 Hz against ~110 Hz), are refused by the plant check."""
    s = dataclasses.replace(parse_scenario(SHORT), actuator=MappingProxyType(change))
    with pytest.raises(ScenarioError, match="unstable"):
        Rig(s, check_stability=False).check_stable()
    assert _callbacks_clear()


@pytest.mark.parametrize("mode", ["road", "rig"])
def test_mujoco_warning_during_a_run_is_an_error_with_its_time(monkeypatch, tmp_path, mode):
    """A NaN in the drive at t = 1.5 s: MuJoCo warns (bad ctrl) and the run stops with a
    SimulationError naming the 10 ms window of simulated time that holds the first step fed the
    bad value (warnings are checked every 10 ms); no callbacks remain. The rig test holds x_ref
    at mid-step of the step from 1.5 s; the road test moves the pan at its mean velocity over a
    step, (z_k+1 - z_k) / dt, so the step ending at 1.5 s already carries it."""
    from rigsim.scenarios.core.drive import Drive

    real = Rig.road_source

    def poisoned(self):
        d = real(self).drive()  # a Drive reads like the RoadDrive a run gets (chunk, times, ...)
        z, held = d.z_m.copy(), d.held_m.copy()  # road mode reads z_m, rig mode the held values
        z[np.searchsorted(d.t_s, 1.5), 0] = held[np.searchsorted(d.t_s, 1.5), 0] = np.nan
        out = object.__new__(Drive)  # Drive refuses NaN; bypass its check to poison the run
        for name, value in (("t_s", d.t_s), ("z_m", z), ("v_mps", d.v_mps), ("corners", d.corners),
                            ("held_m", held)):
            object.__setattr__(out, name, value)
        return out

    monkeypatch.setattr(Rig, "road_source", poisoned)
    monkeypatch.chdir(tmp_path)
    window = r"1\.4900 s and t = 1\.5000 s" if mode == "road" else r"1\.5000 s and t = 1\.5100 s"
    with pytest.raises(SimulationError, match=r"between t = " + window):
        run(parse_scenario(SHORT), mode)
    assert _callbacks_clear()
    # MuJoCo's default handler would have written MUJOCO_LOG.TXT into the working folder.
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
    assert mujoco.get_mju_user_warning() is None


@pytest.mark.parametrize("mode", ["road", "rig"])
def test_pose_track_follows_the_run(mode):
    """Poses recorded for the 3D view (rig mode: from the rollout states) put each pan exactly
    where the run's pan displacement says, at 50 Hz from t = 0."""
    r = run(parse_scenario(SHORT), mode, pose_rate_hz=50.0)
    track = r.poses
    assert track.t_s[0] == 0.0 and np.allclose(np.diff(track.t_s), 0.02)
    i = track.bodies.index("pan_fl")
    rows = np.searchsorted(r.t_s, track.t_s)
    assert np.array_equal(track.position_m[:, i, 2], r.signals["pan_m"][rows, 0])
    chassis = track.bodies.index("chassis")
    assert np.ptp(track.position_m[:, chassis, 2]) > 1e-3  # the truck moves


def test_hydraulic_events_counted_chunk_by_chunk_are_those_of_the_whole_record():
    """A rig whose valve is cut to 40 l/min saturates its spool on the high-roughness road at
    72 km/h. The run counts the events chunk by chunk (0.1 s rollouts) and keeps only spool and
    pressures; the reference is rigsim.hydraulics.events.events applied once to the whole recorded
    spool and pressure record (the other states are zero: the events do not read them)."""
    from rigsim.hydraulics.events import events

    doc = {**SHORT, "duration_s": 3.0, "road": {"roughness": "high"}, "actuator": {"rated_flow_m3_s": 40e-3 / 60}}
    sc = parse_scenario(doc)
    rig = Rig(sc)
    rec = rig.run(rig.road_source(), rate_hz=sc.output_rate_hz)
    assert rec.events, "the cut valve should saturate"
    states = np.zeros(rec.tire_force_N.shape + (len(STATE_NAMES),))
    states[..., STATE_NAMES.index("spool")] = rec.hydraulic["spool"]
    states[..., STATE_NAMES.index("p1_MPa")] = rec.hydraulic["p1_Pa"] / 1e6
    states[..., STATE_NAMES.index("p2_MPa")] = rec.hydraulic["p2_Pa"] / 1e6
    expected = {}
    for name, mask in events(states, rig.params).items():
        per = {c: {"samples": int(np.sum(mask[:, i])), "first_time_s": float(rec.t_s[np.argmax(mask[:, i])])}
               for i, c in enumerate(CORNERS) if np.any(mask[:, i])}
        if per:
            expected[name] = per
    assert rec.events == expected


@pytest.mark.parametrize("corner", CORNERS)
def test_a_step_on_one_corners_drive_moves_that_pan_and_no_other(corner):
    """A 5 mm step in one post's x_ref, the other three at zero: that pan follows (its position
    loop settles within ~0.2 s, validate's Figure 7), the others stay put but for what the truck
    passes between them (under 10 % of the step). A drive wired to the wrong post fails here by
    name; the rms bounds of the road tests barely notice a swap of fl and fr."""
    from rigsim.scenarios.core.drive import Drive, step_drive

    sc = parse_scenario({**SHORT, "duration_s": 0.6})
    rig = Rig(sc)
    step = step_drive(0.6, rig.dt_s, 5e-3, 0.1)
    i = CORNERS.index(corner)
    z = np.zeros_like(step.z_m)
    z[:, i] = step.z_m[:, i]
    rec = rig.run(Drive(step.t_s, z, np.zeros_like(z)), rate_hz=sc.output_rate_hz)
    moved = rec.pan_m[-1] - rec.pan_m[0]
    assert moved[i] == pytest.approx(5e-3, rel=0.2), moved
    others = np.delete(moved, i)
    assert np.max(np.abs(others)) < 0.1 * 5e-3, moved
