"""Stepping a :class:`~rigsim.scenarios.core.rig.Rig` through a drive: the only MuJoCo stepping loops.

* :func:`run_hydraulic`, the rig test: the drive is the actuators' reference x_ref in ``ctrl``;
  the actuator states live in MuJoCo's activation vector, advanced by the callbacks of
  :mod:`rigsim.hydraulics.bridge` (installed for the run only). Steps in C with ``mujoco.rollout``,
  about :data:`ROLLOUT_STEPS` steps (whole warning windows) per call (the constraint warm start carried from call to
  call: bit-identical to a loop of ``mj_step``); a call that warned or diverged is replayed window
  by window from its first state so that the error names its 10 ms of simulated time.
* :func:`run_kinematic`, the road test: the pans follow the drive exactly, as mocap bodies
  whose positions (and, through the tires' ``ctrl``, velocities) each step of the rollout sets.

Both step in rollouts of about :data:`ROLLOUT_STEPS` steps and read the drive one rollout at a
time (``drive.chunk``, ``drive.held``), so a road drive made on demand (:class:`~rigsim.scenarios.core.road_drive.RoadDrive`) is never held at
the step rate: memory grows with the output samples only.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import mujoco
import numpy as np
from mujoco import rollout

from rigsim.hydraulics.bridge import hydraulic_callbacks
from rigsim.hydraulics.events import events as hydraulic_events
from rigsim.hydraulics.params import STATE_NAMES
from rigsim.mjcf import names
from rigsim.mjcf.physics import tire_law
from rigsim.scenarios.core.watch import SimulationError, Watch, output_schedule

__all__ = ["RigRecord", "run_hydraulic", "run_kinematic", "ROLLOUT_STEPS", "RECORDED_STATES"]

MPA = 1e6  # Pa per MPa: the pressure states are in MPa (see rigsim.hydraulics.params.STATE_NAMES)
#: The actuator states a rig run records: name in the record -> (index in STATE_NAMES, scale to SI).
RECORDED_STATES = {"spool": (STATE_NAMES.index("spool"), 1.0), "p1_Pa": (STATE_NAMES.index("p1_MPa"), MPA),
                   "p2_Pa": (STATE_NAMES.index("p2_MPa"), MPA)}
#: Steps per rollout call of a hydraulic run, rounded down to whole warning windows
#: (rigsim.scenarios.core.watch.CHECK_EVERY_S; at least one): 1 s at the rig test's 1e-3 s step, so the
#: calls' Python overhead (output rows, events, warning check) is ~1 % of the stepping.
ROLLOUT_STEPS = 1000
#: What a road-test step's controls set: ``ctrl`` (the tires' pan velocities) and the mocap
#: bodies' positions (the pans).
_PRESCRIBED = int(mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_MOCAP_POS)


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
    hydraulic : Mapping or None
        Rig only: the recorded actuator states in SI, each (n, 4): ``spool`` (1, normalised),
        ``p1_Pa`` and ``p2_Pa`` (chamber pressures, Pa); the other activation states
        (:data:`rigsim.hydraulics.params.STATE_NAMES`) are not kept (memory grows with the record).
    events : Mapping
        ``{event: {corner: {"samples": int, "first_time_s": float (s)}}}`` for the events that
        occurred (spool saturation, cavitation, over-pressure; rig only).
    poses : rigsim.scenarios.core.poses.PoseTrack or None
        Body poses at video rate when asked for.
    """

    t_s: np.ndarray
    x_ref_m: np.ndarray
    pan_m: np.ndarray
    tire_force_N: np.ndarray
    hydraulic: Mapping | None = None
    events: Mapping = field(default_factory=dict)
    poses: object = None


def _pose_recorder(model, drive, decim: int, pose_rate_hz):
    if pose_rate_hz is None:
        return None
    from rigsim.scenarios.core.poses import PoseRecorder

    return PoseRecorder(model, drive.times(0, drive.n_steps), pose_rate_hz, every=decim)


