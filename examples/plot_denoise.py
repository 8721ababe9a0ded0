"""
The load cells' white noise and drift taken out of a residual
=============================================================

The truck-model correction corrects the part of the rig force its model does not explain,
``F_rig - F_model(x_a)``: the model's error, where the truck's force is, plus the load cells' noise,
everywhere. :func:`rigsim.correction.output.denoise.design_noise_gain` reads the white noise's level from
the residual above the truck's band and returns the gain ``max(0, 1 - N0 / S_x(f))``: ~1 where the
model's error outweighs the noise, 0 where the residual is noise alone; with ``drift_hz`` it also
takes out the slow part, where the load cells drift (the model correction's own model carries the
slow force). Here the residual is made up: a 300 N error between 2 and 12 Hz in 100 N of white
noise and 50 N of drift below 0.2 Hz, 30 s at 1 kHz.
"""

import matplotlib.pyplot as plt
import numpy as np
from scipy import signal

from rigsim.correction.output.denoise import DRIFT_HZ, design_noise_gain

fs = 1000.0
rng = np.random.default_rng(0)
sos = signal.butter(4, [2.0, 12.0], btype="bandpass", fs=fs, output="sos")
error = signal.sosfiltfilt(sos, rng.standard_normal((30_000, 1)), axis=0)
error *= 300.0 / error.std()
noise = 100.0 * rng.standard_normal(error.shape)
drift = signal.sosfiltfilt(signal.butter(1, 0.2, fs=fs, output="sos"), rng.standard_normal(error.shape), axis=0)
drift *= 50.0 / drift.std()
residual = error + noise + drift

# %%
# Design the gain (its noise level read over 60-150 Hz), with and without the drift cut, then apply it:

white = design_noise_gain(residual, fs)
gain = design_noise_gain(residual, fs, drift_hz=DRIFT_HZ)
cleaned = gain.apply(residual)
print(f"white noise read: {gain.noise_rms[0]:.1f} N rms (made with 100 N); band white: {bool(gain.measured[0])}")
print(f"error of the residual against the model's error: {np.std(residual - error):.1f} N rms as it is, "
      f"{np.std(white.apply(residual) - error):.1f} N rms with the white noise taken out, "
      f"{np.std(cleaned - error):.1f} N rms with the drift too")

# %%
# The residual's spectrum, the noise's level and the gains. Above ~15 Hz the residual is the noise's
# level and the gain falls to ~0; in the error's band it is ~1; below 0.7 Hz the drift cut takes it
# to 0 where the white-noise gain alone keeps the drift.

f, s_res = signal.welch(residual[:, 0], fs, nperseg=4096)
_, s_clean = signal.welch(cleaned[:, 0], fs, nperseg=4096)
n0 = gain.noise_rms[0] ** 2 / (fs / 2)
fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
top.semilogy(f, s_res, label="residual F_rig - F_model(x_a)")
top.semilogy(f, s_clean, label="with the noise and the drift taken out")
top.axhline(n0, color="k", linestyle=":", label="white noise level read")
top.set_ylabel("PSD [N^2/Hz]")
top.legend(fontsize=7)
bottom.plot(white.freq_hz, white.gain[:, 0], label="white noise only")
bottom.plot(gain.freq_hz, gain.gain[:, 0], label=f"with the drift cut at {DRIFT_HZ:g} Hz")
bottom.legend(fontsize=7)
bottom.set_ylabel("gain [1]")
bottom.set_xlabel("frequency [Hz]")
bottom.set_xlim(0, 60)
fig.tight_layout()
