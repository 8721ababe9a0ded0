"""Files and terminal table of ``rigsim iterate``: the drive CSV, the error plot, ``iteration.json``.

``DIR/drive.csv``: the best iterated drive (m) per corner at the output rate, t >= 0 (s);
``DIR/iteration.json``: :meth:`scenarios.studies.iterate.compute.IterateResult.to_dict`;
``DIR/iteration.png``: the NRMSE against the target per iteration. All written atomically,
after all three are made in memory.
"""

from __future__ import annotations

import io
import pathlib

import numpy as np

from mjcf.names import CORNERS
from scenarios.core.files import atomic_write_bytes, to_json

__all__ = ["drive_csv_bytes", "plot_png", "comparison_table", "write_files", "FILES"]

FILES = ("drive.csv", "iteration.json", "iteration.png")


def drive_csv_bytes(result) -> bytes:
    """The iterated drive as CSV: ``time_s`` (s) and ``drive_<corner>_m`` (m), ``%.10g``."""
    buf = io.StringIO()
    header = ",".join(["time_s"] + [f"drive_{c}_m" for c in CORNERS])
    np.savetxt(buf, np.column_stack([result.t_s, result.iteration.drive]), delimiter=",", fmt="%.10g",
               header=header, comments="")
    return buf.getvalue().encode("ascii")


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
    """Write :data:`FILES` into ``out_dir``; returns their paths by name."""
    d = pathlib.Path(out_dir)
    content = {"drive.csv": drive_csv_bytes(result), "iteration.json": to_json(result).encode("utf-8"),
               "iteration.png": plot_png(result)}
    for name, data in content.items():
        atomic_write_bytes(d / name, data)
    return {name: d / name for name in FILES}
