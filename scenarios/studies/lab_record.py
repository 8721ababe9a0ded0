"""A simulated rig test written as a lab's record, for the benchmarks and walk-throughs of the model correction.

:func:`write_lab_record` runs a scenario on the rig and writes what a lab's acquisition keeps: per
corner the wheel force in kN with load-cell noise (``Fz_FL``), the drive (``Soll_FL``) and the
pan's LVDT (``Weg_FL``) in mm, in the file's format by its extension.
"""

from __future__ import annotations

import pathlib
from types import SimpleNamespace

import numpy as np

__all__ = ["PAIRS", "write_lab_record"]

#: The drive and LVDT channels of each corner in :func:`write_lab_record`'s files, as ``--pairs`` takes them.
PAIRS = "fl=Soll_FL:Weg_FL,fr=Soll_FR:Weg_FR,rl=Soll_RL:Weg_RL,rr=Soll_RR:Weg_RR"


def write_lab_record(path, scenario, noise_N: float = 100.0, noise_seed: int = 7) -> pathlib.Path:
    """Run ``scenario`` on the rig and write it as a lab's record at ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        The file (.csv, .rsp, .mf4, .tdms).
    scenario : rigsim.scenarios.core.config.Scenario
    noise_N : float, N
        The load cells' white noise, rms.
    noise_seed : int
        Seed of that noise.

    Returns
    -------
    pathlib.Path
    """
    from rigsim.correction.io.measured import write_channels
    from rigsim.mjcf.names import CORNERS
    from rigsim.scenarios.core.run import run

    rig = run(scenario, "rig")
    forces = rig.signals["tire_force_N"]
    force = forces + np.random.default_rng(noise_seed).normal(0.0, noise_N, forces.shape)
    data, units = {}, {}
    for i, c in enumerate(CORNERS):
        for name, values, unit in ((f"Fz_{c.upper()}", force[:, i] / 1e3, "kN"),
                                   (f"Soll_{c.upper()}", rig.signals["profile_m"][:, i] * 1e3, "mm"),
                                   (f"Weg_{c.upper()}", rig.signals["pan_m"][:, i] * 1e3, "mm")):
            data[name], units[name] = values, unit
    return write_channels(pathlib.Path(path), SimpleNamespace(time_s=np.asarray(rig.t_s), data=data, units=units),
                          metadata={})
