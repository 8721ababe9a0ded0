"""
Correct a record with a truck model calibrated on it
====================================================

The linear correction ``T_a^-1 T_F`` treats each wheel on its own; the truck on the rig couples
them, and its leaf springs' friction makes its response amplitude-dependent. With each post's
drive and LVDT in the record, the truck model of this project can be calibrated on the record
itself (payload and its position from the static loads; tire stiffness and damping, leaf
friction and the tires' stiffening fitted) and the record corrected by it:
``F_model(x_ref) + L(W(F_rig - F_model(x_a)))``, with ``W`` the load cells' white noise taken out of
the model's residual and ``L`` the linear correction.

Here the simulator makes the record: the paper's high-roughness case at 72 km/h, 20 s, its rig
force with 100 N of load-cell noise, written as a lab's CSV. The road test of the same case is the
reference the correction never sees. The calibration is kept short for this page (one window,
the cab held, at most 20 model evaluations); ``rigsim correct --model`` defaults to two windows.
"""

import dataclasses
import pathlib
import tempfile

import matplotlib.pyplot as plt
import numpy as np

from rigsim.correction.metrics.dlc import dlc
from rigsim.scenarios.core.config import load_scenario, paper_scenarios
from rigsim.scenarios.core.run import run
from rigsim import LinearOptions, ModelOptions, correct_record, identify_record, read_record

# %%
# A rig test and its road test
# ----------------------------
# :func:`rigsim.scenarios.core.run.run` runs the scenario on the road (the pans follow the profile) and
# on the rig (four servo-hydraulic actuators follow it as well as they can).

path = paper_scenarios()[2]
scenario = dataclasses.replace(load_scenario(path), duration_s=20.0)
road, rig = run(scenario, "road"), run(scenario, "rig")
t = np.asarray(rig.t_s)
measured = rig.signals["tire_force_N"] + np.random.default_rng(7).normal(0.0, 100.0, (t.size, 4))

corners = ("fl", "fr", "rl", "rr")
columns = {"time [s]": t}
for i, c in enumerate(corners):
    columns[f"Fz_{c.upper()} [kN]"] = measured[:, i] / 1e3
    columns[f"Soll_{c.upper()} [mm]"] = rig.signals["profile_m"][:, i] * 1e3  # the drive
    columns[f"Weg_{c.upper()} [mm]"] = rig.signals["pan_m"][:, i] * 1e3  # the LVDT
folder = pathlib.Path(tempfile.mkdtemp())
csv = folder / "messung.csv"
np.savetxt(csv, np.column_stack(list(columns.values())), delimiter=",", header=",".join(columns), comments="",
           fmt="%.9g")

# %%
# Both corrections
# ----------------
# The linear correction with T_a identified per corner from the drive and LVDT channels, and the
# model correction; both read the same file.

record = read_record(csv)
pairs = ",".join(f"{c}=Soll_{c.upper()}:Weg_{c.upper()}" for c in corners)
fits = identify_record(record, pairs=pairs).fits
linear = correct_record(record, LinearOptions(actuators=fits),
                        corner_map=",".join(f"{c}=Fz_{c.upper()}" for c in corners))
model = correct_record(record, ModelOptions(path, pairs=pairs, calibration_windows=1, cab="held", max_evaluations=20,
                                            workers=2))
print(model.method, model.reason or "(every wheel by the model)")
print(model.calibration.table())

# %%
# Against the road test
# ---------------------
# DLC = std / mean of each wheel force, on the samples both corrections keep.

road_N = np.asarray(road.signals["tire_force_N"])
ok = linear.settled & model.settled
print("wheel   road     rig      linear   model")
for i, c in enumerate(corners):
    print(f"{c:5s} {dlc(road_N[ok, i]):.4f}  {dlc(measured[ok, i]):.4f}  {dlc(linear.corrected_N[ok, i]):.4f}  "
          f"{dlc(model.corrected_N[ok, i]):.4f}")

fig, ax = plt.subplots(figsize=(7, 3.2))
sel = ok & (t > 10.0) & (t < 11.5)
ax.plot(t[sel], road_N[sel, 2] / 1e3, color="k", lw=1.6, label="road")
ax.plot(t[sel], measured[sel, 2] / 1e3, color="tab:red", lw=1.0, label="rig (measured)")
ax.plot(t[sel], linear.corrected_N[sel, 2] / 1e3, color="tab:orange", lw=1.0, ls="--", label="linear")
ax.plot(t[sel], model.corrected_N[sel, 2] / 1e3, color="tab:blue", lw=1.2, label="truck model")
ax.set_xlabel("time [s]")
ax.set_ylabel("rear-left wheel force [kN]")
ax.legend(loc="upper right", ncol=2, fontsize=8)
fig.tight_layout()
