"""
The actuator's eq. 4 and the correction filter
==============================================

The paper's eq. 4 gives the wheelpan actuator's transfer function ``T_a(s) = X_a(s) / X_p(s)``
from the servovalve, oil column, position loop and the tire spring the pan stands on. Here it is
built from this project's DYNTRAC parameters, linearized by :mod:`rigsim.hydraulics.linearization`, at
the catalogue truck's front and rear tire stiffness, and drawn with the two low-passes the
correction can use and the resulting correction ``T_a^-1 T_F``.
"""

import matplotlib.pyplot as plt
import numpy as np

from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.correction.output.lowpass import paper_lowpass, regularized_lowpass
from rigsim.correction.output.transfer import eq4_transfer_function, frequency_response_hz, transfer_bandwidth_hz
from rigsim.hydraulics.linearization import eq4_parameters
from rigsim.hydraulics.params import ActuatorParams

f = np.logspace(-1, 2, 400)
params = ActuatorParams()
tires = {"front, 9.0e5 N/m": 9.0e5, "rear, 1.8e6 N/m": 1.8e6}

# %%
# The coefficients of eq. 4 (descending powers of s, s in rad/s) and the -3 dB bandwidth:

responses = {}
for label, kt in tires.items():
    p = eq4_parameters(params, kt)
    num, den = eq4_coefficients_from(**p)
    ta = eq4_transfer_function(**p)
    responses[label] = frequency_response_hz(ta, f)
    print(label, "num", np.array2string(np.asarray(num), precision=4), "den",
          np.array2string(np.asarray(den), precision=4), f"bandwidth {transfer_bandwidth_hz(ta):.2f} Hz")

paper = paper_lowpass().response(f)
butter = regularized_lowpass().response(f)

# %%
# Magnitude and phase. ``T_a`` is 1 at low frequency and falls off above ~10 Hz; the paper's
# 16/24 Hz low-pass is already 3 dB down near 8 Hz, the 30 Hz Butterworth leaves the inverse
# nearly exact up to 20 Hz.

fig, (mag, ph) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
for label, h in responses.items():
    mag.semilogx(f, 20 * np.log10(np.abs(h)), label=f"T_a, {label}")
    ph.semilogx(f, np.degrees(np.unwrap(np.angle(h))), label=f"T_a, {label}")
h_rear = responses["rear, 1.8e6 N/m"]
mag.semilogx(f, 20 * np.log10(np.abs(paper)), ":", label="T_F, paper's eq. 5 (16/24 Hz)")
mag.semilogx(f, 20 * np.log10(np.abs(butter)), ":", label="T_F, Butterworth 6th order, 30 Hz")
mag.semilogx(f, 20 * np.log10(np.abs(butter / h_rear)), "--", label="T_a^-1 T_F (rear, Butterworth)")
mag.set_ylim(-40, 15)
mag.set_ylabel("magnitude [dB]")
ph.set_ylabel("phase [deg]")
ph.set_xlabel("frequency [Hz]")
mag.legend(fontsize=7, loc="lower left")
fig.tight_layout()
