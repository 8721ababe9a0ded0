"""Linearized closed loop of one actuator under a tire load: poles, bandwidth, stability check.

The loop couples the full five-state actuator (spool, both chamber pressures, integrator) to the
pan (mass ``pan_mass_kg``, force ``A (P1 - P2) - b v``) and a tire spring ``kt`` to an unsprung
mass ``m_u`` that is otherwise free (suspension and sprung mass neglected: they are much softer
and heavier); ``m_u = inf`` anchors the tire to ground, the load model of the paper's eq. 4.
It is linearized by central differences of the reference equations about the static point
carrying ``load_N``: this keeps both chambers separate (exact, unlike eq. 4 under load).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from .equilibrium import equilibrium_activation
from .model import derivatives_core, force_core
from .packing import pack
from .params import GRAVITY_M_S2, STATE_NAMES, ActuatorParams

__all__ = ["LoopReport", "loop_matrices", "loop_report", "assert_stable", "check_stable",
           "check_design_station", "frequency_response", "euler_map"]

_HZ_GRID = np.geomspace(0.01, 2000.0, 4000)


@dataclass(frozen=True)
class LoopReport:
    """Linear closed-loop summary.

    Attributes
    ----------
    poles : ndarray of complex, rad/s
        Eigenvalues of the continuous-time loop matrix, sorted by frequency.
    bandwidth_hz : float, Hz
        First frequency where ``|x_a / x_ref|`` falls 3 dB below its DC value (nan if never).
        With a free unsprung mass this is usually the narrow notch at its wheel-hop frequency.
    envelope_bandwidth_hz : float, Hz
        Highest frequency at which ``|x_a / x_ref|`` is still within 3 dB of its DC value
        (equal to ``bandwidth_hz`` without notches).
    peak_db : float, dB
        Largest ``|x_a / x_ref|`` over 0.01-2000 Hz.
    peak_hz : float, Hz
        Frequency of that peak.
    state_names : tuple of str
        Names of the loop states (``A`` rows).
    """

    poles: np.ndarray = field(repr=False)
    bandwidth_hz: float
    envelope_bandwidth_hz: float
    peak_db: float
    peak_hz: float
    state_names: tuple

    def describe(self) -> str:
        """One line per pole pair: frequency (Hz) and damping ratio."""
        lines = []
        for lam in self.poles:
            if lam.imag < 0:
                continue
            wn = abs(lam)
            zeta = -lam.real / wn if wn > 0 else 1.0
            lines.append(f"{lam.real:12.2f} {'+-' if lam.imag > 0 else '  '}{abs(lam.imag):10.2f}j rad/s"
                         f"  ({wn / (2 * math.pi):8.2f} Hz, zeta {zeta:6.3f})")
        lines.append(f"-3 dB bandwidth {self.bandwidth_hz:.2f} Hz (envelope {self.envelope_bandwidth_hz:.2f}"
                     f" Hz), peak {self.peak_db:+.2f} dB at {self.peak_hz:.2f} Hz")
        return "\n".join(lines)


def _default_load(params: ActuatorParams, load_mass_kg: float) -> float:
    m = params.pan_mass_kg + (load_mass_kg if math.isfinite(load_mass_kg) else 0.0)
    return m * GRAVITY_M_S2


def loop_matrices(params: ActuatorParams, kt_N_per_m: float, load_mass_kg: float,
                  load_N: float | None = None):
    """Continuous-time ``(A, B, C, names)`` of the loop, input x_ref (m), output x_a (m).

    States: the five ``STATE_NAMES``, then ``x_a`` (m), ``v_a`` (m/s) and, for a finite load
    mass, ``x_u`` (m), ``v_u`` (m/s) of the unsprung mass (deviations from the static point).
    """
    p = params
    kt = float(kt_N_per_m)
    if not kt >= 0.0:
        raise ValueError(f"kt_N_per_m must be >= 0, got {kt_N_per_m!r}")
    if not load_mass_kg > 0.0:
        raise ValueError(f"load_mass_kg must be > 0 (math.inf anchors the tire), got {load_mass_kg!r}")
    load = _default_load(p, load_mass_kg) if load_N is None else float(load_N)
    act0 = equilibrium_activation(p, load)
    prm = pack(p).tolist()
    free = math.isfinite(load_mass_kg)
    names = STATE_NAMES + ("x_a_m", "v_a_m_s") + (("x_u_m", "v_u_m_s") if free else ())
    n = len(names)
    z0 = np.zeros(n)
    z0[:5] = act0
    f0 = force_core(act0[2], act0[3], 0.0, prm)

    def rhs(z, xref):
        out = [0.0] * 5
        derivatives_core(z[0], z[1], z[2], z[3], z[4], xref, z[5], z[6], prm, out)
        xu = z[7] if free else 0.0
        tire = kt * (z[5] - xu)
        acc = (force_core(z[2], z[3], z[6], prm) - f0 - tire) / p.pan_mass_kg
        extra = [z[8], tire / load_mass_kg] if free else []
        return np.array(out + [z[6], acc] + extra)

    a = np.empty((n, n))
    for j in range(n):
        h = 1e-7 * max(1.0, abs(z0[j]))
        zp, zm = z0.copy(), z0.copy()
        zp[j] += h
        zm[j] -= h
        a[:, j] = (rhs(zp, 0.0) - rhs(zm, 0.0)) / (2 * h)
    h = 1e-7
    b = ((rhs(z0, h) - rhs(z0, -h)) / (2 * h)).reshape(n, 1)
    c = np.zeros((1, n))
    c[0, 5] = 1.0
    return a, b, c, names


def frequency_response(a, b, c, hz) -> np.ndarray:
    """Complex ``C (j w I - A)^-1 B`` at the frequencies ``hz`` (Hz)."""
    eye = np.eye(a.shape[0])
    return np.array([(c @ np.linalg.solve(2j * math.pi * f * eye - a, b))[0, 0] for f in np.atleast_1d(hz)])


def loop_report(params: ActuatorParams, kt_N_per_m: float, load_mass_kg: float,
                load_N: float | None = None) -> LoopReport:
    """Poles, -3 dB bandwidth and resonance peak of the linearized loop (see module docstring)."""
    a, b, c, names = loop_matrices(params, kt_N_per_m, load_mass_kg, load_N)
    poles = np.linalg.eigvals(a)
    poles = poles[np.argsort(np.abs(poles))]
    mag = np.abs(frequency_response(a, b, c, _HZ_GRID))
    dc = abs(frequency_response(a, b, c, [1e-6])[0])
    target = dc / math.sqrt(2.0)
    g = lambda f: abs(frequency_response(a, b, c, [f])[0]) - target  # noqa: E731
    below = np.nonzero(mag < target)[0]
    bw = env = math.nan
    if below.size and below[0] > 0:
        i = below[0]
        bw = brentq(g, _HZ_GRID[i - 1], _HZ_GRID[i], xtol=1e-9)
        above = np.nonzero(mag >= target)[0]
        j = above[-1]
        env = brentq(g, _HZ_GRID[j], _HZ_GRID[j + 1], xtol=1e-9) if j + 1 < mag.size else math.nan
    k = int(np.argmax(mag))
    return LoopReport(poles=poles, bandwidth_hz=bw, envelope_bandwidth_hz=env,
                      peak_db=20 * math.log10(mag[k] / dc), peak_hz=float(_HZ_GRID[k]),
                      state_names=names)


def euler_map(a, names, dt_s) -> np.ndarray:
    """One step of MuJoCo's semi-implicit Euler for the linear loop ``dz/dt = A z``.

    Velocities and activations advance explicitly, ``v' = v + dt a(z)``, ``act' = act + dt f(z)``;
    positions use the new velocity, ``q' = q + dt v'`` (what ``mjd_transitionFD`` returns).
    """
    n = a.shape[0]
    m = np.eye(n) + dt_s * a  # explicit rows (velocities, activations)
    for i, name in enumerate(names):
        if name in ("x_a_m", "x_u_m"):
            v = names.index("v_a_m_s" if name == "x_a_m" else "v_u_m_s")
            m[i] = np.eye(n)[i] + dt_s * m[v]
    return m


def _unstable_pole(a, names, dt_s):
    poles = np.linalg.eigvals(a)
    worst = poles[np.argmax(poles.real)]
    if worst.real >= 0.0:
        return worst, "continuous"
    if dt_s is not None:
        z = np.linalg.eigvals(euler_map(a, names, dt_s))
        k = int(np.argmax(np.abs(z)))
        if abs(z[k]) >= 1.0:
            return np.log(z[k]) / dt_s, "euler"
    return None, None


def assert_stable(params: ActuatorParams, kt_N_per_m: float, load_mass_kg: float, *,
                  load_N: float | None = None, gain_margin: float = 2.0,
                  dt_s: float | None = None) -> None:
    """Raise ValueError unless the loop is stable, also with ``kp_per_m * gain_margin``."""
    p = params
    if not gain_margin >= 1.0:
        raise ValueError(f"gain_margin must be >= 1, got {gain_margin!r}")
    where = (f"a {kt_N_per_m:.3g} N/m tire on "
             + (f"a {load_mass_kg:.4g} kg unsprung mass" if math.isfinite(load_mass_kg) else "ground"))
    cases = [(1.0, p)]
    if gain_margin > 1.0:
        cases.append((gain_margin, p.replace(kp_per_m=p.kp_per_m * gain_margin)))
    for factor, q in cases:
        a, _, _, names = loop_matrices(q, kt_N_per_m, load_mass_kg, load_N)
        pole, kind = _unstable_pole(a, names, dt_s)
        if pole is None:
            continue
        f_hz = abs(pole.imag) / (2 * math.pi)
        what = ("is unstable" if factor == 1.0 else
                f"has less than {20 * math.log10(gain_margin):.1f} dB gain margin (unstable with kp x {gain_margin:g})")
        if kind == "euler":
            what = f"is unstable under MuJoCo's Euler at dt = {dt_s:g} s (equivalent pole shown)"
        raise ValueError(
            f"actuator loop under {where} {what}: pole {pole.real:.4g} {'+-' if pole.imag else ''}"
            f"{abs(pole.imag):.4g}j rad/s ({f_hz:.1f} Hz), so raise kdp_per_Pa, lower kp_per_m or "
            f"raise spool_hz (now kdp_per_Pa = {p.kdp_per_Pa:.3g}, kp_per_m = {p.kp_per_m:.3g}, "
            f"spool_hz = {p.spool_hz:.4g})")


def check_stable(params: ActuatorParams, kt_N_per_m: float, load_mass_kg: float, *,
                 load_N: float | None = None, gain_margin: float = 2.0,
                 dt_s: float | None = None) -> LoopReport:
    """Raise ValueError unless the linearized closed loop under a tire load is stable with margin.

    The loop (spool, both chamber pressures, integrator, pan, tire spring, unsprung mass) is
    linearized about the static equilibrium carrying ``load_N``; it must be asymptotically
    stable with the nominal gains and still with ``kp_per_m`` multiplied by ``gain_margin``
    (:func:`assert_stable`).

    Parameters
    ----------
    params : ActuatorParams
    kt_N_per_m : float, N/m
        Tire stiffness between pan and unsprung mass.
    load_mass_kg : float, kg
        Unsprung mass on the tire (``math.inf``: the tire is anchored to ground, as in eq. 4).
    load_N : float, N, optional
        Static load the pan carries (default: weight of pan plus ``load_mass_kg``, or of the
        pan alone when the load mass is infinite).
    gain_margin : float, 1
        Factor on Kp the loop must tolerate (2 = 6 dB gain margin).
    dt_s : float, s, optional
        If given, also require MuJoCo's Euler step of the loop (explicit for velocities and
        activations, positions from the new velocities) to be stable.

    Returns
    -------
    LoopReport
        Poles, -3 dB bandwidth and resonance peak of the nominal loop.
    """
    assert_stable(params, kt_N_per_m, load_mass_kg, load_N=load_N, gain_margin=gain_margin, dt_s=dt_s)
    return loop_report(params, kt_N_per_m, load_mass_kg, load_N)


def check_design_station(params: ActuatorParams) -> None:
    """Raise ValueError unless ``params`` is stable on its own reference wheel station.

    Runs :func:`assert_stable` with ``params.design_tire_N_per_m`` (N/m) and
    ``params.design_load_mass_kg`` (kg) and the default 6 dB gain margin: the check a rig
    builder makes once per actuator when it builds a rig (``ActuatorParams`` itself only
    validates its values).

    Parameters
    ----------
    params : ActuatorParams

    Raises
    ------
    ValueError
        One sentence naming the unstable pole and the gains to change.
    """
    assert_stable(params, params.design_tire_N_per_m, params.design_load_mass_kg)
