"""The one rig: the truck on the DYNTRAC wheelpans, built from a scenario, at rest, linearized, run.

:class:`Rig` is the only place that builds truck + pans (+ the four hydraulic actuators),
gives the rest state, linearizes the closed-loop plant (``mujoco.mjd_transitionFD``) and
steps it. Every command (``run``, ``paper``, ``validate``, ``iterate``, ``sweep``) and the
benchmarks use it; none keeps its own stepping loop.

Two kinds of rig:

* ``Rig(scenario, hydraulic=True)``, the rig test: the drive is the actuators' reference
  x_ref in ``ctrl``; the actuator states live in MuJoCo's activation vector and are advanced
  by the callbacks of :mod:`hydraulics.bridge`, installed for a run only. It steps in C with
  ``mujoco.rollout`` in 10 ms chunks (the constraint warm start carried from chunk to chunk;
  bit-identical to a loop of ``mj_step``).
* ``Rig(scenario, hydraulic=False)``, the road test: the pans follow the drive exactly
  (positions and velocities set before every step).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import mujoco
import numpy as np
from mujoco import rollout

from hydraulics.bridge import add_hydraulic_actuators, hydraulic_callbacks
from hydraulics.equilibrium import equilibrium_activation
from hydraulics.events import events as hydraulic_events
from hydraulics.loop import check_design_station
from hydraulics.params import STATE_NAMES, ActuatorParams
from mjcf import names
from mjcf.build import build_spec
from mjcf.physics import RigIndex, friction_disabled, static_equilibrium, tire_stiffness
from scenarios.core.config import Scenario, ScenarioError
from scenarios.core.drive import Drive, road_drive
from scenarios.core.memory import check_memory
from scenarios.core.plant import PlantLinearization
from scenarios.core.watch import SimulationError, Watch, mujoco_warnings_captured, output_schedule

__all__ = ["actuator_params", "Rig", "RigRecord"]

MPA = 1e6  # Pa per MPa: the pressure states are in MPa (see hydraulics.params.STATE_NAMES)
#: Warning windows (scenarios.core.watch.CHECK_EVERY_S) per rollout call of a hydraulic run:
#: 0.1 s at the 1e-4 s step, so the calls' Python overhead is ~1 % of the stepping.
ROLLOUT_CHECKS = 10


def actuator_params(scenario: Scenario) -> ActuatorParams:
    """The scenario's actuator parameters (defaults with the ``[actuator]`` overrides)."""
    try:
        return ActuatorParams(**dict(scenario.actuator))
    except (TypeError, ValueError) as exc:
        raise ScenarioError(str(exc)) from None


@dataclass(frozen=True)
class RigRecord:
    """What a run of the rig records at the output rate, from the first step at t >= 0.

    Attributes
    ----------
    t_s : numpy.ndarray, s, (n,)
    x_ref_m : numpy.ndarray, m, (n, 4)
        The drive at the recorded instants (road mode: the pan motion itself).
    pan_m : numpy.ndarray, m, (n, 4)
        Pan displacement x_a (the state before the step that applies ``x_ref_m``).
    tire_force_N : numpy.ndarray, N, (n, 4)
        Tire force on each pan, compression positive.
    states : numpy.ndarray or None, (n, 4, 5)
        Hydraulic activation states in :data:`hydraulics.params.STATE_NAMES` order (rig only).
    events : Mapping
        ``{event: {corner: {"samples": int, "first_time_s": float (s)}}}`` for the events that
        occurred (spool saturation, cavitation, over-pressure; rig only).
    poses : scenarios.core.poses.PoseTrack or None
        Body poses at video rate when asked for.
    """

    t_s: np.ndarray
    x_ref_m: np.ndarray
    pan_m: np.ndarray
    tire_force_N: np.ndarray
    states: np.ndarray | None = None
    events: Mapping = field(default_factory=dict)
    poses: object = None

    def state(self, name: str) -> np.ndarray:
        """One hydraulic state per corner, (n, 4), in SI (pressures in Pa, spool normalised)."""
        if self.states is None:
            raise ValueError("a road-mode record has no hydraulic states")
        x = self.states[:, :, list(STATE_NAMES).index(name)]
        return x * MPA if name.endswith("_MPa") else x


