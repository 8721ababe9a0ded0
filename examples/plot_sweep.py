"""
A test matrix: the rig's loss and the correction across speeds
==============================================================

``rigsim sweep GRID.toml --out DIR`` runs every combination of the grid's axes as a road test and
a rig test, corrects the rig force as ``rigsim paper`` does and writes one row per case to
``DIR/results.csv`` (resumable; on all cores, or on a Dask cluster with ``--scheduler``). Here a
small grid, three speeds on the paper's high-roughness road with 10 s records and the paper's
eq. 4 for T_a (no identification runs), runs from Python through the command's own entry point.
"""

import csv
import pathlib
import tempfile

import matplotlib.pyplot as plt

from rigsim.scenarios.cli.main import main

GRID = """
[sweep]
name = "speeds"
actuator = "eq4"
lowpass = "regularized"
correction_mode = "zerophase"
noise_N = 100.0

[base]
name = "speeds"
speed_kmh = 72.0
duration_s = 10.0
seed = 1995

[base.road]
roughness = "high"

[base.vehicle]
payload_kg = 3640.0

[axes]
speed_kmh = [40, 60, 80]
"""

with tempfile.TemporaryDirectory() as folder:
    grid = pathlib.Path(folder) / "speeds.toml"
    grid.write_text(GRID)
    assert main(["sweep", str(grid), "--out", str(pathlib.Path(folder) / "out"), "--jobs", "1", "--quiet"]) == 0
    with open(pathlib.Path(folder) / "out" / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))

print("columns:", ", ".join(rows[0]))

# %%
# DLC of the road test, the rig test and the corrected rig force, by speed:

speed = [float(r["speed_kmh"]) for r in rows]
fig, ax = plt.subplots(figsize=(6, 3.8))
for key, label, style in (("dlc_road", "road", "k-o"), ("dlc_rig", "rig, measured", "r-s"),
                          ("dlc_corrected", "corrected", "b--^")):
    ax.plot(speed, [float(r[key]) for r in rows], style, label=label)
ax.set_xlabel("speed, km/h")
ax.set_ylabel("DLC (mean of the four wheels)")
ax.legend()
ax.grid(alpha=0.3)
fig.tight_layout()
plt.show()
