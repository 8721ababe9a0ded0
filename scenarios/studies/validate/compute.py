"""``rigsim validate``: the paper's linearized actuator model checked against the multibody plant.

Three routes to the actuator transfer function ``T_a = X_a / X_p`` (drive signal x_ref of
``hyd_<c>`` to pan displacement, qpos of ``pan_<c>_z``) of the truck on the DYNTRAC rig:

1. **analytic**: the paper's eq. 4 (:func:`correction.transfer.eq4_transfer_function`) with
   Merritt's Kq, Kc from :func:`hydraulics.linearization` at each wheel station's static load
   and that station's tire stiffness;
2. **numerical**: the whole closed-loop MuJoCo plant (truck, pans, four hydraulic actuators,
   all states) linearized at static rest with ``mujoco.mjd_transitionFD`` (leaf-spring dry
   friction off), ``H(f) = C (exp(j 2 pi f dt) I - A)^-1 B``, all 4 x 4 paths;
3. **identified**: the nonlinear rig driven by independent road-like random drives on all four
   wheels, the MIMO H1 estimate with its coherence (:mod:`correction.identify`) and a fitted
   stable rational transfer function per wheel.

Then the paper's Figure 7 (step responses, nonlinear against linear) and Table 1 (DLC of the
road test, the rig test and the truck driven by the linearized actuator model) for the
high-roughness, 72 km/h, 3640 kg case. :func:`validate` computes everything;
:func:`write_report` writes ``validate.json``, the PNGs and ``report.md``.

This is the module where :mod:`mjcf`, :mod:`hydraulics` and :mod:`correction` meet.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import dataclasses
import math
import os
import pathlib
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import control
import mujoco
import numpy as np
from scipy import signal

from correction.identify import fit_rational, h1_estimate
from correction.transfer import (apply_transfer_function, bandwidth_hz, describe_roots,
                                 eq4_transfer_function, state_space_frequency_response,
                                 transfer_bandwidth_hz)
from hydraulics.bridge import hydraulic_callbacks
from hydraulics.events import event_summary, events as hydraulic_events
from hydraulics.linearization import linearization
from hydraulics.loop import loop_matrices
from hydraulics.model import land_coefficient, orifice_root
from hydraulics.packing import pack
from hydraulics.params import ActuatorParams
from mjcf.build import CORNERS
from mjcf.physics import RigIndex, friction_disabled
from scenarios.core.config import Scenario, ScenarioError, load_scenario, paper_scenarios
from scenarios.studies.paper.command import PAPER_TABLE1  # the paper's Table 1, one home for its numbers
from scenarios.core.rig import actuator_params, rest_state, rig_model

__all__ = [
    "PAPER_TABLE1", "PlantLinearization", "table1_scenario_path", "linearize_plant",
    "route1_models", "identification_drive", "run_rig_drive", "identify", "validate",
    "add_parser", "cmd_validate",
]

#: Frequency range of the Bode plots, Hz (issue 3).
BODE_RANGE_HZ = (0.1, 50.0)
#: Upper end of the FRF comparisons against route 2, Hz (issue 3).
COMPARE_MAX_HZ = 30.0
#: Coherence above which an identified FRF point counts (issue 3).
COHERENCE_MIN = 0.95
#: Goals of issue 3: route 3 against route 2, and the linearized-model DLC against the rig's.
GOAL_FRF_DB, GOAL_FRF_DEG, GOAL_TABLE1_PCT = 0.5, 5.0, 2.0
#: Step sizes of the Figure 7 analogue, m (issue 3: about 1 mm and 1 cm).
STEP_SMALL_M, STEP_LARGE_M = 1.0e-3, 1.0e-2
#: Identification drive: RMS displacement (the high-roughness 72 km/h drive has 9.5 mm RMS),
#: corner frequency above which the displacement PSD falls as 1/f^2 (a road's white
#: velocity spectrum), band edges, seed.
IDENT_RMS_M = 9.5e-3
IDENT_CORNER_HZ = 1.0
IDENT_BAND_HZ = (0.05, 60.0)
IDENT_SEED = 20240604
#: Rate at which the identification record is kept, Hz (the drive has nothing above 60 Hz).
IDENT_RATE_HZ = 1000.0
#: Fade-in of the identification drive and what is dropped before the analysis, s.
IDENT_FADE_S, IDENT_SKIP_S = 1.0, 3.0
#: Orders of the rational fit of route 3 (numerator, denominator): six poles for eq. 4's four
#: plus the spool's pair, three zeros for eq. 4's one and the vehicle's dips.
FIT_ORDERS = (3, 6)
#: Duration of the step runs and the time of the step, s.
STEP_RUN_S, STEP_AT_S = 2.0, 0.05

ProgressFn = Callable[[str], None]


def _say(progress: ProgressFn | None, text: str) -> None:
    if progress is not None:
        progress(text)


def table1_scenario_path() -> pathlib.Path:
    """The shipped scenario of the paper's Table 1 (high roughness, 72 km/h, 3640 kg)."""
    for p in paper_scenarios():
        if p.name == "high_72kmh_3640kg.toml":
            return p
    raise FileNotFoundError("scenarios/data/paper/high_72kmh_3640kg.toml is missing")  # pragma: no cover


def _scenario(path, duration_s: float | None, *, friction: bool = True) -> Scenario:
    """The scenario at ``path``, optionally with another duration or without leaf-spring friction."""
    sc = load_scenario(path)
    if duration_s is not None:
        sc = dataclasses.replace(sc, duration_s=float(duration_s))
    if not friction:
        sc = dataclasses.replace(sc, vehicle=dataclasses.replace(
            sc.vehicle, spring_friction_front_N=0.0, spring_friction_rear_N=0.0))
    return sc