class Rig:
    """The truck of a scenario on the four-post rig.

    Parameters
    ----------
    scenario : Scenario
        Truck variant, actuator overrides (``[actuator]``), road and output rate.
    hydraulic : bool
        True: the pans are driven by the servo-hydraulic actuators (rig test); False: the pans
        follow their drive exactly (road test).
    check_stability : bool
        With ``hydraulic``: refuse actuator parameters whose loop is unstable under the design
        wheel station (:func:`hydraulics.loop.check_design_station`) or whose closed loop under
        this truck is unstable (:meth:`check_stable`). False only to study an unstable rig.

    Raises
    ------
    ScenarioError
        Bad actuator or vehicle parameters, disagreeing pan masses, an unstable loop.
    """

    def __init__(self, scenario: Scenario, *, hydraulic: bool = True, check_stability: bool = True):
        self.scenario = scenario
        self.hydraulic = bool(hydraulic)
        self.params = params = actuator_params(scenario)
        variant = scenario.vehicle
        # The pan mass is one physical quantity with two homes (the MuJoCo pan body and the
        # actuator parameters the linear models use): the actuator's value unless the scenario
        # sets vehicle.pan_mass_kg, and two different values are refused.
        if variant.pan_mass_kg is None:
            variant = dataclasses.replace(variant, pan_mass_kg=params.pan_mass_kg)
        elif "pan_mass_kg" in scenario.actuator and scenario.actuator["pan_mass_kg"] != variant.pan_mass_kg:
            raise ScenarioError(
                f"vehicle.pan_mass_kg ({variant.pan_mass_kg:g} kg) and actuator.pan_mass_kg "
                f"({scenario.actuator['pan_mass_kg']:g} kg) disagree; set only one of them")
        self.pan_mass_kg = float(variant.pan_mass_kg)
        if hydraulic and check_stability:
            try:
                check_design_station(params)
            except ValueError as exc:
                raise ScenarioError(f"actuator: {exc}") from None
        try:
            spec = build_spec(variant)
        except ValueError as exc:
            raise ScenarioError(str(exc)) from None
        # One stroke: the actuator's. The pan joints' limits are set from it.
        for c in names.CORNERS:
            spec.joint(names.pan_joint(c)).range = [-params.half_stroke_m, params.half_stroke_m]
        if hydraulic:
            add_hydraulic_actuators(spec, params, names.CORNERS)
        self.model = model = spec.compile()
        self.index = RigIndex.of(model)
        obj = mujoco.mjtObj
        self.sensors = np.array([model.sensor_adr[mujoco.mj_name2id(model, obj.mjOBJ_SENSOR, names.tire_sensor(c))]
                                 for c in names.CORNERS])
        if hydraulic:
            self.actuators = np.array([mujoco.mj_name2id(model, obj.mjOBJ_ACTUATOR, names.hydraulic_actuator(c))
                                       for c in names.CORNERS])
            dim = int(model.actuator_actnum[self.actuators[0]])
            self.act_index = model.actuator_actadr[self.actuators][:, None] + np.arange(dim)[None, :]
        if hydraulic and check_stability:
            self.check_stable()

    # ------------------------------------------------------------------------ properties
    @property
    def dt_s(self) -> float:
        """float, s: the simulation time step."""
        return float(self.model.opt.timestep)

    @property
    def half_stroke_m(self) -> float:
        """float, m: the actuators' travel from mid-stroke (``actuator.stroke_m / 2``)."""
        return self.params.half_stroke_m

    @property
    def tire_stiffness_N_per_m(self) -> np.ndarray:
        """numpy.ndarray, N/m, (4,): each wheel station's tire stiffness, as compiled."""
        return tire_stiffness(self.model, self.index)

    @property
    def wheelbase_m(self) -> float:
        """float, m: front-to-rear axle distance of the compiled truck."""
        data = mujoco.MjData(self.model)
        mujoco.mj_kinematics(self.model, data)
        sid = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, names.wheel_site(c)) for c in ("fl", "rl")]
        return float(data.site_xpos[sid[0], 0] - data.site_xpos[sid[1], 0])

    @property
    def truck_mass_kg(self) -> float:
        """float, kg: chassis, payload and axles (pans excluded)."""
        ids = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, n) for n in names.TRUCK_BODIES]
        return float(self.model.body_mass[ids].sum())

    @property
    def unsprung_kg(self) -> np.ndarray:
        """numpy.ndarray, kg, (4,): half the mass of the axle over each pan."""
        return np.array([0.5 * self.model.body_mass[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY,
                                                                      names.axle_body(c))] for c in names.CORNERS])

    def road_drive(self) -> Drive:
        """The scenario's road as the four pan drives on this rig's time step, stroke-checked."""
        return road_drive(self.scenario, dt_s=self.dt_s, wheelbase_m=self.wheelbase_m,
                          half_stroke_m=self.half_stroke_m)

    # ------------------------------------------------------------------------ rest, linear
    def rest_state(self, pan_z_m=None) -> mujoco.MjData:
        """MjData at static rest: the truck in equilibrium on the pans (at ``pan_z_m``, m,
        default mid-stroke); with the actuators, each one's pressures carrying its tire load
        plus the pan's weight and the spool at the flow balance."""
        model, data = self.model, mujoco.MjData(self.model)
        static_equilibrium(model, data, pan_z_m=np.zeros(4) if pan_z_m is None else pan_z_m)
        if self.hydraulic:
            loads = self._actuator_loads(data)
            for i, act in enumerate(self.actuators):
                data.act[self.act_index[i]] = equilibrium_activation(self.params, float(loads[i]))
                data.ctrl[act] = 0.0
            mujoco.mj_forward(model, data)
        return data

    def _actuator_loads(self, data: mujoco.MjData) -> np.ndarray:
        g = -self.model.opt.gravity[2]
        pans = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, names.pan_body(c)) for c in names.CORNERS]
        return data.actuator_force[self.index.tire_actuator] + self.model.body_mass[pans] * g

    def static_loads_N(self) -> np.ndarray:
        """numpy.ndarray, N, (4,): each actuator's static load at rest (tire force + pan weight)."""
        return self._actuator_loads(self.rest_state())

    def linearize(self, eps: float = 1e-6) -> PlantLinearization:
        """The closed-loop plant (truck, pans, four actuators) linearized at static rest.

        ``mujoco.mjd_transitionFD`` (centred differences with step ``eps`` in the state's units)
        with the hydraulic callbacks installed and leaf-spring dry friction off (it locks the
        springs at rest and has no derivative), for the linearization only.
        """
        if not self.hydraulic:
            raise ValueError("linearize() needs the hydraulic rig (Rig(scenario, hydraulic=True))")
        model, data = self.model, self.rest_state()
        n = 2 * model.nv + model.na
        a, b = np.zeros((n, n)), np.zeros((n, model.nu))
        with hydraulic_callbacks(model), friction_disabled(model):
            mujoco.mj_forward(model, data)
            mujoco.mjd_transitionFD(model, data, eps, True, a, b, None, None)
        c = np.zeros((8, n))
        c[np.arange(4), self.index.pan_dof] = 1.0  # no quaternions: the qpos tangent is qpos itself
        c[4 + np.arange(4), model.nv + self.index.pan_dof] = 1.0
        return PlantLinearization(a=a, b=b[:, self.actuators].copy(), c=c, dt_s=self.dt_s,
                                  kt_N_per_m=np.asarray(self.tire_stiffness_N_per_m, float),
                                  load_N=np.asarray(self._actuator_loads(data), float),
                                  unsprung_kg=self.unsprung_kg)

    def check_stable(self) -> None:
        """Refuse a rig whose linearized closed loop under this truck is unstable.

        Raises
        ------
        ScenarioError
            Naming the unstable pole and the parameters to change.
        """
        lam = self.linearize().poles()
        worst = lam[np.argmax(lam.real)]
        # A growth rate below 1e-3 1/s is numerical noise of the finite differences around
        # the neutrally stable integrator states, not an instability over a run of minutes.
        if worst.real > 1e-3:
            raise ScenarioError(
                f"the rig's closed loop under this truck is unstable: pole {worst.real:.3g} "
                f"{'+-' if worst.imag else ''}{abs(worst.imag):.4g}j rad/s ({abs(worst.imag) / (2 * np.pi):.1f} Hz); "
                "raise actuator.kdp_per_Pa, lower actuator.kp_per_m or raise actuator.spool_hz")

    # ------------------------------------------------------------------------ running
    def run(self, drive: Drive, *, rate_hz: float, progress=None, pose_rate_hz: float | None = None) -> RigRecord:
        """Run ``drive`` from rest and record at ``rate_hz`` from its first step at t >= 0.

        Parameters
        ----------
        drive : Drive
            One sample per time step of the model (its ``t_s`` may start below 0: a lead-in).
        rate_hz : float, Hz
            Output rate; must divide the simulation rate.
        progress : callable, optional
            ``progress(simulated_s, total_s)``.
        pose_rate_hz : float, Hz, optional
            Also sample the bodies' poses at this (video) rate for a recording.

        Raises
        ------
        SimulationError
            A MuJoCo warning or diverging states, naming the simulated time.
        """
        if drive.t_s.size > 1 and abs(drive.dt_s - self.dt_s) > 1e-9 * self.dt_s:
            raise ValueError(f"the drive's step {drive.dt_s:g} s is not the model's {self.dt_s:g} s")
        decim = 1.0 / (rate_hz * self.dt_s)
        if abs(decim - round(decim)) > 1e-9:
            raise ScenarioError(f"output_rate_hz = {rate_hz:g} Hz must divide the simulation rate "
                                f"{1.0 / self.dt_s:g} Hz")
        n_out = output_schedule(drive.t_s, self.dt_s, rate_hz)[2]
        check_memory(0, n_out, f"a drive of {drive.t_s[-1] - drive.t_s[0]:g} s recorded at {rate_hz:g} Hz is "
                     f"{n_out:.3g} output samples", "shorten duration_s or lower output_rate_hz")
        with mujoco_warnings_captured():
            if self.hydraulic:
                return self._run_hydraulic(drive, rate_hz, progress, pose_rate_hz)
            return self._run_kinematic(drive, rate_hz, progress, pose_rate_hz)

    def _poses(self, drive: Drive, decim: int, pose_rate_hz):
        if pose_rate_hz is None:
            return None
        from scenarios.core.poses import PoseRecorder

        return PoseRecorder(self.model, drive.t_s, pose_rate_hz, every=decim)

    def _run_kinematic(self, drive: Drive, rate_hz, progress, pose_rate_hz) -> RigRecord:
        model, idx = self.model, self.index
        data = self.rest_state(pan_z_m=drive.z_m[0])
        k0, decim, n_out = output_schedule(drive.t_s, self.dt_s, rate_hz)
        pan, force = np.empty((n_out, 4)), np.empty((n_out, 4))
        watch = Watch(drive.t_s, self.dt_s, progress)
        poses = self._poses(drive, decim, pose_rate_hz)
        qa, da, tires = idx.pan_qpos, idx.pan_dof, idx.tire_actuator
        z, vz = drive.z_m, drive.v_mps
        # The step loop in Python (MuJoCo cannot prescribe joint motion inside a rollout): views
        # and the warning window hoisted out of it, the cost of a step is mj_step's plus ~2 us.
        qpos, qvel, act_force, step = data.qpos, data.qvel, data.actuator_force, mujoco.mj_step
        check, j = watch.check, 0
        for k in range(drive.t_s.size):
            qpos[qa] = z[k]
            qvel[da] = vz[k]
            if k >= k0 and (k - k0) % decim == 0:
                pan[j] = z[k]
                step(model, data)
                force[j] = act_force[tires]
                j += 1
                if poses is not None:
                    poses(data, k)
            else:
                step(model, data)
            if k % check == check - 1:
                watch.checked(data, k - check + 1, k)
        watch.finish(data)
        if not np.all(np.isfinite(force)):
            raise SimulationError("the simulation produced non-finite tire forces")
        return RigRecord(t_s=drive.t_s[k0::decim].copy(), x_ref_m=drive.z_m[k0::decim].copy(), pan_m=pan,
                         tire_force_N=force, poses=None if poses is None else poses.track())

    def _run_hydraulic(self, drive: Drive, rate_hz, progress, pose_rate_hz) -> RigRecord:
        model = self.model
        data = self.rest_state()
        k0, decim, n_out = output_schedule(drive.t_s, self.dt_s, rate_hz)
        dim = self.act_index.shape[1]
        pan, force, states = np.empty((n_out, 4)), np.empty((n_out, 4)), np.empty((n_out, 4, dim))

        def diverged(data_: mujoco.MjData, t: float) -> None:
            if not np.all(np.isfinite(data_.act)):
                raise SimulationError(f"the hydraulic states diverged by t = {t:.4f} s of simulated time; "
                                      "the actuator parameters make the loop unstable")

        watch = Watch(drive.t_s, self.dt_s, progress, extra=diverged)
        kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
        state = np.empty(mujoco.mj_stateSize(model, kind))
        mujoco.mj_getState(model, data, state, kind)
        q0, a0 = 1, 1 + model.nq + model.nv  # offsets of qpos and act in a FULLPHYSICS state
        qa, hyd, sensors = self.index.pan_qpos, self.actuators, self.sensors
        poses = self._poses(drive, decim, pose_rate_hz)
        scratch = mujoco.MjData(model) if poses is not None else None
        frames = set(int(k) for k in poses.steps) if poses is not None else set()
        # Rollouts of ROLLOUT_CHECKS warning windows each; a rollout that warned or diverged is
        # replayed window by window from its first state to name the window (deterministic).
        n, chunk = drive.t_s.size, watch.check * ROLLOUT_CHECKS
        ctrl = np.zeros((chunk, model.nu))
        with hydraulic_callbacks(model):
            for k in range(0, n, chunk):
                kk = min(chunk, n - k)
                ctrl[:kk, hyd] = drive.z_m[k:k + kk]
                warm = data.qacc_warmstart.copy()
                out_state, out_sensor = rollout.rollout(model, data, state, ctrl[:kk], initial_warmstart=warm)
                if watch.warned(data) or not np.all(np.isfinite(out_state[0, -1])):
                    self._replay_windows(watch, data, state, warm, ctrl[:kk], k)
                # Output samples in this chunk: the pre-step state of step k+i is the chunk's
                # initial state (i = 0) or the state after step k+i-1; forces are step k+i's.
                steps = np.arange(k, k + kk)
                rows = steps[(steps >= k0) & ((steps - k0) % decim == 0)]
                if rows.size:
                    i = rows - k
                    j = (rows - k0) // decim
                    pre = np.where((i == 0)[:, None], state[None, :], out_state[0, np.maximum(i - 1, 0)])
                    pan[j] = pre[:, q0 + qa]
                    states[j] = pre[:, a0 + self.act_index]
                    force[j] = out_sensor[0, i][:, sensors]
                    if poses is not None:
                        for row, k_row in zip(pre, rows):
                            if int(k_row) in frames:
                                scratch.qpos[:] = row[q0:q0 + model.nq]
                                mujoco.mj_kinematics(model, scratch)
                                poses(scratch, int(k_row))
                state = out_state[0, -1].copy()
                watch.checked(data, k, k + kk - 1)
            watch.finish(data)
        t_out = drive.t_s[k0::decim].copy()
        return RigRecord(t_s=t_out, x_ref_m=drive.z_m[k0::decim].copy(), pan_m=pan, tire_force_N=force,
                         states=states, events=self._events(states, t_out),
                         poses=None if poses is None else poses.track())

    def _replay_windows(self, watch: Watch, data, state, warm, ctrl, k0: int) -> None:
        """Replay a rollout that warned or diverged, one warning window at a time from its first
        ``state``, so that :class:`Watch` names the window where it went wrong (raises)."""
        data.warning.number[:] = 0
        w = watch.check
        for j in range(0, ctrl.shape[0], w):
            out_state, _ = rollout.rollout(self.model, data, state, ctrl[j:j + w], initial_warmstart=warm)
            watch.checked(data, k0 + j, k0 + j + ctrl[j:j + w].shape[0] - 1)
            state, warm = out_state[0, -1].copy(), data.qacc_warmstart.copy()

    def _events(self, states: np.ndarray, t_s: np.ndarray) -> dict:
        out = {}
        for name, mask in hydraulic_events(states, self.params).items():
            mask = np.asarray(mask)
            per = {}
            for i, c in enumerate(names.CORNERS):
                m_c = mask[:, i] if mask.ndim == 2 else mask
                if np.any(m_c):
                    per[c] = {"samples": int(np.sum(m_c)), "first_time_s": float(t_s[np.argmax(m_c)])}
            if per:
                out[name] = per
        return out
