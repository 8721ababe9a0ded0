"""
Correct a lab's measured file with the Python API
=================================================

A rig's record holds, per corner, the drive, the pan's LVDT and the wheel force. Here a small
synthetic record stands in for one: 20 s at 1 kHz, written the way a German DAQ might export it
(semicolons, decimal commas, kN and mm). The rig force of each wheel is its "road" force seen
through that corner's actuator, the paper's eq. 4 with this project's DYNTRAC parameters at the
corner's tire stiffness; the drives are independent random signals and each LVDT the drive
through the same T_a. The record is read, T_a identified per corner from drive and LVDT, and
the forces corrected by ``T_a^-1 T_F`` (the linear correction, 30 Hz Butterworth, zero-phase).
"""

import pathlib
import tempfile

import matplotlib.pyplot as plt
import numpy as np
from scipy import signal

from rigsim.correction.metrics.dlc import dlc
from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.hydraulics.linearization import eq4_parameters
from rigsim.hydraulics.params import ActuatorParams
from rigsim import LinearOptions, correct_record, identify_record, read_record

# %%
# A synthetic record
# ------------------
# Road forces: a static load plus band-limited random dynamic load with an axle-hop-like
# resonance near 10 Hz. Front tires 9.0e5 N/m, rear 1.8e6 N/m (the catalogue truck's).

fs = 1000.0
n = int(20 * fs)
t = np.arange(n) / fs
rng = np.random.default_rng(7)
corners = ("fl", "fr", "rl", "rr")
kt = {"fl": 9.0e5, "fr": 9.0e5, "rl": 1.8e6, "rr": 1.8e6}
ta = {c: eq4_coefficients_from(**eq4_parameters(ActuatorParams(), kt[c])) for c in corners}

hop = signal.butter(2, [8.0, 12.0], "bandpass", fs=fs, output="sos")
broad = signal.butter(4, [0.5, 25.0], "bandpass", fs=fs, output="sos")
columns = {"Zeit [s]": t}
road = {}
for c in corners:
    dyn = signal.sosfilt(broad, rng.standard_normal(n)) + 2.0 * signal.sosfilt(hop, rng.standard_normal(n))
    road[c] = 30e3 + 5e3 * dyn / dyn.std()
    rig = signal.lsim(ta[c], road[c] - 30e3, t)[1] + 30e3
    drive = 0.01 * signal.sosfilt(broad, rng.standard_normal(n))
    lvdt = signal.lsim(ta[c], drive, t)[1]
    columns[f"Fz_{c.upper()} [kN]"] = rig / 1e3 + rng.normal(0.0, 0.1, n)  # 100 N rms noise
    columns[f"Soll_{c.upper()} [mm]"] = drive * 1e3
    columns[f"Weg_{c.upper()} [mm]"] = lvdt * 1e3

folder = pathlib.Path(tempfile.mkdtemp())
path = folder / "messung.csv"
with open(path, "w", encoding="utf-8") as f:
    f.write("# Prüfstand: synthetisch\n" + ";".join(columns) + "\n")
    for row in zip(*columns.values()):
        f.write(";".join(f"{v:.6f}".replace(".", ",") for v in row) + "\n")
print(path.read_text(encoding="utf-8").splitlines()[2][:100], "...")

# %%
# Read, identify, correct
# -----------------------
# :func:`~rigsim.scenarios.records.read_record` finds the delimiter, the decimal comma and the units;
# every channel comes back in SI under its name without the unit.

record = read_record(path)
print(record.names[:4], record.units["Fz_FL"], record.source_units["Fz_FL"], f"{record.fs_hz:g} Hz")

pairs = ",".join(f"{c}=Soll_{c.upper()}:Weg_{c.upper()}" for c in corners)
identification = identify_record(record, pairs=pairs)
for c, fit in identification.fits.items():
    print(c, f"bandwidth {fit.bandwidth_hz:.2f} Hz")

result = correct_record(record, LinearOptions(actuators=identification.fits),
                        corner_map=",".join(f"{c}=Fz_{c.upper()}" for c in corners))
print(result.table())
result.write(folder / "corrected.rsp")

# %%
# Against the road forces
# -----------------------
# The corrected DLC against the road force's, both on the settled samples the correction keeps.

ok = result.settled
for i, c in enumerate(corners):
    print(f"{c}: road {dlc(road[c][ok]):.4f}  rig {dlc(result.measured_N[ok, i]):.4f}  "
          f"corrected {dlc(result.corrected_N[ok, i]):.4f}")

fig, ax = plt.subplots(figsize=(7, 3))
sel = ok & (t > 10.0) & (t < 11.0)
ax.plot(t[sel], road["rl"][sel] / 1e3, label="road")
ax.plot(t[sel], result.measured_N[sel, 2] / 1e3, label="rig (measured)")
ax.plot(t[sel], result.corrected_N[sel, 2] / 1e3, "--", label="corrected")
ax.set_xlabel("time [s]")
ax.set_ylabel("rear-left wheel force [kN]")
ax.legend(loc="upper right")
fig.tight_layout()
