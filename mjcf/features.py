"""Helpers of the plant features (:mod:`rigsim.mjcf.frame`, :mod:`rigsim.mjcf.engine`, :mod:`rigsim.mjcf.dampers`).

:func:`check_field` validates a feature's argument against its module's ``BOUNDS`` (the shape of
:data:`rigsim.mjcf.variant.BOUNDS`). A feature that takes mass out of a body (the engine out of the
chassis) or splits one in two (the flexible frame) keeps the truck's mass, centre of mass and
inertia tensor: :func:`tensor_of` reads a body's explicit inertial as a 3x3 tensor about its centre
of mass in the body's axes, :func:`set_tensor` writes one back in MuJoCo's principal form.
"""

from __future__ import annotations

import math
import numbers

import mujoco
import numpy as np

__all__ = ["check_field", "parallel_axis", "box_inertia", "tensor_of", "set_tensor"]


def check_field(bounds: dict[str, tuple[float, float, str, str]], field: str, value) -> float:
    """``value`` as a float if it is a finite number within ``bounds[field]`` (inclusive), else a
    ValueError in one sentence naming ``vehicle.<field>``, its bounds and why they are those."""
    low, high, unit, why = bounds[field]
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"vehicle.{field} must be a finite number ({unit}), got {value!r}")
    if not low <= value <= high:
        raise ValueError(f"vehicle.{field} = {value:g} {unit} is outside {low:g} to {high:g} {unit}: {why}")
    return float(value)


def parallel_axis(offset: np.ndarray, mass: float) -> np.ndarray:
    """Inertia (kg m^2, 3x3) of a point ``mass`` (kg) at ``offset`` (m) about the origin."""
    offset = np.asarray(offset, dtype=float)
    return mass * (float(offset @ offset) * np.eye(3) - np.outer(offset, offset))


def box_inertia(mass: float, lengths) -> np.ndarray:
    """Principal moments (kg m^2, 3) of a uniform box of ``mass`` (kg) and edge ``lengths`` (m, 3)."""
    a, b, c = (float(v) for v in lengths)
    return mass / 12.0 * np.array([b**2 + c**2, a**2 + c**2, a**2 + b**2])


def tensor_of(body) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass (kg), centre of mass (m, 3) and inertia tensor about it (kg m^2, 3x3), in the axes of
    ``body`` (an :class:`mujoco.MjsBody` with an explicit inertial: mass, ipos, iquat, inertia)."""
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, np.asarray(body.iquat, dtype=float))
    rot = rot.reshape(3, 3)
    tensor = rot @ np.diag(np.asarray(body.inertia, dtype=float)) @ rot.T
    return float(body.mass), np.array(body.ipos, dtype=float), tensor


def set_tensor(body, mass: float, com, tensor: np.ndarray, problem: str) -> None:
    """Give ``body`` the explicit inertial of ``mass`` (kg) at ``com`` (m, body axes) with ``tensor``
    (kg m^2, 3x3 about ``com``), as principal moments and the rotation to their axes.

    Raises
    ------
    ValueError
        ``problem`` (one sentence naming the field to change) when the tensor is no rigid body's:
        a principal moment larger than the sum of the other two (a body's sum of m r r^T, half its
        moments' sum minus each moment, must be positive semi-definite) or a mass not above 0.
    """
    moments, axes = np.linalg.eigh(0.5 * (tensor + tensor.T))
    if mass <= 0 or np.min(0.5 * moments.sum() - moments) < -1e-9 * max(moments.sum(), 1.0):
        raise ValueError(problem)
    axes = axes * np.sign(np.linalg.det(axes))  # a rotation, not a reflection
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, axes.reshape(9))
    body.mass, body.ipos, body.iquat, body.inertia = float(mass), np.asarray(com, dtype=float), quat, moments
    body.explicitinertial = True