# --------------------------------------------------------------------------------------------
# Route 2: the whole plant linearized by MuJoCo.
@dataclass(frozen=True)
class PlantLinearization:
    """Discrete-time linearization of the closed-loop rig plant about static rest.

    ``x[k+1] = A x[k] + B u[k]`` with MuJoCo's state ``(qpos, qvel, act)`` (deviations),
    ``u`` the four drive signals x_ref (m, ``hyd_<c>`` in :data:`CORNERS` order).

    Attributes
    ----------
    a : numpy.ndarray, (n, n)
    b : numpy.ndarray, (n, 4), per m of drive
    c : numpy.ndarray, (8, n)
        Rows 0-3: pan displacement (m), rows 4-7: pan velocity (m/s), in corner order.
    dt_s : float, s
        Time step of the map (the model's).
    kt_N_per_m : numpy.ndarray, (4,), N/m
        Tire stiffness of each wheel station (the eq. 4 load).
    load_N : numpy.ndarray, (4,), N
        Static actuator load: tire force plus pan weight.
    unsprung_kg : numpy.ndarray, (4,), kg
        Half the mass of the axle over each pan.
    """

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    dt_s: float
    kt_N_per_m: np.ndarray
    load_N: np.ndarray
    unsprung_kg: np.ndarray

    def frequency_response(self, f_hz) -> np.ndarray:
        """Complex 4 x 4 ``x_a / x_ref`` at ``f_hz`` (Hz), shape (nf, 4, 4) [output, input]."""
        return state_space_frequency_response(self.a, self.b, self.c[:4], f_hz, self.dt_s)

    def poles(self) -> np.ndarray:
        """Continuous-time equivalents ``log(mu) / dt`` of the discrete poles, rad/s."""
        return np.log(np.linalg.eigvals(self.a).astype(complex)) / self.dt_s

    def siso_zeros(self, corner: int) -> np.ndarray:
        """Continuous-time equivalents (rad/s) of the transmission zeros of one wheel's own path
        that do not (nearly, within 1 %) cancel a pole."""
        sys_d = control.ss(self.a, self.b[:, [corner]], self.c[[corner]], 0.0, self.dt_s)
        z = np.asarray(sys_d.zeros(), dtype=complex)
        z = z[np.abs(z) > 1e-12]
        zc = np.log(z) / self.dt_s
        pc = self.poles()
        keep = [s for s in zc if np.min(np.abs(pc - s)) > 0.01 * max(abs(s), 1.0)]
        return np.array(keep)


def linearize_plant(scenario: Scenario, params: ActuatorParams | None = None, eps: float = 1e-6
                    ) -> PlantLinearization:
    """Route 2: ``mjd_transitionFD`` of the truck on the hydraulic rig at static rest.

    The hydraulic callbacks are installed and leaf-spring dry friction is disabled (it locks
    the springs at rest and has no derivative) for the linearization only.

    Parameters
    ----------
    scenario : Scenario
        Truck variant and actuator overrides.
    params : ActuatorParams, optional
        Default: the scenario's.
    eps : float
        Finite-difference step of ``mjd_transitionFD`` (centred), in the state's units.
    """
    params = actuator_params(scenario) if params is None else params
    model = rig_model(scenario, params)
    data = rest_state(model, params)
    idx = RigIndex.of(model)
    hyd = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"hyd_{c}") for c in CORNERS])
    n = 2 * model.nv + model.na
    a = np.zeros((n, n))
    b = np.zeros((n, model.nu))
    with hydraulic_callbacks(model), friction_disabled(model):
        mujoco.mj_forward(model, data)
        mujoco.mjd_transitionFD(model, data, eps, True, a, b, None, None)
    c = np.zeros((8, n))
    c[np.arange(4), idx.pan_dof] = 1.0  # no quaternions: the qpos tangent is qpos itself
    c[4 + np.arange(4), model.nv + idx.pan_dof] = 1.0
    tire = data.actuator_force[idx.tire_actuator]
    g = -model.opt.gravity[2]
    pan_body = model.jnt_bodyid[[model.actuator_trnid[i, 0] for i in hyd]]
    load = tire + model.body_mass[pan_body] * g
    kt = -model.actuator_biasprm[idx.tire_actuator, 1]
    axle = {c_: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY,
                                  "front_axle" if c_.startswith("f") else "rear_axle") for c_ in CORNERS}
    unsprung = np.array([0.5 * model.body_mass[axle[c_]] for c_ in CORNERS])
    return PlantLinearization(a=a, b=b[:, hyd].copy(), c=c, dt_s=float(model.opt.timestep),
                              kt_N_per_m=np.asarray(kt, float), load_N=np.asarray(load, float),
                              unsprung_kg=unsprung)


def _modal_simulate(a, b, c, u, *, diagonal: bool) -> np.ndarray:
    """Run ``x[k+1] = A x[k] + B u[k]``, ``y[k] = C x[k]`` from rest on ``u`` (N, m) by modes.

    Each eigenvalue of ``A`` is a first-order recursive filter (``scipy.signal.lfilter``, C
    speed): minutes at 10 kHz take a second or two. ``diagonal``: output row ``i`` sees only
    input ``i % m`` (each wheel driven by its own path only); otherwise all inputs.
    """
    lam, v = np.linalg.eig(a)
    cv = c @ v
    wb = np.linalg.solve(v, b)
    n_out, m = c.shape[0], b.shape[1]
    y = np.zeros((u.shape[0], n_out))
    for j in range(m):
        uj = np.asarray(u[:, j], dtype=complex)
        rows = [i for i in range(n_out) if not diagonal or i % m == j]
        for k in range(lam.size):
            if lam[k].imag < 0:
                continue  # conjugate of a mode handled below (real signals)
            q = signal.lfilter([0.0, 1.0], [1.0, -lam[k]], uj)
            factor = 1.0 if lam[k].imag == 0 else 2.0
            for i in rows:
                y[:, i] += factor * np.real(cv[i, k] * wb[k, j] * q)
    return y


# --------------------------------------------------------------------------------------------
# Route 1: the paper's eq. 4.
def _flow_gains(params: ActuatorParams, load_N: float) -> dict[str, float]:
    """Merritt's Kq at the static point under ``load_N`` for each flow direction (m^3/s).

    ``QL = (Q1 - Q2) / 2``. Extending (spool > 0): supply -> chamber 1 across ``Ps - P1``,
    chamber 2 -> return across ``P2 - Pr``; retracting: across ``P1 - Pr`` and ``Ps - P2``.
    """
    lin = linearization(params, load_N)
    kv = land_coefficient(pack(params).tolist())
    ps, pr, lam = params.supply_pressure_Pa, params.return_pressure_Pa, params.laminar_drop_Pa
    p1, p2 = lin.p1_Pa, lin.p2_Pa
    ext = 0.5 * kv * (orifice_root(ps - p1, lam) + orifice_root(p2 - pr, lam))
    ret = 0.5 * kv * (orifice_root(p1 - pr, lam) + orifice_root(ps - p2, lam))
    return {"static_mean": lin.kq_m3_s, "extending": ext, "retracting": ret, "mean_of_directions": 0.5 * (ext + ret)}


#: Route 1 variants: how Kq and Kc are taken (the first is the one reported as route 1).
ROUTE1_VARIANTS = {
    "static_mean": "Kq, Kc = exact slopes of the valve at the static loaded point, Kq the mean of both "
                   "chambers' flow paths (hydraulics.linearization; at rest the spool sits in the smoothed "
                   "null region, so all four metering lands contribute)",
    "null": "Kq, Kc at the unloaded valve null (load 0, P1 = P2): Merritt's textbook point",
    "extending": "Kq of the extending direction (supply to the loaded chamber 1 across Ps - P1, chamber 2 to return)",
    "retracting": "Kq of the retracting direction (chamber 1 to return across P1 - Pr, supply to chamber 2)",
}