def _output_rows(k: int, kk: int, k0: int, decim: int) -> tuple[np.ndarray, np.ndarray]:
    """(i, j): the steps k + i of a chunk of ``kk`` that are output samples, and their rows."""
    steps = np.arange(k, k + kk)
    rows = steps[(steps >= k0) & ((steps - k0) % decim == 0)]
    return rows - k, (rows - k0) // decim


def run_kinematic(rig, drive, rate_hz: float, progress, pose_rate_hz) -> RigRecord:
    """The road test of ``rig`` (``hydraulic=False``): the pans follow ``drive`` exactly.

    The pans are mocap bodies (``build_spec(pans="mocap")``): each step holds each pan at the
    drive's mid-step value (:meth:`~rigsim.scenarios.core.drive.Drive.held`) moving at its mean velocity
    over the step, (z_k+1 - z_k) / dt, fed to the tire's damping through ``ctrl``. The tire force
    recorded at t_k is the tire's law (:func:`rigsim.mjcf.physics.tire_law`) with the pan at z_k moving
    at v_k, from the tendon's length and rate MuJoCo computed at the step's start with the pan at
    mid-step: the tendon is near vertical, so it is longer by (held - z_k).
    """
    model, idx = rig.model, rig.index
    data = rig.rest_state(pan_z_m=drive.chunk(0, 1)[0][0])
    k0, decim, n_out = output_schedule(drive, rig.dt_s, rate_hz)
    t_out, x_ref, pan, force = np.empty(n_out), np.empty((n_out, 4)), np.empty((n_out, 4)), np.empty((n_out, 4))
    watch = Watch(drive, rig.dt_s, progress)
    state = _full_state(model, data)
    q0 = 1  # offset of qpos in a FULLPHYSICS state
    poses = _pose_recorder(model, drive, decim, pose_rate_hz)
    frames = _Frames(model, poses)
    n, chunk, dt = drive.n_steps, _chunk_steps(watch), rig.dt_s
    # The controls of a step: ctrl (the tires' pan velocities) then every mocap body's position.
    control = np.zeros((chunk, model.nu + 3 * model.nmocap))
    mocap = control[:, model.nu:].reshape(chunk, model.nmocap, 3)
    mocap[:] = data.mocap_pos
    base_z = model.body_pos[idx.pan_body, 2]
    lengths, rates = rig.tire_length_sensors, rig.tire_rate_sensors
    for k in range(0, n, chunk):
        kk = min(chunk, n - k)
        z_next, v_next = drive.chunk(k, min(k + kk + 1, n))
        z, v = z_next[:kk], v_next[:kk]
        held = drive.held(k, k + kk)
        rate = np.empty((kk, 4))
        m = z_next.shape[0] - 1  # steps with a next sample; the drive's last step keeps its velocity
        rate[:m] = (z_next[1:] - z_next[:-1]) / dt
        rate[m:] = v[m:]
        control[:kk, idx.tire_actuator] = rate
        mocap[:kk, idx.pan_mocap, 2] = base_z + held
        out_state, out_sensor = _rollout_watched(model, watch, data, state, control[:kk], k, _PRESCRIBED)
        i, j = _output_rows(k, kk, k0, decim)
        if i.size:
            t_out[j] = drive.times(k, k + kk)[i]
            x_ref[j] = z[i]
            pan[j] = z[i]
            s = out_sensor[0, i]
            force[j] = tire_law(model, idx, s[:, lengths] + (held[i] - z[i]), s[:, rates] - v[i])
            if poses is not None:
                pre = _pre_step(state, out_state, i)
                frames.record(pre[:, q0:q0 + model.nq], i + k, mocap_z=(idx.pan_mocap, base_z + z[i]))
        state = out_state[0, -1].copy()
        watch.checked(data, k, k + kk - 1)
    watch.finish(data)
    if not np.all(np.isfinite(force)):
        raise SimulationError("the simulation produced non-finite tire forces")
    return RigRecord(t_s=t_out, x_ref_m=x_ref, pan_m=pan, tire_force_N=force,
                     poses=None if poses is None else poses.track())


