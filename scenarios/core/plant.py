"""The rig's plant linearized about static rest: a discrete-time state-space model.

:meth:`rigsim.scenarios.core.rig.Rig.linearize` makes it with ``mujoco.mjd_transitionFD`` (truck,
pans and the four hydraulic actuators, all states); this module evaluates it: frequency
responses in Hz, poles and zeros in rad/s, and simulation by modes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

from rigsim.correction.output.transfer import state_space_frequency_response

__all__ = ["PlantLinearization", "fine_factor", "simulate"]


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
        import control  # python-control costs ~0.3 s to import: only here, not in every run

        sys_d = control.ss(self.a, self.b[:, [corner]], self.c[[corner]], 0.0, self.dt_s)
        z = np.asarray(sys_d.zeros(), dtype=complex)
        z = z[np.abs(z) > 1e-12]
        zc = np.log(z) / self.dt_s
        pc = self.poles()
        keep = [s for s in zc if np.min(np.abs(pc - s)) > 0.01 * max(abs(s), 1.0)]
        return np.array(keep)

    def pan_drive(self, drive, *, diagonal: bool = False):
        """The pans' motion this model gives for the drive x_ref = ``drive``, as a drive on
        ``drive``'s own steps (for a road test whose pans follow the linear model).

        The model runs on its own step (:attr:`dt_s`): ``drive`` is refined onto it
        (:meth:`~rigsim.scenarios.core.drive.Drive.refined`, cubic Hermite), each fine step holds the
        drive at its middle (as MuJoCo's steps hold ``ctrl``), and the result is taken back at
        every run step with exact mid-step values (:meth:`~rigsim.scenarios.core.drive.Drive.every`).
        ``drive``'s step must be an even multiple of :attr:`dt_s` (ValueError otherwise)."""
        from rigsim.scenarios.core.drive import Drive

        r = fine_factor(drive.dt_s, self.dt_s)
        fine = drive.refined(r)
        y = self.simulate(fine.held(0, fine.n_steps), diagonal=diagonal)
        return Drive(fine.t_s, y[:, :4], y[:, 4:], drive.corners).every(r)

    def simulate(self, u, *, diagonal: bool = False) -> np.ndarray:
        """Pan displacement (m) and velocity (m/s), shape (N, 8), from rest on drives ``u``
        (N, 4), m: :func:`simulate` with this model's ``a``, ``b``, ``c``."""
        return simulate(self.a, self.b, self.c, u, diagonal=diagonal)


def fine_factor(coarse_dt_s: float, fine_dt_s: float) -> int:
    """How many steps of ``fine_dt_s`` (s) make one of ``coarse_dt_s`` (s): an even integer
    (ValueError naming both steps otherwise)."""
    r = coarse_dt_s / fine_dt_s
    if abs(r - round(r)) > 1e-6 * r or round(r) < 2 or round(r) % 2:
        raise ValueError(f"the run's step {coarse_dt_s:g} s must be an even multiple of the linear "
                         f"model's step {fine_dt_s:g} s")
    return int(round(r))


def simulate(a, b, c, u, *, diagonal: bool) -> np.ndarray:
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