def route1_models(params: ActuatorParams, kt_N_per_m: float, load_N: float
                  ) -> dict[str, tuple[control.TransferFunction, dict]]:
    """Eq. 4 for one wheel station, for each way of taking Merritt's coefficients.

    Parameters
    ----------
    params : ActuatorParams
    kt_N_per_m : float, N/m
        The station's tire stiffness.
    load_N : float, N
        Static actuator load (tire force plus pan weight).

    Returns
    -------
    dict
        ``variant -> (TransferFunction, coefficients)`` for the keys of :data:`ROUTE1_VARIANTS`;
        the coefficients dict holds ``ksv``, ``kq_m3_s``, ``kc_m3_s_Pa`` used.
    """
    lin = linearization(params, load_N)
    lin0 = linearization(params, 0.0)
    kq = _flow_gains(params, load_N)
    out = {}
    for name in ROUTE1_VARIANTS:
        ln = lin0 if name == "null" else lin
        coeff = {"ksv": ln.ksv, "kq_m3_s": ln.kq_m3_s if name in ("null", "static_mean") else kq[name],
                 "kc_m3_s_Pa": ln.kce_m3_s_Pa, "load_N": ln.load_N}
        tf = eq4_transfer_function(
            ksv=coeff["ksv"], kq_m3_s=coeff["kq_m3_s"], kc_m3_s_Pa=coeff["kc_m3_s_Pa"],
            kp_per_m=params.kp_per_m, kdp_per_Pa=params.kdp_per_Pa,
            piston_area_m2=params.piston_area_m2, fluid_volume_m3=ln.vf_m3,
            bulk_modulus_Pa=ln.beta_e_Pa, mass_kg=params.pan_mass_kg,
            damping_N_s_m=params.friction_N_s_m, tire_N_per_m=float(kt_N_per_m), ti_s=params.ti_s)
        out[name] = (tf, coeff)
    return out


def _budget_models(params: ActuatorParams, kt: float, load: float, f_hz) -> dict[str, np.ndarray]:
    """FRFs of the steps from eq. 4 to the plant: which assumption of eq. 4 costs what.

    (A free unsprung mass on the tire without its suspension is not a step of this ladder: it
    puts an undamped anti-resonance at sqrt(kt / m_u) that the real axle, held by its leaf
    spring and damper, does not have. The rest, route 2 minus the last step, is the vehicle.)
    """
    static_valve = params.replace(spool_hz=math.inf, check_loop_on_init=False)
    out = {}
    for name, (p, mass) in {"two_chamber_static_valve": (static_valve, math.inf),
                            "plus_spool_dynamics": (params, math.inf)}.items():
        a, b, c, _ = loop_matrices(p, kt, mass, load_N=load)
        out[name] = state_space_frequency_response(a, b, c, f_hz)[:, 0, 0]
    return out


# --------------------------------------------------------------------------------------------
# The nonlinear rig with an arbitrary drive.
def run_rig_drive(scenario: Scenario, x_ref_m, *, record_every: int = 1,
                  progress: Callable[[float, float], None] | None = None) -> dict:
    """Drive the nonlinear multibody rig with an arbitrary drive from static rest.

    Parameters
    ----------
    scenario : Scenario
        Truck variant and actuator overrides (road and duration are not used).
    x_ref_m : array_like, (N, 4), m
        Drive signal x_ref of each actuator (``ctrl`` of ``hyd_<c>``), one row per time step of
        the model (1e-4 s); it should start at 0 (the rest state).
    record_every : int
        Keep every ``record_every``-th step.
    progress : callable, optional
        ``progress(simulated_s, total_s)``.

    Returns
    -------
    dict
        ``t_s`` (n,), ``x_ref_m`` (n, 4) and ``x_a_m`` (n, 4) (the pan displacement at the
        same instants: before the step that applies ``x_ref``), ``dt_s``, ``events`` (spool
        saturation, cavitation, over-pressure per corner).

    Raises
    ------
    scenarios.core.runner.SimulationError
        On a MuJoCo warning or diverging hydraulic states, naming the simulated time.
    """
    from hydraulics.params import STATE_NAMES
    from scenarios.core.runner import Drive, SimulationError, Watch

    x_ref = np.asarray(x_ref_m, dtype=float)
    if x_ref.ndim != 2 or x_ref.shape[1] != len(CORNERS):
        raise ValueError(f"x_ref_m must have shape (N, {len(CORNERS)}), got {x_ref.shape}")
    if not np.all(np.isfinite(x_ref)):
        raise ValueError("x_ref_m must be finite")
    params = actuator_params(scenario)
    model = rig_model(scenario, params)
    data = rest_state(model, params)
    idx = RigIndex.of(model)
    hyd = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"hyd_{c}") for c in CORNERS])
    dim = int(model.actuator_actnum[hyd[0]])
    act_index = model.actuator_actadr[hyd][:, None] + np.arange(dim)[None, :]
    qa = idx.pan_qpos
    dt = float(model.opt.timestep)
    n_steps = x_ref.shape[0]
    t = np.arange(n_steps) * dt
    every = max(1, int(record_every))
    n_rec = (n_steps - 1) // every + 1
    pan = np.empty((n_rec, 4))
    states = np.empty((n_rec, 4, dim))

    def diverged(data_, t_):
        if not np.all(np.isfinite(data_.act)):
            raise SimulationError(f"the hydraulic states diverged by t = {t_:.4f} s of simulated time")

    watch = Watch(Drive(t_s=t, z_m=x_ref, v_mps=np.zeros_like(x_ref)), dt, progress, extra=diverged)
    j = 0
    with hydraulic_callbacks(model):
        for k in range(n_steps):
            data.ctrl[hyd] = x_ref[k]
            if k % every == 0:
                pan[j] = data.qpos[qa]
                states[j] = data.act[act_index]
                j += 1
            mujoco.mj_step(model, data)
            watch.tick(data, k)
        watch.finish(data)
    t_rec = t[::every]
    ev = event_summary(hydraulic_events(states, params), t_rec) if len(STATE_NAMES) == dim else {}
    return {"t_s": t_rec, "x_ref_m": x_ref[::every].copy(), "x_a_m": pan, "dt_s": dt, "events": ev}