def run_hydraulic(rig, drive, rate_hz: float, progress, pose_rate_hz) -> RigRecord:
    """The rig test of ``rig`` (``hydraulic=True``): ``drive`` is the actuators' reference x_ref."""
    model = rig.model
    data = rig.rest_state()
    k0, decim, n_out = output_schedule(drive, rig.dt_s, rate_hz)
    t_out, x_ref = np.empty(n_out), np.empty((n_out, 4))
    pan, force = np.empty((n_out, 4)), np.empty((n_out, 4))
    hydraulic = {name: np.empty((n_out, 4)) for name in RECORDED_STATES}
    events = _EventLog(rig.params)

    def diverged(data_: mujoco.MjData, t: float) -> None:
        if not np.all(np.isfinite(data_.act)):
            raise SimulationError(f"the hydraulic states diverged by t = {t:.4f} s of simulated time; "
                                  "the actuator parameters make the loop unstable")

    watch = Watch(drive, rig.dt_s, progress, extra=diverged)
    state = _full_state(model, data)
    q0, a0 = 1, 1 + model.nq + model.nv  # offsets of qpos and act in a FULLPHYSICS state
    qa, hyd, sensors = rig.index.pan_qpos, rig.actuators, rig.sensors
    poses = _pose_recorder(model, drive, decim, pose_rate_hz)
    frames = _Frames(model, poses)
    n, chunk = drive.n_steps, _chunk_steps(watch)
    ctrl = np.zeros((chunk, model.nu))
    with hydraulic_callbacks(model):
        for k in range(0, n, chunk):
            kk = min(chunk, n - k)
            z = drive.chunk(k, k + kk)[0]  # x_ref at the steps, recorded; the velocity is not needed
            ctrl[:kk, hyd] = drive.held(k, k + kk)  # what each step holds: x_ref at mid-step
            out_state, out_sensor = _rollout_watched(model, watch, data, state, ctrl[:kk], k)
            # Output samples in this chunk: their pre-step states (:func:`_pre_step`); forces are step k+i's.
            i, j = _output_rows(k, kk, k0, decim)
            if i.size:
                pre = _pre_step(state, out_state, i)
                t_out[j] = drive.times(k, k + kk)[i]
                x_ref[j] = z[i]
                pan[j] = pre[:, q0 + qa]
                states = pre[:, a0 + rig.act_index]  # (rows, 4, 5) in STATE_NAMES order
                for name, (col, scale) in RECORDED_STATES.items():
                    hydraulic[name][j] = states[:, :, col] * scale
                events.add(states, t_out[j])
                force[j] = out_sensor[0, i][:, sensors]
                if poses is not None:
                    frames.record(pre[:, q0:q0 + model.nq], i + k)
            state = out_state[0, -1].copy()
            watch.checked(data, k, k + kk - 1)
        watch.finish(data)
    return RigRecord(t_s=t_out, x_ref_m=x_ref, pan_m=pan, tire_force_N=force,
                     hydraulic=hydraulic, events=events.summary(),
                     poses=None if poses is None else poses.track())


def _full_state(model, data) -> np.ndarray:
    """``data``'s full physics state (``mjSTATE_FULLPHYSICS``), the initial state of a rollout."""
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, state, kind)
    return state


