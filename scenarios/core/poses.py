"""Body poses sampled during a run at video rate, for the 3D view of a recording.

Numpy on MuJoCo's arrays, no rerun: the runs record poses here when a recording is asked
for, and :mod:`rigsim.scenarios.review.recording` draws them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import mujoco

__all__ = ["DEFAULT_POSE_RATE_HZ", "Geoms", "PoseTrack", "PoseRecorder", "model_geoms", "drawn_bodies"]

#: Video rate of the body poses, Hz (divides MuJoCo's 10 kHz; 60 s make 3000 frames).
DEFAULT_POSE_RATE_HZ = 50.0
#: The drawable geom types by their ``mjtGeom`` name. MuJoCo is imported where a model is read
#: (:func:`model_geoms`, :func:`drawn_bodies`), not by this module: the recording process
#: (:mod:`rigsim.scenarios.review.recording_process`) unpickles poses and never steps (0.19 s of CPU less
#: beside the run).
_KIND_NAMES = {"mjGEOM_PLANE": "plane", "mjGEOM_SPHERE": "sphere", "mjGEOM_CAPSULE": "capsule",
               "mjGEOM_CYLINDER": "cylinder", "mjGEOM_BOX": "box"}


@dataclass(frozen=True)
class Geoms:
    """Visual geoms of a compiled model, each in its body's frame (MuJoCo conventions).

    Attributes
    ----------
    body : tuple of str
        Name of each geom's body (``"world"`` for static scenery).
    kind : tuple of str
        ``"box"``, ``"cylinder"``, ``"capsule"``, ``"sphere"`` or ``"plane"``.
    size_m : numpy.ndarray, m, (G, 3)
        MuJoCo ``geom_size``: half sizes (box), radius and half length (cylinder, capsule).
    pos_m : numpy.ndarray, m, (G, 3)
        Centre in the body frame.
    quat_wxyz : numpy.ndarray, (G, 4)
        Orientation in the body frame, MuJoCo's scalar-first order.
    rgba : numpy.ndarray, (G, 4)
        Colour, 0..1.
    """

    body: tuple[str, ...]
    kind: tuple[str, ...]
    size_m: np.ndarray
    pos_m: np.ndarray
    quat_wxyz: np.ndarray
    rgba: np.ndarray


def model_geoms(model: mujoco.MjModel, groups: Sequence[int] = (0, 1, 2)) -> Geoms:
    """The geoms of ``model`` in ``groups`` whose shape can be drawn (see :class:`Geoms`).

    Meshes and height fields are skipped (the truck model has none).
    """
    import mujoco

    kinds = {int(getattr(mujoco.mjtGeom, k)): v for k, v in _KIND_NAMES.items()}
    keep = [g for g in range(model.ngeom)
            if int(model.geom_group[g]) in groups and int(model.geom_type[g]) in kinds]
    rgba = model.geom_rgba[keep].copy()
    for i, g in enumerate(keep):
        if model.geom_matid[g] >= 0:
            rgba[i] = model.mat_rgba[model.geom_matid[g]]
    return Geoms(
        body=tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(model.geom_bodyid[g])) for g in keep),
        kind=tuple(kinds[int(model.geom_type[g])] for g in keep),
        size_m=model.geom_size[keep].copy(),
        pos_m=model.geom_pos[keep].copy(),
        quat_wxyz=model.geom_quat[keep].copy(),
        rgba=rgba,
    )


@dataclass(frozen=True)
class PoseTrack:
    """World poses of the model's bodies over time, with the geoms that draw them.

    Attributes
    ----------
    t_s : numpy.ndarray, s, (M,)
        Sample times, on the run's time axis (0 = end of the lead-in).
    bodies : tuple of str
        Body names, B of them.
    position_m : numpy.ndarray, m, (M, B, 3)
        Body frame origins in the world (MuJoCo ``data.xpos``).
    quat_wxyz : numpy.ndarray, (M, B, 4)
        Body orientations in the world, scalar first (MuJoCo ``data.xquat``).
    geoms : Geoms
        The visual geoms, each attached to one of ``bodies`` or to ``"world"``.
    """

    t_s: np.ndarray
    bodies: tuple[str, ...]
    position_m: np.ndarray
    quat_wxyz: np.ndarray
    geoms: Geoms

    def __post_init__(self):
        m, b = np.shape(self.t_s)[0], len(self.bodies)
        if np.shape(self.position_m) != (m, b, 3) or np.shape(self.quat_wxyz) != (m, b, 4):
            raise ValueError(
                f"PoseTrack: position_m {np.shape(self.position_m)} and quat_wxyz "
                f"{np.shape(self.quat_wxyz)} must be ({m}, {b}, 3) and ({m}, {b}, 4)"
            )


def drawn_bodies(model: mujoco.MjModel, geoms: Geoms) -> tuple[list[int], tuple[str, ...]]:
    import mujoco

    names = tuple(dict.fromkeys(n for n in geoms.body if n != "world"))
    return [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in names], names


class PoseRecorder:
    """Samples the world poses of the drawn bodies at video rate during a run.

    Construct it once the run's model is compiled and call it after ``mujoco.mj_step`` with
    the step's index ``k``; take :meth:`track` at the end. After ``mj_step`` for step ``k``,
    ``data.xpos``/``data.xquat`` hold the kinematics of the state at ``t_s[k]`` (the forward
    pass precedes the integration): the instant of the tire force read there, so the sample is
    stamped ``t_s[k]``.

    It may be called at every step or only every ``every``-th step from the first step at
    t >= 0 (for example inside the runner's ``if record:`` block at the output rate): the
    frame interval is rounded to a whole multiple of ``every`` steps, so every frame falls on a
    call. A call between frames costs one integer compare.

    Parameters
    ----------
    model : mujoco.MjModel
        The model being stepped.
    t_s : numpy.ndarray, s
        Time of every step (``Drive.t_s``: negative during the lead-in). Frames are taken from
        the first step at t >= 0, as the runner's output schedule.
    rate_hz : float, Hz
        Video rate.
    every : int
        The steps between two calls (1: every step).
    """

    def __init__(self, model: mujoco.MjModel, t_s: np.ndarray, rate_hz: float = DEFAULT_POSE_RATE_HZ,
                 every: int = 1):
        if not rate_hz > 0:
            raise ValueError(f"rate_hz must be > 0, got {rate_hz!r}")
        if int(every) != every or every < 1:
            raise ValueError(f"every must be a positive whole number of steps, got {every!r}")
        dt = float(model.opt.timestep)
        decim = int(every) * max(1, int(round(1.0 / (rate_hz * dt * every))))
        self._t_all = np.asarray(t_s, dtype=float)
        k0 = int(np.searchsorted(self._t_all, -0.5 * dt))
        self.steps = np.arange(k0, self._t_all.size, decim)
        self._k0, self._decim = k0, decim
        self.geoms = model_geoms(model)
        ids, self.bodies = drawn_bodies(model, self.geoms)
        self._ids = np.asarray(ids, dtype=np.intp)
        self._t = np.full(self.steps.size, np.nan)
        self._pos = np.full((self.steps.size, len(self._ids), 3), np.nan)
        self._quat = np.full((self.steps.size, len(self._ids), 4), np.nan)
        self._j = 0
        self._next = int(self.steps[0]) if self.steps.size else self._t_all.size

    def is_frame(self, steps) -> np.ndarray:
        """Which of the step indices ``steps`` take a frame (bool, their shape): :attr:`steps`,
        told by arithmetic, so a caller that must compute the kinematics first (a rollout's
        recorded states) does so for the frames only."""
        s = np.asarray(steps, dtype=np.int64)
        return (s >= self._k0) & (s < self._t_all.size) & ((s - self._k0) % self._decim == 0)

    def __call__(self, data: mujoco.MjData, k: int) -> None:
        """Record the poses if frame time has come at step ``k`` (call after ``mj_step``)."""
        if k < self._next:
            return
        j = self._j
        self._t[j] = self._t_all[k]
        self._pos[j] = data.xpos[self._ids]
        self._quat[j] = data.xquat[self._ids]
        self._j = j + 1
        self._next = self._k0 + ((k - self._k0) // self._decim + 1) * self._decim
        if j + 1 >= self.steps.size:
            self._next = self._t_all.size

    def track(self) -> PoseTrack:
        """The frames taken so far as a :class:`PoseTrack`."""
        j = self._j
        return PoseTrack(self._t[:j].copy(), self.bodies, self._pos[:j].copy(), self._quat[:j].copy(), self.geoms)