def identification_drive(duration_s: float, dt_s: float, seed: int = IDENT_SEED, *,
                         rms_m: float = IDENT_RMS_M, corner_hz: float = IDENT_CORNER_HZ,
                         band_hz: tuple[float, float] = IDENT_BAND_HZ,
                         fade_s: float = IDENT_FADE_S) -> np.ndarray:
    """Four independent Gaussian random drives with a road-like spectrum.

    The displacement PSD is flat up to ``corner_hz`` and falls as ``1/f^2`` above it (a road's
    white velocity spectrum), band-limited to ``band_hz``; random phases, scaled to ``rms_m``;
    a cosine fade-in over ``fade_s`` starts it from rest.

    Parameters
    ----------
    duration_s : float, s
    dt_s : float, s
        Sample interval (the model's time step).
    seed : int
        ``numpy.random.default_rng`` seed.
    rms_m : float, m
        RMS displacement of each drive (after the fade-in).
    corner_hz : float, Hz
    band_hz : (float, float), Hz
    fade_s : float, s

    Returns
    -------
    numpy.ndarray, (N, 4), m
    """
    n = int(round(duration_s / dt_s)) + 1
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n, dt_s)
    amp = np.where(f < corner_hz, 1.0, (corner_hz / np.maximum(f, 1e-12)) ** 2) ** 0.5
    amp[(f < band_hz[0]) | (f > band_hz[1])] = 0.0
    spec = amp[:, None] * np.exp(2j * np.pi * rng.random((f.size, len(CORNERS))))
    z = np.fft.irfft(spec, n=n, axis=0)
    z *= rms_m / z.std(axis=0)
    tau = np.clip(np.arange(n) * dt_s / fade_s, 0.0, 1.0)
    return z * (0.5 - 0.5 * np.cos(np.pi * tau))[:, None]