class _Frames:
    """Body poses for a recording, taken from a rollout's recorded states on a scratch MjData."""

    def __init__(self, model, poses) -> None:
        self.model, self.poses = model, poses
        self.scratch = mujoco.MjData(model) if poses is not None else None

    def record(self, qpos: np.ndarray, steps: np.ndarray, mocap_z=None) -> None:
        """Record the frames among ``steps`` (their pre-step ``qpos`` rows); ``mocap_z``: (mocap
        ids, heights (rows, 4), m) of prescribed pans at those steps."""
        for r in np.flatnonzero(self.poses.is_frame(steps)):
            self.scratch.qpos[:] = qpos[r]
            if mocap_z is not None:
                self.scratch.mocap_pos[mocap_z[0], 2] = mocap_z[1][r]
            mujoco.mj_kinematics(self.model, self.scratch)
            self.poses(self.scratch, int(steps[r]))


def _chunk_steps(watch: Watch) -> int:
    """Steps per rollout call: :data:`ROLLOUT_STEPS` rounded down to whole warning windows (at least one)."""
    return watch.check * max(1, ROLLOUT_STEPS // watch.check)


def _rollout_watched(model, watch: Watch, data, state, controls, k0: int,
                     control_spec: int = int(mujoco.mjtState.mjSTATE_CTRL)):
    """One rollout call from ``state`` (steps ``k0`` on), carrying ``data``'s constraint warm start;
    a call that warned or diverged is replayed window by window so that the error names its
    window (raises). Returns rollout's (state, sensordata), each (1, steps, ...)."""
    warm = data.qacc_warmstart.copy()
    out_state, out_sensor = rollout.rollout(model, data, state, controls, control_spec=control_spec,
                                            initial_warmstart=warm)
    if watch.warned(data) or not np.all(np.isfinite(out_state[0, -1])):
        _replay_windows(model, watch, data, state, warm, controls, k0, control_spec)
    return out_state, out_sensor


def _pre_step(state: np.ndarray, out_state: np.ndarray, i: np.ndarray) -> np.ndarray:
    """The states before a chunk's steps ``i``: the chunk's initial ``state`` for i = 0, else the
    rollout's state after step i - 1."""
    return np.where((i == 0)[:, None], state[None, :], out_state[0, np.maximum(i - 1, 0)])


def _replay_windows(model, watch: Watch, data, state, warm, ctrl, k0: int,
                    control_spec: int = int(mujoco.mjtState.mjSTATE_CTRL)) -> None:
    """Replay a rollout that warned or diverged, one warning window at a time from its first
    ``state``, so that :class:`Watch` names the window where it went wrong (raises)."""
    data.warning.number[:] = 0
    w = watch.check
    for j in range(0, ctrl.shape[0], w):
        out_state, _ = rollout.rollout(model, data, state, ctrl[j:j + w], control_spec=control_spec,
                                       initial_warmstart=warm)
        watch.checked(data, k0 + j, k0 + j + ctrl[j:j + w].shape[0] - 1)
        state, warm = out_state[0, -1].copy(), data.qacc_warmstart.copy()


class _EventLog:
    """Hydraulic events (:func:`rigsim.hydraulics.events.events`) counted chunk by chunk: per event and
    corner the output samples it held on and the first time, s."""

    def __init__(self, params) -> None:
        self.params, self.log = params, {}

    def add(self, states: np.ndarray, t_s: np.ndarray) -> None:
        for name, mask in hydraulic_events(states, self.params).items():
            mask = np.asarray(mask)
            for i, c in enumerate(names.CORNERS):
                m_c = mask[:, i] if mask.ndim == 2 else mask
                if np.any(m_c):
                    per = self.log.setdefault(name, {})
                    if c not in per:
                        per[c] = {"samples": 0, "first_time_s": float(t_s[np.argmax(m_c)])}
                    per[c]["samples"] += int(np.sum(m_c))

    def summary(self) -> dict:
        """``{event: {corner: {"samples": int, "first_time_s": float (s)}}}`` in the event
        function's order, corners in :data:`rigsim.mjcf.names.CORNERS` order."""
        order = list(hydraulic_events(np.zeros((1, 4, len(STATE_NAMES))), self.params))
        return {name: {c: self.log[name][c] for c in names.CORNERS if c in self.log[name]}
                for name in order if name in self.log}
