"""Physics accessors for the truck-on-rig model: named indices, tire forces, static equilibrium.

The dm_control-style middle layer: the XML describes the model, this module reads and solves it
by name, and the scenario layer (``scenarios``) runs tasks on top. The vibration modes about a
state: :mod:`rigsim.mjcf.modes`."""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

import mujoco
import numpy as np

from rigsim.mjcf.names import (CAB_JOINTS, CORNERS, ENGINE_JOINTS, FRAME_JOINTS, pan_body, pan_joint, tire_actuator,
                               tire_tendon)
from rigsim.errors import RigsimError

__all__ = [
    "TRUCK_JOINTS",
    "OPTIONAL_JOINTS",
    "RigIndex",
    "EquilibriumError",
    "NO_REST",
    "CONTINUATION_STEP",
    "CONTINUATION_MIN",
    "friction_disabled",
    "static_equilibrium",
    "tire_forces",
    "tire_law",
    "tire_stiffness",
]

#: The truck's degrees of freedom (the pans' are :func:`rigsim.mjcf.names.pan_joint`; a suspended cab, a
#: flexible frame and an engine on mounts add :data:`OPTIONAL_JOINTS`).
TRUCK_JOINTS: tuple[str, ...] = (
    "chassis_z",
    "chassis_pitch",
    "chassis_roll",
    "front_axle_z",
    "front_axle_roll",
    "rear_axle_z",
    "rear_axle_roll",
)

#: The plant features' joints, each group in a model only with its feature, in this order after
#: :data:`TRUCK_JOINTS`: the suspended cab, the flexible frame, the engine on mounts.
OPTIONAL_JOINTS: tuple[tuple[str, ...], ...] = (CAB_JOINTS, FRAME_JOINTS, ENGINE_JOINTS)
#: The physical situation behind a failed static equilibrium, and what to check.
NO_REST = ("the truck finds no rest on its tires: a tire is off its pan or the springs bottom out; check "
           "vehicle.payload_kg, vehicle.payload_x_m and the tire stiffness and free radius")
#: The continuation from mid-stroke where Newton from the mid-stroke pose finds no rest
#: (:func:`static_equilibrium`): the pans move there in steps of at most this fraction of the way,
#: halved where a step finds no rest, down to :data:`CONTINUATION_MIN` (fractions, 1). A step must
#: keep the tires on their pans at its start: Newton's first Jacobian is taken with the truck where
#: the last rest left it, and a tire lifted off by the pans' move gives its axle no restoring force.
#: Measured: the empty truck on pans pitched 45 mm (front +12.1 mm, rear -33.4 mm, the first sample
#: of a class D road at 100 km/h), whose rear tires stiffen beyond 6.3 mm, rests in steps of a tenth
#: and not of a quarter.
CONTINUATION_STEP, CONTINUATION_MIN = 0.25, 1.0 / 64.0


class EquilibriumError(RigsimError, ValueError):
    """The truck has no static rest position on the pans (one sentence: why, and what to check)."""


@dataclass(frozen=True)
class RigIndex:
    """Addresses of the named elements of a compiled truck-on-rig model.

    Attributes
    ----------
    truck_qpos, truck_dof : numpy.ndarray of int
        qpos and dof addresses of :data:`TRUCK_JOINTS`, in that order, then of each group of
        :data:`OPTIONAL_JOINTS` the model has (a suspended cab, a flexible frame, an engine).
    pan_qpos, pan_dof : numpy.ndarray of int
        qpos and dof addresses of :func:`rigsim.mjcf.names.pan_joint` in :data:`rigsim.mjcf.names.CORNERS` order
        (empty when the pans are fixed or prescribed).
    tire_actuator : numpy.ndarray of int
        Actuator ids of :func:`rigsim.mjcf.names.tire_actuator`, in the same order.
    tire_extra : numpy.ndarray of int
        Ids of every other actuator on a tire tendon (:func:`rigsim.mjcf.names.tire_tendon`; the
        progressive tire's second element, ``TruckVariant.tire_progressive_ratio``), empty for
        the XML's tire; a wheel's tire force is the sum of its tendon's elements.
    tire_extra_corner : numpy.ndarray of int
        Index in :data:`rigsim.mjcf.names.CORNERS` of each of :attr:`tire_extra`.
    pan_body : numpy.ndarray of int
        Body ids of :func:`rigsim.mjcf.names.pan_body`, in the same order.
    pan_mocap : numpy.ndarray of int
        Mocap ids of the pans when they are prescribed (``build_spec(pans="mocap")``), else empty.
    """

    truck_qpos: np.ndarray
    truck_dof: np.ndarray
    pan_qpos: np.ndarray
    pan_dof: np.ndarray
    tire_actuator: np.ndarray
    pan_body: np.ndarray
    pan_mocap: np.ndarray
    tire_extra: np.ndarray
    tire_extra_corner: np.ndarray

    @classmethod
    def of(cls, model: mujoco.MjModel) -> "RigIndex":
        def jid(name: str) -> int:
            i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
            if i < 0:
                raise KeyError(f"the model has no joint named {name!r}")
            return i

        present = [g for g in OPTIONAL_JOINTS if all(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n) >= 0
                                                     for n in g)]
        truck = [jid(n) for n in TRUCK_JOINTS + sum(present, ())]
        pan_names = [pan_joint(c) for c in CORNERS]
        has_pans = all(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n) >= 0 for n in pan_names)
        pans = [jid(n) for n in pan_names] if has_pans else []
        tires = []
        for c in CORNERS:
            i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, tire_actuator(c))
            if i < 0:
                raise KeyError(f"the model has no actuator named {tire_actuator(c)!r}")
            tires.append(i)
        as_int = lambda v: np.asarray(v, dtype=np.intp)  # noqa: E731
        tendons = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, tire_tendon(c)) for c in CORNERS]
        on_tendon = model.actuator_trntype == mujoco.mjtTrn.mjTRN_TENDON
        extra = [(a, tendons.index(int(model.actuator_trnid[a, 0]))) for a in range(model.nu)
                 if on_tendon[a] and int(model.actuator_trnid[a, 0]) in tendons and a not in tires]
        bodies = as_int([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, pan_body(c)) for c in CORNERS])
        mocap = model.body_mocapid[bodies]
        return cls(
            truck_qpos=as_int(model.jnt_qposadr[truck]),
            truck_dof=as_int(model.jnt_dofadr[truck]),
            pan_qpos=as_int(model.jnt_qposadr[pans] if pans else []),
            pan_dof=as_int(model.jnt_dofadr[pans] if pans else []),
            tire_actuator=as_int(tires),
            pan_body=bodies,
            pan_mocap=as_int(mocap if np.all(mocap >= 0) else []),
            tire_extra=as_int([a for a, _ in extra]),
            tire_extra_corner=as_int([c for _, c in extra]),
        )


