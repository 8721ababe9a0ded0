"""Files and terminal table of ``rigsim iterate``: the drive files, the error plot, ``iteration.json``.

``DIR/drive.csv``: the best iterated drive (m) per corner at the output rate, t >= 0 (s);
``DIR/drive.drv``: the same drive as an MTS RPC III drive file (TIME_TYPE DRIVE, int16, channels
``drive_<corner>`` in m; header keys ``scenario``, ``target``, ``iterations``...), written by
:func:`rigsim.correction.io.measured.write_channels`, for a lab to play on a real rig;
``DIR/iteration.json``: :meth:`rigsim.scenarios.studies.iterate.compute.IterateResult.to_dict`;
``DIR/iteration.png``: the NRMSE against the target per iteration. Each file is written
atomically, after all of them are made in memory (the RPC III file is written first, so a
refusal of its writer leaves the folder as it was).
"""

from __future__ import annotations

import io
import pathlib
from types import SimpleNamespace

import numpy as np

from rigsim.correction.io.measured import write_channels
from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.files import atomic_write_bytes, to_json

__all__ = ["drive_csv_bytes", "drive_channels", "drive_metadata", "plot_png", "comparison_table", "write_files",
           "FILES"]

FILES = ("drive.csv", "drive.drv", "iteration.json", "iteration.png")


def drive_csv_bytes(result) -> bytes:
    """The iterated drive as CSV: ``time_s`` (s) and ``drive_<corner>_m`` (m), ``%.10g``."""
    buf = io.StringIO()
    header = ",".join(["time_s"] + [f"drive_{c}_m" for c in CORNERS])
    np.savetxt(buf, np.column_stack([result.t_s, result.iteration.drive]), delimiter=",", fmt="%.10g",
               header=header, comments="")
    return buf.getvalue().encode("ascii")


def drive_channels(result) -> SimpleNamespace:
    """The iterated drive for :func:`rigsim.correction.io.measured.write_channels`: ``time_s`` (s) and
    ``drive_<corner>`` (m) per corner."""
    drive = np.asarray(result.iteration.drive, dtype=float)
    names = [f"drive_{c}" for c in CORNERS]
    return SimpleNamespace(time_s=np.asarray(result.t_s, dtype=float),
                           data={n: drive[:, i] for i, n in enumerate(names)}, units={n: "m" for n in names})


def _header_value(text) -> str:
    """One line of at most 96 latin-1 bytes (an RPC III header value)."""
    text = " ".join(str(text).split()).encode("latin-1", errors="replace").decode("latin-1")
    return text if len(text) <= 96 else text[:93] + "..."


def drive_metadata(result) -> dict[str, str]:
    """Header keys of the RPC III drive: what made it, for which scenario and target, after how
    many drive updates (``iterations``: the updates behind the drive written, ``rig_runs``: rig
    runs the iteration made), its status and gain."""
    from rigsim.scenarios.records.output import rigsim_version

    rigsim = rigsim_version()
    it = result.iteration
    meta = {"made_by": "rigsim iterate", "rigsim_version": rigsim, "scenario": result.scenario_name,
            "target": result.target, "iterations": str(it.best_index), "rig_runs": str(it.runs),
            "status": it.status, "gain": f"{it.gain:g}", "band_hz": "{:g} {:g}".format(*result.band_hz),
            "drive_unit": "m"}
    return {k: _header_value(v) for k, v in meta.items()}


def plot_png(result) -> bytes:
    """NRMSE against the target (1) per rig run of the iteration, the mean and each wheel, log scale."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    steps = result.iteration.steps
    fig, ax = plt.subplots(figsize=(6, 4))
    k = [s.index for s in steps]
    ax.semilogy(k, [s.nrmse_mean for s in steps], "o-k", label="mean")
    for i, c in enumerate(CORNERS):
        ax.semilogy(k, [s.nrmse[i] for s in steps], ".--", lw=0.8, label=c)
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.set_xlabel("iteration (rig run after the original)")
    ax.set_ylabel("NRMSE against the target")
    ax.set_title(f"{result.scenario_name}: target {result.target}, g = {result.iteration.gain:g}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    return buf.getvalue()


def comparison_table(result) -> str:
    """The comparison for the terminal: DLC, its error against the road, NRMSE against the road, rig runs."""
    it = result.iteration
    lines = [f"{result.scenario_name}: target {result.target}, {it.status}: {it.message}",
             f"{'':22s} {'DLC':>7s} {'DLC err':>8s} {'NRMSE':>7s} {'rig runs':>8s}"]
    for name, row in result.comparison.items():
        lines.append(f"{name:22s} {row.dlc:7.4f} {100 * row.dlc_error:7.1f}% {row.nrmse_vs_road:7.3f} "
                     f"{row.rig_runs:8d}")
    n = int(np.count_nonzero(result.compared))
    where = "where the output correction has settled" if result.score is not None else "(1 s inside both ends)"
    lines.append(f"DLC and NRMSE (against the road force): means of the four wheels over {n / result.rig.rate_hz:.2f} s "
                 f"{where}")
    if result.output_correction_error:
        lines.append(result.output_correction_error)
    return "\n".join(lines)


def write_files(result, out_dir) -> dict[str, pathlib.Path]:
    """Write :data:`FILES` into ``out_dir`` (replacing earlier ones); returns their paths by name."""
    d = pathlib.Path(out_dir)
    content = {"drive.csv": drive_csv_bytes(result), "iteration.json": to_json(result).encode("utf-8"),
               "iteration.png": plot_png(result)}
    write_channels(d / "drive.drv", drive_channels(result), metadata=drive_metadata(result), overwrite=True)
    for name, data in content.items():
        atomic_write_bytes(d / name, data)
    return {name: d / name for name in FILES}
