"""The summary plot of a sweep (``DIR/summary.png``, matplotlib's Agg backend).

Top rows: DLC against speed, one panel per roughness and payload: road, road through the
correction's band limit, rig, corrected (means over the cases that differ only in other swept
keys). Bottom rows: the correction error (NRMSE of the corrected force against the band-limited
road force; the uncorrected rig force in grey) against each swept key, every case a dot and the
mean a line. Failed cases are left out and counted in the title.
"""

from __future__ import annotations

import math
import pathlib
from collections import defaultdict
from collections.abc import Mapping

__all__ = ["plot_summary"]

_NCOLS = 4
_DLC_LINES = (("dlc_road", "road", "k", "-"), ("dlc_road_band", "road, band-limited", "0.5", ":"),
              ("dlc_rig", "rig", "tab:red", "--"), ("dlc_corrected", "corrected", "tab:blue", "-."))


def _get(doc: Mapping, key: str, default=None):
    node = doc
    for part in key.split("."):
        if not isinstance(node, Mapping) or part not in node:
            return default
        node = node[part]
    return node


def _road_label(doc: Mapping) -> str:
    road = doc.get("road", {})
    if "roughness" in road:
        return f"roughness {road['roughness']}"
    if "gd_n0_m3" in road:
        return f"Gd(n0) {road['gd_n0_m3']:.3g} m^3"
    return f"profile {pathlib.Path(str(road.get('profile_csv', '?'))).name}"


def _payload_label(doc: Mapping) -> str:
    p = _get(doc, "vehicle.payload_kg")
    return "nominal payload" if p is None else f"{float(p):g} kg"


def _numeric(values) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)


def plot_summary(grid, records: Mapping[str, dict], path) -> pathlib.Path:
    """Write the summary figure of a sweep.

    Parameters
    ----------
    grid : SweepGrid
    records : Mapping[str, dict]
        Case files by case id (:func:`rigsim.scenarios.studies.sweep.store.read_case_files`).
    path : path
        The PNG to write (atomically).

    Returns
    -------
    pathlib.Path
    """
    import io

    from matplotlib.figure import Figure  # no pyplot: the Agg canvas, no global figure state

    from rigsim.scenarios.core.files import atomic_write_bytes

    cases = {c.case_id: c for c in grid.cases}
    ok = [(cases[cid], rec["result"]) for cid, rec in sorted(records.items())
          if rec.get("status") == "ok" and cid in cases]
    n_failed = sum(1 for rec in records.values() if rec.get("status") != "ok")

    groups: dict[str, dict[float, list[dict]]] = defaultdict(lambda: defaultdict(list))
    for case, res in ok:
        label = f"{_road_label(case.doc)}, {_payload_label(case.doc)}"
        groups[label][float(case.doc["speed_kmh"])].append(res)
    keys = list(grid.keys) or ["speed_kmh"]
    n_top = max(1, len(groups))
    rows_top = math.ceil(n_top / _NCOLS)
    rows_bot = math.ceil(len(keys) / _NCOLS)
    ncols = min(_NCOLS, max(n_top, len(keys)))
    fig = Figure(figsize=(4.2 * ncols, 3.4 * (rows_top + rows_bot)), layout="constrained")
    fig.suptitle(f"sweep {grid.name}: {len(ok)} of {len(grid.cases)} cases"
                 + (f", {n_failed} failed" if n_failed else "")
                 + f" (T_a {grid.settings.actuator}, low-pass {grid.settings.lowpass}, "
                   f"{grid.settings.correction_mode}, noise {grid.settings.noise_N:g} N)")
    nrows = rows_top + rows_bot

    for i, (label, by_speed) in enumerate(sorted(groups.items())):
        ax = fig.add_subplot(nrows, ncols, i + 1)
        speeds = sorted(by_speed)
        for key, name, color, style in _DLC_LINES:
            ys = [sum(r[key] for r in by_speed[v]) / len(by_speed[v]) for v in speeds]
            ax.plot(speeds, ys, color=color, linestyle=style, marker="o", label=name)
        ax.set_title(label, fontsize=10)
        ax.set_xlabel("speed (km/h)")
        ax.set_ylabel("DLC (mean of 4 wheels)")
        ax.grid(True, alpha=0.3)
        if i == 0:
            ax.legend(fontsize=8)
    if not groups:
        ax = fig.add_subplot(nrows, ncols, 1)
        ax.text(0.5, 0.5, "no finished case", ha="center", va="center", transform=ax.transAxes)

    for j, key in enumerate(keys):
        ax = fig.add_subplot(nrows, ncols, rows_top * ncols + j + 1)
        xs_raw = [_get(case.doc, key) for case, _ in ok]
        numeric = _numeric(xs_raw)
        if numeric:
            xs = [float(x) for x in xs_raw]
            ticks = None
        else:
            levels = list(dict.fromkeys(str(x) for x in xs_raw))
            xs = [float(levels.index(str(x))) for x in xs_raw]
            ticks = levels
        for metric, name, color in (("nrmse_rig", "rig (uncorrected)", "0.6"),
                                    ("nrmse_corrected", "corrected", "tab:blue")):
            ys = [res[metric] for _, res in ok]
            ax.scatter(xs, ys, s=14, color=color, alpha=0.7, label=name)
            means = defaultdict(list)
            for x, y in zip(xs, ys):
                means[x].append(y)
            mx = sorted(means)
            ax.plot(mx, [sum(means[x]) / len(means[x]) for x in mx], color=color)
        if ticks is not None:
            ax.set_xticks(range(len(ticks)), ticks)
        ax.set_xlabel(key)
        ax.set_ylabel("NRMSE vs road, band-limited")
        ax.set_ylim(bottom=0)
        ax.grid(True, alpha=0.3)
        if j == 0:
            ax.legend(fontsize=8)

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    path = pathlib.Path(path)
    atomic_write_bytes(path, buf.getvalue())
    return path