def identify(record: dict, *, skip_s: float = IDENT_SKIP_S) -> dict:
    """Route 3's non-parametric part: MIMO H1 and multiple coherence of a rig record.

    Two Welch resolutions are spliced: 4 s segments (0.25 Hz, many averages) from 1 Hz up,
    16 s segments (0.0625 Hz) below 1 Hz when the record holds at least four of them.

    Returns
    -------
    dict
        ``f_hz`` (nf,), ``H`` (nf, 4, 4) [output, input], ``coherence`` (nf, 4), ``nperseg``.
    """
    dt = float(record["t_s"][1] - record["t_s"][0])
    fs = 1.0 / dt
    k0 = int(round(skip_s / dt))
    u = record["x_ref_m"][k0:]
    y = record["x_a_m"][k0:]
    n = u.shape[0]
    short = min(int(round(4.0 * fs)), n // 4)
    f, h, coh = h1_estimate(u, y, fs, short)
    used = {"high": short}
    long_ = int(round(16.0 * fs))
    if n >= 4 * long_:
        fl, hl, cl = h1_estimate(u, y, fs, long_)
        lo = (fl > 0) & (fl < 1.0)
        hi = f >= 1.0
        f = np.concatenate([fl[lo], f[hi]])
        h = np.concatenate([hl[lo], h[hi]])
        coh = np.concatenate([cl[lo], coh[hi]])
        used["low"] = long_
    else:
        keep = f > 0
        f, h, coh = f[keep], h[keep], coh[keep]
    return {"f_hz": f, "H": h, "coherence": coh, "nperseg": used, "fs_hz": fs}


# --------------------------------------------------------------------------------------------
# Workers (one run per process: MuJoCo's actuator callbacks are process-global).
def _job_ident(path: str, duration_s: float, friction: bool = True) -> dict:
    sc = _scenario(path, None, friction=friction)
    params = actuator_params(sc)
    dt = rig_model(sc, params).opt.timestep
    drive = identification_drive(duration_s + IDENT_SKIP_S, dt)
    every = int(round(1.0 / (IDENT_RATE_HZ * dt)))
    rec = run_rig_drive(sc, drive, record_every=every)
    rec["drive_rms_m"] = float(np.mean(drive[int(IDENT_SKIP_S / dt):].std(axis=0)))
    rec["drive_velocity_rms_m_s"] = float(np.mean((np.diff(drive, axis=0) / dt).std(axis=0)))
    return rec


def _step_drive(n: int, dt: float, size_m: float) -> np.ndarray:
    u = np.zeros((n, len(CORNERS)))
    u[int(round(STEP_AT_S / dt)):] = size_m
    return u


def _job_step(path: str, size_m: float, friction: bool = True) -> dict:
    sc = _scenario(path, None, friction=friction)
    dt = rig_model(sc, actuator_params(sc)).opt.timestep
    n = int(round(STEP_RUN_S / dt)) + 1
    return run_rig_drive(sc, _step_drive(n, dt, size_m))


def _summary(result) -> dict:
    s = result.summary()
    return {"dlc_mean": s["dlc_mean"], "dlc": {c: w["dlc"] for c, w in s["wheels"].items()},
            "mean_force_N": {c: w["mean_force_N"] for c, w in s["wheels"].items()},
            "events": s["events"], "wall_time_s": s["info"]["wall_time_s"]}


def _job_scenario(path: str, duration_s: float | None, mode: str, pose_rate_hz: float | None = None) -> dict:
    """Run the Table 1 scenario in ``mode``; the summary, plus the whole result when poses are
    asked for (a recording is wanted)."""
    from scenarios.core.runner import run

    result = run(_scenario(path, duration_s), mode, pose_rate_hz=pose_rate_hz)
    out = _summary(result)
    if pose_rate_hz is not None:
        out["result"] = result
    return out


def _job_linear(path: str, duration_s: float | None, kind: str, model) -> dict:
    """Road run with the pans following a linear actuator model of the profile.

    ``kind``: "route2_per_wheel" / "route2_mimo" (``model`` = (A, B, C)) or "eq4" (``model`` =
    per-corner (num, den)).
    """
    from scenarios.core.runner import Drive, run

    def pan_drive(drive: Drive) -> Drive:
        dt = float(drive.t_s[1] - drive.t_s[0])
        if kind.startswith("route2"):
            a, b, c = model
            y = _modal_simulate(a, b, c, drive.z_m, diagonal=(kind == "route2_per_wheel"))
            z, v = y[:, :4], y[:, 4:]
        else:
            # First-order hold (exact for the piecewise-linear drive; a zero-order hold adds half
            # a step of delay), and the profile's velocity through the same T_a (d/dt commutes).
            z = np.empty_like(drive.z_m)
            v = np.empty_like(drive.z_m)
            for i, (num, den) in enumerate(model):
                bd, ad, _ = signal.cont2discrete((num, den), dt, method="foh")
                z[:, i] = signal.lfilter(np.ravel(bd), ad, drive.z_m[:, i])
                v[:, i] = signal.lfilter(np.ravel(bd), ad, drive.v_mps[:, i])
        return Drive(t_s=drive.t_s, z_m=z, v_mps=v)

    return _summary(run(_scenario(path, duration_s), "road", pan_drive=pan_drive))


# --------------------------------------------------------------------------------------------
def _err_db_deg(h, ref) -> tuple[np.ndarray, np.ndarray]:
    r = np.asarray(h) / np.asarray(ref)
    return 20.0 * np.log10(np.abs(r)), np.degrees(np.angle(r))


def _roots(r) -> list[dict]:
    return [{k: round(v, 6) for k, v in d.items()} for d in describe_roots(r)]


def _tf_json(tf: control.TransferFunction) -> dict:
    return {"num": [float(x) for x in np.ravel(tf.num[0][0])],
            "den": [float(x) for x in np.ravel(tf.den[0][0])],
            "poles": _roots(tf.poles()), "zeros": _roots(tf.zeros())}


def _steps_linear(lin: PlantLinearization, eq4: list, fits: list, size_m: float, n: int) -> dict[str, np.ndarray]:
    u = _step_drive(n, lin.dt_s, size_m)
    out = {"route2": _modal_simulate(lin.a, lin.b, lin.c[:4], u, diagonal=False)}
    out["route1"] = np.column_stack([apply_transfer_function(tf, u[:, i], lin.dt_s) for i, tf in enumerate(eq4)])
    if fits:
        out["route3"] = np.column_stack([apply_transfer_function(tf, u[:, i], lin.dt_s) for i, tf in enumerate(fits)])
    return out


def validate(*, duration_s: float | None = None, ident_duration_s: float | None = None,
             jobs: int | None = None, progress: ProgressFn | None = None,
             pose_rate_hz: float | None = None) -> dict:
    """Compute the whole validation (routes 1-3, Figure 7 and Table 1 analogues).

    Parameters
    ----------
    duration_s : float, s, optional
        Analysed duration of the Table 1 runs (default: the scenario's 60 s).
    ident_duration_s : float, s, optional
        Analysed duration of the identification record (default twice ``duration_s``,
        at least 10 s).
    jobs : int, optional
        Worker processes (default: all cores).
    progress : callable, optional
        ``progress(line)`` for one-line progress messages.

    Returns
    -------
    dict
        ``{"json": <everything of validate.json>, "arrays": <curves for the plots>}``.
    """
    wall0 = time.perf_counter()
    path = str(table1_scenario_path())
    sc = _scenario(path, duration_s)
    table_s = sc.duration_s
    ident_s = float(ident_duration_s) if ident_duration_s is not None else max(2.0 * table_s, 10.0)
    if not ident_s > 0:
        raise ScenarioError(f"ident_duration_s must be > 0, got {ident_duration_s!r}")
    params = actuator_params(sc)
    workers = max(1, min(8, jobs or os.cpu_count() or 1))
    _say(progress, f"validate: {sc.name}, Table 1 runs {table_s:g} s, identification {ident_s:g} s, "
                   f"{workers} worker(s)")
    futures: dict[str, cf.Future] = {}
    with cf.ProcessPoolExecutor(max_workers=workers) as pool:
        try:
            # Longest first; all of these are independent of the linearizations below.
            futures["ident"] = pool.submit(_job_ident, path, ident_s)
            futures["rig"] = pool.submit(_job_scenario, path, table_s, "rig", pose_rate_hz)
            futures["road"] = pool.submit(_job_scenario, path, table_s, "road", pose_rate_hz)
            futures["step_small"] = pool.submit(_job_step, path, STEP_SMALL_M)
            futures["step_large"] = pool.submit(_job_step, path, STEP_LARGE_M)
            # Diagnostics: the same without leaf-spring dry friction (route 2 linearizes without it).
            futures["ident_nofriction"] = pool.submit(_job_ident, path, ident_s, False)
            futures["step_small_nofriction"] = pool.submit(_job_step, path, STEP_SMALL_M, False)
            futures["step_large_nofriction"] = pool.submit(_job_step, path, STEP_LARGE_M, False)

            _say(progress, "validate: route 2, linearizing the plant with mjd_transitionFD")
            lin = linearize_plant(sc, params)
            _say(progress, "validate: route 1, eq. 4 per wheel station")
            r1 = [route1_models(params, lin.kt_N_per_m[i], lin.load_N[i]) for i in range(4)]
            eq4 = [r1[i]["static_mean"][0] for i in range(4)]
            model_r2 = (lin.a, lin.b, lin.c)
            futures["lin_route2_per_wheel"] = pool.submit(_job_linear, path, table_s, "route2_per_wheel", model_r2)
            futures["lin_eq4"] = pool.submit(
                _job_linear, path, table_s, "eq4",
                [(np.ravel(tf.num[0][0]), np.ravel(tf.den[0][0])) for tf in eq4])
            futures["lin_route2_mimo"] = pool.submit(_job_linear, path, table_s, "route2_mimo", model_r2)

            results = {}
            pending = set(futures.values())
            names = {fut: k for k, fut in futures.items()}
            t_start = time.perf_counter()
            while pending:
                done, pending = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
                for fut in done:
                    results[names[fut]] = fut.result()
                    _say(progress, f"validate: [{len(results)}/{len(futures)}] {names[fut]} done "
                                   f"({time.perf_counter() - t_start:.1f} s)")
        except BaseException:
            for fut in futures.values():
                fut.cancel()
            raise

    _say(progress, "validate: route 3, H1 estimate and rational fits; comparing")
    js, arrays = _assemble(sc, params, lin, r1, results, table_s, ident_s)
    js["wall_time_s"] = round(time.perf_counter() - wall0, 2)
    runs = {k: results[k].pop("result") for k in ("road", "rig") if "result" in results[k]}
    return {"json": js, "arrays": arrays, "runs": runs}


def _assemble(sc, params, lin, r1, results, table_s, ident_s):
    corners = list(CORNERS)
    f_bode = np.geomspace(BODE_RANGE_HZ[0], BODE_RANGE_HZ[1], 400)
    f_cmp = np.geomspace(BODE_RANGE_HZ[0], COMPARE_MAX_HZ, 400)
    h2_bode = lin.frequency_response(f_bode)
    h2_cmp = lin.frequency_response(f_cmp)
    dc2 = np.abs(lin.frequency_response([1e-4])[0])
    f_bw = np.geomspace(0.05, 200.0, 3000)
    h2_bw = lin.frequency_response(f_bw)

    js: dict = {
        "scenario": sc.name,
        "duration_s": table_s,
        "ident_duration_s": ident_s,
        "timestep_s": lin.dt_s,
        "compare_range_hz": [BODE_RANGE_HZ[0], COMPARE_MAX_HZ],
        "coherence_min": COHERENCE_MIN,
    }

    # ---- route 2
    bw2 = {c: bandwidth_hz(f_bw, h2_bw[:, i, i], reference=float(dc2[i, i])) for i, c in enumerate(corners)}
    poles2 = lin.poles()
    coupling2 = {}
    for i, c in enumerate(corners):
        for j, c2 in enumerate(corners):
            if i != j:
                mag = np.abs(h2_bode[:, i, j])
                k = int(np.argmax(mag))
                coupling2[f"{c2}->{c}"] = {"max_db": float(20 * np.log10(mag[k])), "at_hz": float(f_bode[k])}
    worst_c2 = max(coupling2.items(), key=lambda kv: kv[1]["max_db"])
    js["route2"] = {
        "method": "mujoco.mjd_transitionFD (centred, eps 1e-6) of truck + pans + 4 hydraulic actuators at "
                  "static rest, leaf-spring frictionloss disabled; H = C (exp(j 2 pi f dt) I - A)^-1 B",
        "states": int(lin.a.shape[0]),
        "dc_gain": {c: float(dc2[i, i]) for i, c in enumerate(corners)},
        "bandwidth_hz": bw2,
        "poles": _roots(poles2),
        "zeros": {c: _roots(lin.siso_zeros(i)) for i, c in enumerate(corners)},
        "cross_coupling_max": {"path": worst_c2[0], **worst_c2[1]},
        "cross_coupling": coupling2,
        "static_load_N": {c: float(lin.load_N[i]) for i, c in enumerate(corners)},
        "tire_N_per_m": {c: float(lin.kt_N_per_m[i]) for i, c in enumerate(corners)},
    }

    # ---- route 1 (all variants) and the departure budget
    r1_json = {"flow_direction": (
        "route 1 = variant 'static_mean': Kq and Kc are the exact slopes of the valve at each station's "
        "static loaded point (P1 > P2), Kq the mean of the two chambers' flow paths, QL = (Q1 - Q2)/2, "
        "Kc including cross-piston leakage; the other variants show the effect of the choice"),
        "variants": {}, "bandwidth_hz": {}, "models": {}}
    h1_bode = {}
    for name, text in ROUTE1_VARIANTS.items():
        var = {"description": text, "corners": {}}
        for i, c in enumerate(corners):
            tf, coeff = r1[i][name]
            h = _freqresp(tf, f_cmp)
            db, deg = _err_db_deg(h, h2_cmp[:, i, i])
            var["corners"][c] = {**{k: float(v) for k, v in coeff.items()},
                                 "bandwidth_hz": transfer_bandwidth_hz(tf),
                                 "frf_max_error_db": float(np.max(np.abs(db))),
                                 "frf_max_error_deg": float(np.max(np.abs(deg)))}
        var["frf_max_error_db"] = max(v["frf_max_error_db"] for v in var["corners"].values())
        var["frf_max_error_deg"] = max(v["frf_max_error_deg"] for v in var["corners"].values())
        r1_json["variants"][name] = var
    r1_json["mid_band_gain_db"] = {}
    for i, c in enumerate(corners):
        tf = r1[i]["static_mean"][0]
        r1_json["bandwidth_hz"][c] = transfer_bandwidth_hz(tf)
        # Between 1/Ti and the bandwidth eq. 4 is ~ b1 s / (a1 s): the proportional loop's droop
        # under the tire-to-ground load, b1 / a1 = K / (K + Kc' kt / Ap^2).
        b1, a1 = float(np.ravel(tf.num[0][0])[0]), float(np.ravel(tf.den[0][0])[3])
        r1_json["mid_band_gain_db"][c] = 20.0 * math.log10(b1 / a1)
        r1_json["models"][c] = _tf_json(tf)
        h1_bode[c] = _freqresp(tf, f_bode)
    js["route1"] = r1_json

    budget, budget_curves, one_pressure = {}, {}, {}
    for i, c in enumerate(corners):
        stages = {"eq4": _freqresp(r1[i]["static_mean"][0], f_cmp)}
        stages.update(_budget_models(params, float(lin.kt_N_per_m[i]), float(lin.load_N[i]), f_cmp))
        row = {}
        for name, h in stages.items():
            db, deg = _err_db_deg(h, h2_cmp[:, i, i])
            row[name] = {"max_error_db": float(np.max(np.abs(db))), "max_error_deg": float(np.max(np.abs(deg))),
                         "error_db_at_30hz": float(db[-1]), "error_deg_at_30hz": float(deg[-1])}
        budget[c] = row
        budget_curves[c] = stages
        db, deg = _err_db_deg(stages["eq4"], stages["two_chamber_static_valve"])
        one_pressure[c] = {"max_db": float(np.max(np.abs(db))), "max_deg": float(np.max(np.abs(deg)))}
    js["departure_budget"] = {
        "stages": {
            "eq4": "paper's eq. 4 (route 1)",
            "two_chamber_static_valve": "both chambers linearized separately at the loaded point, static valve, tire to ground",
            "plus_spool_dynamics": "... with the 150 Hz second-order spool (the valve of the plant); what "
                                   "remains to route 2 is the vehicle",
            "route2": "the whole plant (truck, suspension, the other three actuators), MuJoCo's Euler map",
        },
        "versus_route2": budget,
        "eq4_vs_two_chamber_static_valve": one_pressure,
    }

    # ---- route 3 (and the same without leaf-spring friction, a diagnostic)
    ident = results["ident"]
    r3_corners, est, fits, coupling3 = _route3(ident, lin, f_cmp, h2_cmp)
    f3, h3, coh3 = est["f_hz"], est["H"], est["coherence"]
    h2_at3 = lin.frequency_response(f3)
    worst_c3 = max(coupling3.items(), key=lambda kv: kv[1]["max_db"])
    js["route3"] = {
        "method": "4 independent road-like Gaussian drives (displacement PSD flat to 1 Hz, 1/f^2 above, "
                  "0.05-60 Hz) on the nonlinear rig (leaf friction on); MIMO H1 = S_yu S_uu^-1 with "
                  "multiple coherence; stable rational fit (Sanathanan-Koerner) per wheel, weight "
                  "sqrt(coh / (1 - coh)) / |H| (relative error, trusted points first)",
        "record_s": ident_s,
        "drive_rms_m": ident["drive_rms_m"],
        "drive_velocity_rms_m_s": ident["drive_velocity_rms_m_s"],
        "pan_rms_m": float(np.mean(ident["x_a_m"].std(axis=0))),
        "rate_hz": est["fs_hz"],
        "nperseg": est["nperseg"],
        "fit_orders": list(FIT_ORDERS),
        "seed": IDENT_SEED,
        "events": ident["events"],
        "corners": r3_corners,
        "bandwidth_hz": {c: r3_corners[c]["bandwidth_hz"] for c in corners},
        "cross_coupling_max": {"path": worst_c3[0], **worst_c3[1]},
    }
    nf_corners, _, _, _ = _route3(results["ident_nofriction"], lin, f_cmp, h2_cmp)

    # ---- headline FRF errors
    js["bandwidth_hz"] = {
        "route1": r1_json["bandwidth_hz"],
        "route2": bw2,
        "route3": js["route3"]["bandwidth_hz"],
    }
    js["frf_max_error_db"] = {"route1": r1_json["variants"]["static_mean"]["frf_max_error_db"],
                              "route3": _nanmax(r3_corners[c]["frf_max_error_db"] for c in corners)}
    js["frf_max_error_deg"] = {"route1": r1_json["variants"]["static_mean"]["frf_max_error_deg"],
                               "route3": _nanmax(r3_corners[c]["frf_max_error_deg"] for c in corners)}

    # ---- Figure 7 analogue
    steps_json, step_curves = {}, {}
    for key, size in (("small", STEP_SMALL_M), ("large", STEP_LARGE_M)):
        rec = results[f"step_{key}"]
        nl = rec["x_a_m"]
        linear = _steps_linear(lin, [r1[i]["static_mean"][0] for i in range(4)], fits, size, nl.shape[0])
        entry = {"step_m": size, "step_at_s": STEP_AT_S, "events": rec["events"],
                 "nonlinear_overshoot_pct": float(100 * (np.max(nl) - size) / size),
                 "nonlinear_final_m": {c: float(nl[-1, i]) for i, c in enumerate(corners)}}
        for name, y in linear.items():
            err = np.abs(y - nl)
            k, i = np.unravel_index(int(np.argmax(err)), err.shape)
            entry[name] = {"max_error_mm": float(1e3 * err[k, i]), "max_error_pct": float(100 * err[k, i] / size),
                           "at_s": float(rec["t_s"][k]), "corner": corners[i]}
        steps_json[key] = entry
        step_curves[key] = {"t_s": rec["t_s"], "nonlinear": nl, **linear}
    js["steps"] = steps_json
    js["step_models"] = {"headline": "step_max_error_*: route 2 against the nonlinear rig; *_eq4: eq. 4",
                         "route2": "the whole linearized plant (all four inputs stepped: cross-coupling included)",
                         "route1": "eq. 4 per wheel", "route3": "rational fit per wheel (own path only)"}
    js["step_max_error_small_mm"] = steps_json["small"]["route2"]["max_error_mm"]
    js["step_max_error_small_pct"] = steps_json["small"]["route2"]["max_error_pct"]
    js["step_max_error_large_mm"] = steps_json["large"]["route2"]["max_error_mm"]
    js["step_max_error_large_pct"] = steps_json["large"]["route2"]["max_error_pct"]
    js["step_max_error_small_pct_eq4"] = steps_json["small"]["route1"]["max_error_pct"]
    js["step_max_error_large_pct_eq4"] = steps_json["large"]["route1"]["max_error_pct"]
    nf_steps = {}
    for key, size in (("small", STEP_SMALL_M), ("large", STEP_LARGE_M)):
        nl = results[f"step_{key}_nofriction"]["x_a_m"]
        y2 = _modal_simulate(lin.a, lin.b, lin.c[:4], _step_drive(nl.shape[0], lin.dt_s, size), diagonal=False)
        err = float(np.max(np.abs(y2 - nl)))
        nf_steps[key] = {"max_error_mm": 1e3 * err, "max_error_pct": 100 * err / size}

    # ---- Table 1 analogue
    rig = results["rig"]["dlc_mean"]
    lin_pw = results["lin_route2_per_wheel"]["dlc_mean"]
    t1 = {
        "road_test": results["road"]["dlc_mean"],
        "rig_test": rig,
        "linearized_model": lin_pw,
        "linearized_model_eq4": results["lin_eq4"]["dlc_mean"],
        "linearized_model_route2_mimo": results["lin_route2_mimo"]["dlc_mean"],
        "linearized_vs_rig_pct": 100.0 * (lin_pw - rig) / rig,
        "linearized_eq4_vs_rig_pct": 100.0 * (results["lin_eq4"]["dlc_mean"] - rig) / rig,
        "linearized_route2_mimo_vs_rig_pct": 100.0 * (results["lin_route2_mimo"]["dlc_mean"] - rig) / rig,
        "paper": dict(PAPER_TABLE1),
        "paper_linearized_vs_rig_pct": 100.0 * (PAPER_TABLE1["linearized_model"] - PAPER_TABLE1["rig_test"])
                                       / PAPER_TABLE1["rig_test"],
        "notes": ("rig_test is the nonlinear multibody rig, so it stands for both the paper's DYNTRAC test and "
                  "its nonlinear model; linearized_model: the pans follow route 2's own-path T_a of each wheel "
                  "applied to the profile (ZOH, exact discretization); _eq4: eq. 4 per wheel; _route2_mimo: "
                  "the whole linear plant with all four profiles (cross-coupling included). DLC = mean over "
                  "the four wheels of std/mean tire force."),
        "per_wheel": {k: results[r]["dlc"] for k, r in (("road_test", "road"), ("rig_test", "rig"),
                                                         ("linearized_model", "lin_route2_per_wheel"),
                                                         ("linearized_model_eq4", "lin_eq4"),
                                                         ("linearized_model_route2_mimo", "lin_route2_mimo"))},
        "rig_events": results["rig"]["events"],
    }
    js["table1"] = t1

    js["diagnostics_friction_off"] = {
        "what": "the nonlinear rig again with the leaf springs' dry friction (frictionloss) set to 0, "
                "as in route 2's linearization: separates friction from the hydraulic nonlinearity",
        "route3_frf_max_error_db": _nanmax(nf_corners[c]["frf_max_error_db"] for c in corners),
        "route3_frf_max_error_deg": _nanmax(nf_corners[c]["frf_max_error_deg"] for c in corners),
        "route3_corners": {c: {k: nf_corners[c][k] for k in (
            "frf_max_error_db", "frf_max_error_db_at_hz", "frf_max_error_deg", "frf_max_error_deg_at_hz",
            "coherence_min_to_30hz", "bandwidth_hz")} for c in corners},
        "step_max_error_small_mm": nf_steps["small"]["max_error_mm"],
        "step_max_error_small_pct": nf_steps["small"]["max_error_pct"],
        "step_max_error_large_mm": nf_steps["large"]["max_error_mm"],
        "step_max_error_large_pct": nf_steps["large"]["max_error_pct"],
    }
    js["goals"] = {
        "route3_within_0p5db_5deg_to_30hz": bool(js["frf_max_error_db"]["route3"] <= GOAL_FRF_DB
                                                 and js["frf_max_error_deg"]["route3"] <= GOAL_FRF_DEG),
        "table1_linearized_within_2pct_of_rig": bool(abs(t1["linearized_vs_rig_pct"]) <= GOAL_TABLE1_PCT),
        "table1_road_above_rig": bool(t1["road_test"] > t1["rig_test"]),
    }
    arrays = {"f_bode": f_bode, "h1": h1_bode, "h2": h2_bode, "f3": f3, "h3": h3, "coh3": coh3,
              "fits": fits, "steps": step_curves, "f_cmp": f_cmp, "budget": budget_curves,
              "h2_cmp": h2_cmp, "h2_at_f3": h2_at3}
    return js, arrays


def _route3(ident: dict, lin: PlantLinearization, f_cmp, h2_cmp):
    """H1 estimate, per-wheel fits and their comparison with route 2 for one rig record."""
    est = identify(ident)
    f3, h3, coh3 = est["f_hz"], est["H"], est["coherence"]
    h2_at3 = lin.frequency_response(f3)
    fits, out = [], {}
    sel = (f3 >= BODE_RANGE_HZ[0]) & (f3 <= COMPARE_MAX_HZ)
    for i, c in enumerate(CORNERS):
        hii = h3[:, i, i]
        ci = coh3[:, i]
        good = sel & (ci > COHERENCE_MIN) & np.isfinite(hii)
        db, deg = _err_db_deg(hii, h2_at3[:, i, i])
        w = np.clip(np.nan_to_num(ci), 0.0, 0.999999)
        # sqrt(coh / (1 - coh)) ~ 1 / relative standard deviation of H1; / |H|: relative error.
        w = np.sqrt(w / (1.0 - w)) / np.maximum(np.abs(np.nan_to_num(hii)), 1e-12)
        fit = fit_rational(f3, hii, FIT_ORDERS[0], FIT_ORDERS[1], weight=w, f_max=BODE_RANGE_HZ[1],
                           f_min=BODE_RANGE_HZ[0])
        fits.append(fit)
        fdb, fdeg = _err_db_deg(_freqresp(fit, f3), hii)
        gdb, gdeg = _err_db_deg(_freqresp(fit, f_cmp), h2_cmp[:, i, i])
        low = (f3 >= BODE_RANGE_HZ[0]) & (f3 <= 1.0) & np.isfinite(hii)
        fin = np.isfinite(hii)
        k_db = int(np.argmax(np.where(good, np.abs(db), -1.0)))
        k_deg = int(np.argmax(np.where(good, np.abs(deg), -1.0)))
        out[c] = {
            "frf_max_error_db": float(abs(db[k_db])) if np.any(good) else math.nan,
            "frf_max_error_db_at_hz": float(f3[k_db]) if np.any(good) else math.nan,
            "frf_max_error_deg": float(abs(deg[k_deg])) if np.any(good) else math.nan,
            "frf_max_error_deg_at_hz": float(f3[k_deg]) if np.any(good) else math.nan,
            "points_compared": int(np.sum(good)),
            "points_in_range": int(np.sum(sel)),
            "coherence_min_to_30hz": float(np.nanmin(ci[sel])),
            "low_frequency_gain": float(np.mean(np.abs(hii[low]))) if np.any(low) else math.nan,
            "bandwidth_h1_hz": bandwidth_hz(f3[fin], hii[fin], reference=1.0),
            "bandwidth_hz": transfer_bandwidth_hz(fit),
            "fit": _tf_json(fit),
            "fit_max_error_db_vs_h1": float(np.max(np.abs(fdb[good]))) if np.any(good) else math.nan,
            "fit_max_error_deg_vs_h1": float(np.max(np.abs(fdeg[good]))) if np.any(good) else math.nan,
            "fit_max_error_db_vs_route2": float(np.max(np.abs(gdb))),
            "fit_max_error_deg_vs_route2": float(np.max(np.abs(gdeg))),
        }
    coupling = {}
    for i, c in enumerate(CORNERS):
        for j, c2 in enumerate(CORNERS):
            if i != j:
                ok = (f3 >= BODE_RANGE_HZ[0]) & (f3 <= BODE_RANGE_HZ[1]) & np.isfinite(h3[:, i, j])
                mag = np.abs(h3[ok, i, j])
                k = int(np.argmax(mag))
                coupling[f"{c2}->{c}"] = {"max_db": float(20 * np.log10(mag[k])), "at_hz": float(f3[ok][k])}
    return out, est, fits, coupling


def _nanmax(values) -> float:
    v = [x for x in values if not math.isnan(x)]
    return max(v) if v else math.nan


def _freqresp(tf, f_hz) -> np.ndarray:
    from correction.transfer import frequency_response_hz

    return frequency_response_hz(tf, f_hz)


# --------------------------------------------------------------------------------------------
# Command line (wired into scenarios/cli.py by the lead).
def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``validate`` on an ``argparse`` sub-parser collection; sets ``func=cmd_validate``."""
    p = subparsers.add_parser(
        "validate", help="validate the linearized actuator model (eq. 4) against the multibody plant")
    p.add_argument("--out", required=True, help="output folder (validate.json, report.md, PNGs)")
    p.add_argument("--duration-s", type=float, default=None,
                   help="analysed duration of the Table 1 runs in s (default: the scenario's 60 s)")
    p.add_argument("--ident-duration-s", type=float, default=None,
                   help="identification record in s (default: twice --duration-s, at least 10 s)")
    p.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    p.add_argument("--rrd", default=None, help="also write a rerun recording of the Table 1 road and rig runs")
    p.add_argument("--view", action="store_true", help="with --rrd: open the recording in the rerun viewer")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.set_defaults(func=cmd_validate)
    return p


def cmd_validate(args) -> int:
    """Run :func:`validate`, write the report into ``args.out``, print the key numbers."""
    for name in ("duration_s", "ident_duration_s"):
        v = getattr(args, name, None)
        if v is not None and not (math.isfinite(v) and 0 < v <= 3600):
            raise ScenarioError(f"--{name.replace('_', '-')} must lie in (0, 3600] s, got {v!r}")
    out = pathlib.Path(args.out)
    if out.exists() and not out.is_dir():
        raise ScenarioError(f"--out {out} exists and is not a folder")
    quiet = getattr(args, "quiet", False)
    progress = None if quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    rrd = getattr(args, "rrd", None)
    pose_rate = None
    if rrd:
        from scenarios.review.recording import DEFAULT_POSE_RATE_HZ

        pose_rate = DEFAULT_POSE_RATE_HZ
    result = validate(duration_s=args.duration_s, ident_duration_s=getattr(args, "ident_duration_s", None),
                      jobs=getattr(args, "jobs", None), progress=progress, pose_rate_hz=pose_rate)
    from scenarios.studies.validate.report import summary_lines, write_report

    paths = write_report(result, args.out)
    if rrd:
        from scenarios.review.recording import write_recording

        runs = [result["runs"][k] for k in ("road", "rig") if k in result.get("runs", {})]
        write_recording(rrd, runs, dlc_table="\n".join(summary_lines(result["json"])),
                        spawn=getattr(args, "view", False))
        print(f"wrote recording {rrd} (Table 1 road and rig runs)")
    for line in summary_lines(result["json"]):
        print(line)
    print(f"wrote {paths['validate.json']}, {paths['report.md']} and {len(paths) - 2} PNGs")
    return 0