@contextlib.contextmanager
def friction_disabled(model: mujoco.MjModel):
    """Disable MuJoCo's dry friction (``frictionloss``) on ``model`` inside the block.

    Dry friction makes the static equilibrium non-unique and a linearization about rest
    meaningless (the springs are stuck); both are computed without it. The flag is
    restored on exit, also on error.
    """
    bit = int(mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS)
    old = int(model.opt.disableflags)
    model.opt.disableflags = old | bit
    try:
        yield model
    finally:
        model.opt.disableflags = old


def tire_stiffness(model: mujoco.MjModel, index: RigIndex | None = None) -> np.ndarray:
    """Vertical stiffness of each wheel station's tire in N/m (fl, fr, rl, rr), as compiled: the
    tire element's (:func:`rigsim.mjcf.names.tire_actuator`; a progressive tire's below its onset)."""
    index = index or RigIndex.of(model)
    return -model.actuator_biasprm[index.tire_actuator, 1].copy()


def tire_forces(model: mujoco.MjModel, data: mujoco.MjData, index: RigIndex | None = None) -> np.ndarray:
    """Tire forces in N per corner (fl, fr, rl, rr), compression positive.

    Exact: the forces MuJoCo applied at the last force evaluation (``mj_forward`` or the
    start of the last ``mj_step``), summed over each tire tendon's elements (:class:`RigIndex`).
    """
    index = index or RigIndex.of(model)
    force = data.actuator_force[index.tire_actuator].copy()
    np.add.at(force, index.tire_extra_corner, data.actuator_force[index.tire_extra])
    return force


def _affine_law(model: mujoco.MjModel, actuators: np.ndarray, length, rate) -> np.ndarray:
    """b0 + b1 L + b2 dL/dt of ``actuators`` (``actuator_biasprm``) clamped to their force ranges, N."""
    b = model.actuator_biasprm[actuators]
    force = b[:, 0] + b[:, 1] * length + b[:, 2] * rate
    limited = model.actuator_forcelimited[actuators].astype(bool)
    lo = np.where(limited, model.actuator_forcerange[actuators, 0], -np.inf)
    hi = np.where(limited, model.actuator_forcerange[actuators, 1], np.inf)
    return np.clip(force, lo, hi)


def tire_law(model: mujoco.MjModel, index: RigIndex, length_m, rate_m_s) -> np.ndarray:
    """The tires' compiled force law evaluated for given tendon states, N (compression positive).

    F = b0 + b1 L + b2 dL/dt clamped to the actuator's force range (the XML's affine bias,
    ``actuator_biasprm``, with its parameters as compiled): the force MuJoCo applies for a
    tendon of length ``length_m`` (m) changing at ``rate_m_s`` (m/s), each (..., 4) in
    :data:`rigsim.mjcf.names.CORNERS` order; summed over every element on the tire tendon, each clamped
    to its own range (a progressive tire's second element, :attr:`RigIndex.tire_extra`). The road
    test evaluates it at the pan position of an output instant while MuJoCo held the pan at
    mid-step (:mod:`rigsim.scenarios.core.stepping`).
    """
    length, rate = np.asarray(length_m, float), np.asarray(rate_m_s, float)
    force = _affine_law(model, index.tire_actuator, length, rate)
    if index.tire_extra.size:
        corner = index.tire_extra_corner
        extra = _affine_law(model, index.tire_extra, length[..., corner], rate[..., corner])
        for j, c in enumerate(corner):
            force[..., c] += extra[..., j]
    return force


