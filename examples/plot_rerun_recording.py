"""
A road test and a rig test as a rerun recording
===============================================

Every command that runs the simulator can also write a recording for the rerun viewer
(``--rrd FILE.rrd``, ``rigsim paper --rrd``): the truck and the four pans moving, the drive, the
pan motion and the tire forces as time series, one recording per scenario. From Python the same
file comes from :func:`rigsim.scenarios.review.recording.write_recording`. Here a 10 s case of the
paper (high roughness, 72 km/h) runs as a road test and as a rig test with body poses recorded
at 50 Hz, and both go into one file; ``rerun FILE.rrd`` (or ``--view`` on the command line) opens
it. The figure shows what the recording's force panel shows for the front left wheel.
"""

import dataclasses
import pathlib
import tempfile

import matplotlib.pyplot as plt

from rigsim.scenarios.core.config import load_scenario, paper_scenarios
from rigsim.scenarios.core.run import run
from rigsim.scenarios.review.recording import write_recording

scenario = dataclasses.replace(load_scenario(paper_scenarios()[2]), duration_s=10.0)
road = run(scenario, "road", pose_rate_hz=50.0)
rig = run(scenario, "rig", pose_rate_hz=50.0)

with tempfile.TemporaryDirectory() as folder:
    path = write_recording(pathlib.Path(folder) / "high_72kmh.rrd", [road, rig])
    print(f"wrote {path.name}: {path.stat().st_size / 1e6:.1f} MB, one recording ({scenario.name}), "
          "road and rig runs, body poses at 50 Hz")

# %%
# The front left tire force of both tests, as the recording's force panel plots it:

fig, ax = plt.subplots(figsize=(8, 3.5))
ax.plot(road.t_s, road.signals["tire_force_N"][:, 0] / 1e3, color="k", lw=1.2, label="road test")
ax.plot(rig.t_s, rig.signals["tire_force_N"][:, 0] / 1e3, color="tab:red", lw=1.0, label="rig test")
ax.set_xlabel("time, s")
ax.set_ylabel("tire force fl, kN")
ax.legend()
ax.grid(alpha=0.3)
fig.tight_layout()
plt.show()
