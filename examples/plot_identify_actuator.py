"""
Identifying an actuator from its drive and LVDT record
======================================================

A lab that does not trust eq. 4's parameters measures ``T_a`` instead: it drives one post with a
random signal and records the drive ``x_p`` and the pan's LVDT ``x_a``.
:func:`rigsim.correction.identification.actuator_fit.fit_actuator` estimates the frequency response
(H1, Welch) and fits a rational ``T_a(s)``, choosing its orders by the error on frequencies held
out of the fit. Here the "rig" is a known ``T_a`` (eq. 4 of the project's DYNTRAC parameters on a
rear tire) with 20 micrometres of LVDT noise, so the fit can be checked against the truth.
"""

import matplotlib.pyplot as plt
import numpy as np
from scipy import signal

from rigsim.correction.identification.actuator_fit import fit_actuator
from rigsim.correction.identification.actuator_fit_rules import rational_response
from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.hydraulics.linearization import eq4_parameters
from rigsim.hydraulics.params import ActuatorParams

fs = 1000.0  # Hz
rng = np.random.default_rng(8608)

# %%
# The "rig": eq. 4 at a rear dual's 1.8 MN/m, driven by 120 s of random drive band-limited to
# 40 Hz (2 mm rms), its LVDT read with white noise.

num, den = eq4_coefficients_from(**eq4_parameters(ActuatorParams(), 1.8e6))
t = np.arange(int(120 * fs)) / fs
b, a = signal.butter(4, 40.0, fs=fs)
drive = signal.lfilter(b, a, rng.standard_normal(t.size))
drive *= 2e-3 / np.std(drive)
_, lvdt, _ = signal.lsim((num, den), drive, t)
lvdt = lvdt + 20e-6 * rng.standard_normal(t.size)

# %%
# The fit, and how far it lies from the truth in the band the correction uses:

fit = fit_actuator(drive, lvdt, fs)
print(f"orders {fit.orders}, bandwidth {fit.bandwidth_hz:.2f} Hz, held-out error {fit.held_out_error:.4f}")
f = np.logspace(-1, np.log10(60.0), 300)
truth = rational_response(num, den, f)
fitted = rational_response(*fit.as_tf(), f)
band = f <= 30.0
print(f"worst magnitude error to 30 Hz: {np.max(np.abs(20 * np.log10(np.abs(fitted[band] / truth[band])))):.3f} dB")

# %%
# The H1 estimate (dots), the fit and the truth:

fig, (mag, phase) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
shown = (fit.f_hz > 0) & (fit.f_hz <= 60.0)
mag.semilogx(fit.f_hz[shown], 20 * np.log10(np.abs(fit.h[shown])), ".", ms=3, color="0.6", label="H1 estimate")
mag.semilogx(f, 20 * np.log10(np.abs(truth)), "k", lw=2, label="truth (eq. 4)")
mag.semilogx(f, 20 * np.log10(np.abs(fitted)), "tab:red", ls="--", label=f"fit, orders {fit.orders}")
mag.set_ylabel("|T_a|, dB")
mag.legend()
mag.grid(alpha=0.3, which="both")
phase.semilogx(fit.f_hz[shown], np.degrees(np.unwrap(np.angle(fit.h[shown]))), ".", ms=3, color="0.6")
phase.semilogx(f, np.degrees(np.unwrap(np.angle(truth))), "k", lw=2)
phase.semilogx(f, np.degrees(np.unwrap(np.angle(fitted))), "tab:red", ls="--")
phase.set_ylabel("phase, deg")
phase.set_xlabel("frequency, Hz")
phase.grid(alpha=0.3, which="both")
fig.tight_layout()
plt.show()