def static_equilibrium(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    *,
    pan_z_m: np.ndarray | None = None,
    tol: float = 1e-10,
    max_iter: int = 30,
) -> np.ndarray:
    """Solve for the truck's rest position on the pans and leave ``data`` there.

    Newton iteration on the truck joints' accelerations (zero velocity, dry friction off)
    with a finite-difference Jacobian; the pans are held at ``pan_z_m``.

    Parameters
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
    pan_z_m : array_like of 4 floats, m, optional
        Pan positions (default: mid-stroke, 0).
    tol : float, m/s^2
        Convergence tolerance on the largest truck-joint acceleration.
    max_iter : int
        Newton iterations before giving up.

    Returns
    -------
    numpy.ndarray
        The equilibrium ``qpos`` (also left in ``data.qpos``, with ``qvel`` zero and
        ``mj_forward`` evaluated; ``data.act`` is left as the caller set it).

    Raises
    ------
    EquilibriumError
        No rest position (a singular Newton step, a diverging or non-converging iteration),
        in one sentence naming the physical situation and the parameters to check.
    """
    idx = RigIndex.of(model)
    data.qvel[:] = 0.0
    z = np.zeros(4) if pan_z_m is None else np.broadcast_to(np.asarray(pan_z_m, dtype=float), (4,))
    q_adr = idx.truck_qpos
    q0 = data.qpos[q_adr].copy()
    try:
        q = _newton_rest(model, data, idx, z, q0, tol, max_iter)
    except EquilibriumError as first:
        if not np.any(z):
            raise
        # Newton from the truck's pose at mid-stroke can start far from contact: pans pitched a few
        # centimetres (a rough road's first sample) leave a tire off its pan, its axle and the frame
        # without a restoring force. Continuation: the rest at mid-stroke, then the pans moved there
        # in steps, each solve started from the last rest.
        try:
            q = _newton_rest(model, data, idx, np.zeros(4), q0, tol, max_iter)
        except EquilibriumError:
            raise first from None  # no rest at mid-stroke either: the truck's own values
        done, step = 0.0, CONTINUATION_STEP
        while done < 1.0:
            to = min(1.0, done + step)
            try:
                q, done, step = _newton_rest(model, data, idx, to * z, q, tol, max_iter), to, min(2 * step, CONTINUATION_STEP)
            except EquilibriumError:
                step /= 2
                if step < CONTINUATION_MIN:
                    raise EquilibriumError(f"{NO_REST}; no rest found on pans at {', '.join(f'{1e3 * v:.1f}' for v in z)} "
                                           f"mm, directly or moved there from mid-stroke (stuck at {done:.0%} of the way)"
                                           ) from None
    # Final evaluation with the model as the caller has it (friction on at rest adds nothing).
    data.qpos[q_adr] = q
    mujoco.mj_forward(model, data)
    return data.qpos.copy()


def _newton_rest(model, data, idx: "RigIndex", z: np.ndarray, q: np.ndarray, tol: float, max_iter: int) -> np.ndarray:
    """Newton iteration for the truck's rest (``qpos`` of its joints) with the pans at ``z`` (m, (4,)),
    started from ``q``; leaves the pans at ``z`` and the truck at the result (dry friction off)."""
    if idx.pan_qpos.size:
        data.qpos[idx.pan_qpos] = z
    if idx.pan_mocap.size:  # prescribed pans: their bodies' positions, raised by z
        data.mocap_pos[idx.pan_mocap] = model.body_pos[idx.pan_body]
        data.mocap_pos[idx.pan_mocap, 2] += z
    q_adr, dof = idx.truck_qpos, idx.truck_dof

    def residual(q: np.ndarray) -> np.ndarray:
        data.qpos[q_adr] = q
        mujoco.mj_forward(model, data)
        return data.qacc[dof].copy()

    with friction_disabled(model):
        q = np.array(q, dtype=float)
        r = residual(q)
        h = 1e-7
        for _ in range(max_iter):
            if np.max(np.abs(r)) < tol:
                break
            jac = np.empty((q.size, q.size))
            for j in range(q.size):
                dq = np.zeros_like(q)
                dq[j] = h
                jac[:, j] = (residual(q + dq) - residual(q - dq)) / (2 * h)
            try:
                q = q - np.linalg.solve(jac, r)
            except np.linalg.LinAlgError:
                # A singular Jacobian: some truck joint feels no restoring force (a tire off its
                # pan leaves its axle, or the whole truck, hanging in the air).
                raise EquilibriumError(f"{NO_REST}; no Newton step exists (singular stiffness)") from None
            r = residual(q)
            if not np.all(np.isfinite(r)):
                raise EquilibriumError(f"{NO_REST}; the Newton iteration diverged") from None
        else:
            raise EquilibriumError(
                f"{NO_REST}; {max_iter} Newton steps left a residual acceleration of {np.max(np.abs(r)):.3g} m/s^2"
            )
    return q
