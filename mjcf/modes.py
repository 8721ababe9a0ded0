"""Vibration modes of the truck-on-rig model about a state, each named after the joints that carry it.

:func:`modal_analysis` linearizes the model (:func:`mujoco.mjd_transitionFD`, dry friction off) and
names each oscillatory mode after the joint holding most of its kinetic energy (:data:`MODE_NAMES`).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from rigsim.mjcf.physics import friction_disabled

__all__ = ["MODE_NAMES", "COUPLED_SHARE", "Mode", "eigen", "modal_analysis"]

#: Name of a vibration mode after the joint that holds most of its kinetic energy.
MODE_NAMES: dict[str, str] = {
    "chassis_z": "body bounce",
    "chassis_pitch": "body pitch",
    "chassis_roll": "body roll",
    "front_axle_z": "front axle hop",
    "front_axle_roll": "front axle roll",
    "rear_axle_z": "rear axle hop",
    "rear_axle_roll": "rear axle roll",
    "cab_z": "cab bounce",
    "cab_pitch": "cab pitch",
    "frame_torsion": "frame torsion",
    "frame_bending": "frame bending",
    "engine_z": "engine bounce",
    "engine_pitch": "engine pitch",
}
#: A mode whose dominant joint holds less than this share of its kinetic energy (1) is named after
#: its two largest, "cab bounce with body pitch": with the cab on 2 Hz mounts the cab's bounce
#: couples with the body's bounce and pitch into two modes (1.5 and 3.2 Hz, cab share 0.37 and 0.54),
#: which the dominant joint alone named the same.
COUPLED_SHARE = 0.6


@dataclass(frozen=True)
class Mode:
    """One vibration mode of a linearized model.

    Attributes
    ----------
    name : str
        Named after the joint that holds most of the mode's kinetic energy, and the next one where
        the first holds less than :data:`COUPLED_SHARE` ("cab bounce with body pitch").
    frequency_hz : float, Hz
        Undamped natural frequency |lambda| / (2 pi).
    damping_ratio : float
        -Re(lambda) / |lambda|.
    energy_share : dict[str, float]
        Kinetic-energy share of each truck joint in the mode (sums to 1).
    """

    name: str
    frequency_hz: float
    damping_ratio: float
    energy_share: dict


def eigen(model: mujoco.MjModel, data: mujoco.MjData, eps: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    """The continuous-time eigenvalues (1/s) and eigenvectors of the model linearized about the state in
    ``data``: ``mujoco.mjd_transitionFD`` (centred differences, dry friction disabled), each eigenvalue
    mu of the step mapped to lambda = log(mu) / dt. The vectors' first ``nv`` rows are the positions."""
    n = 2 * model.nv + model.na
    a = np.zeros((n, n))
    with friction_disabled(model):
        mujoco.mjd_transitionFD(model, data, eps, True, a, None, None, None)
    mu, vec = np.linalg.eig(a)
    return np.log(mu.astype(complex)) / model.opt.timestep, vec


def modal_analysis(model: mujoco.MjModel, data: mujoco.MjData, eps: float = 1e-6) -> list[Mode]:
    """Vibration modes of the model about the state in ``data``.

    Linearizes the discrete-time transition with ``mujoco.mjd_transitionFD`` (centred
    differences, dry friction disabled), maps each eigenvalue mu to continuous time with
    lambda = log(mu) / dt, and keeps one of each complex-conjugate pair.

    Returns
    -------
    list of Mode
        Oscillatory modes, sorted by frequency.
    """
    nv = model.nv
    lam, vec = eigen(model, data, eps)
    mass = np.zeros((nv, nv))
    mujoco.mj_fullM(model, data, mass)
    names = {}
    for j in range(model.njnt):
        names[int(model.jnt_dofadr[j])] = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
    modes = []
    for k in np.argsort(np.abs(lam)):
        if lam[k].imag <= 1e-9:
            continue
        p = vec[:nv, k]
        energy = np.real(np.conj(p) * (mass @ p))
        energy = np.clip(energy, 0.0, None)
        total = energy.sum()
        if total <= 0:
            continue
        share = {names[i]: float(energy[i] / total) for i in range(nv)}
        first, second = sorted(share, key=share.get, reverse=True)[:2] if len(share) > 1 else (max(share), None)
        name = MODE_NAMES.get(first, first)
        if second is not None and share[first] < COUPLED_SHARE:
            name += f" with {MODE_NAMES.get(second, second)}"
        wn = float(abs(lam[k]))
        modes.append(
            Mode(
                name=name,
                frequency_hz=wn / (2 * np.pi),
                damping_ratio=float(-lam[k].real / wn),
                energy_share=share,
            )
        )
    return sorted(modes, key=lambda m_: m_.frequency_hz)
