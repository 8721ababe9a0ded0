"""How a scenario is put into a rerun recording and laid out in the viewer.

- :func:`log_case`: the entity tree of one scenario (described in :mod:`rigsim.scenarios.review.recording`):
  the per-wheel series grouped by plot (:func:`case_series`, :data:`PLOTS`), the 3D scene
  (:func:`geom_shapes`, MuJoCo's wxyz quaternions turned into rerun's xyzw; the road under
  the tracks, :func:`road_lines`) and the text panels (:func:`dlc_markdown`,
  :func:`parameters_markdown`).
- :func:`review_blueprint`: the 3D view of the rig and the truck, with the DLC table and the
  scenario's parameters under it, beside the plots. The plots are in tabs (tire force,
  displacement, pressure, spool), each tab one plot per wheel in a 2 x 2 grid laid out like
  the truck seen from above (fl fr / rl rr); road, rig and corrected tire forces of a wheel
  are overlaid on one plot.

Imported only by :func:`rigsim.scenarios.review.recording.write_recording`, so rerun is loaded only when a
recording is written.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from rigsim.correction.metrics.dlc import force_statistics
from rigsim.mjcf.names import pan_body

__all__ = ["COLORS", "PLOTS", "case_series", "log_case", "road_lines", "xyzw", "series_lines", "geom_shapes",
           "review_blueprint", "dlc_markdown", "parameters_markdown"]

#: Line colour (RGB) of each series name; road blue, rig red, corrected green.
COLORS: dict[str, tuple[int, int, int]] = {
    "road": (31, 119, 180),
    "rig": (214, 39, 40),
    "corrected": (44, 160, 44),
    "drive": (90, 90, 90),
    "pan road": (31, 119, 180),
    "pan rig": (214, 39, 40),
    "p1": (148, 103, 189),
    "p2": (255, 127, 14),
    "spool": (214, 39, 40),
}
#: Colour of the road profile line strips.
ROAD_COLOR = (230, 200, 60)
_ROAD_DX_M = 0.1  # m; point spacing of the road line strips
_FLOOR_HALF_M = (7.0, 4.0)  # m; an infinite MuJoCo plane is drawn as this finite slab
_FLOOR_RGBA = (0.2, 0.3, 0.4, 1.0)  # the darker colour of scene.xml's checker texture
# 3D eye: front-left three-quarter view of the cab, the whole truck and its pans in frame.
_EYE = {"position": (7.5, 8.0, 3.4), "look_target": (0.6, 0.0, 0.6), "eye_up": (0.0, 0.0, 1.0)}
#: Plots show this window around the time cursor (s), so they follow playback; zoom out for all.
PLOT_WINDOW_S = (-2.5, 2.5)


def xyzw(q_wxyz) -> np.ndarray:
    """MuJoCo's scalar-first quaternions (..., 4) in rerun's scalar-last order."""
    return np.asarray(q_wxyz)[..., [1, 2, 3, 0]]


def _rotate(q_wxyz: np.ndarray, v: np.ndarray) -> np.ndarray:
    w, u = q_wxyz[..., :1], q_wxyz[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def series_lines(names, unit: str) -> rr.SeriesLines:
    """Legend names (with the unit) and colours of the series of one plot, in row order."""
    suffix = f" ({unit})" if unit and unit != "1" else ""
    palette = list(COLORS.values())
    colors = [COLORS.get(n, palette[i % len(palette)]) for i, n in enumerate(names)]
    return rr.SeriesLines(names=[f"{n}{suffix}" for n in names], colors=colors, widths=[1.0] * len(names))


def geom_shapes(geoms) -> dict[str, dict[str, object]]:
    """Rerun shapes of :class:`rigsim.scenarios.core.poses.Geoms`: ``{body: {kind: archetype}}``, each
    in its body's frame (one archetype per body and geom type)."""
    g = geoms
    rgba = np.array(g.rgba, dtype=float)
    rgba[[k == "plane" for k in g.kind]] = _FLOOR_RGBA  # the floor's texture does not survive
    colors = np.round(np.clip(rgba, 0, 1) * 255).astype(np.uint8)
    out: dict[str, dict[str, object]] = {}
    for body, kind in dict.fromkeys(zip(g.body, g.kind)):
        sel = np.array([b == body and k == kind for b, k in zip(g.body, g.kind)])
        size, pos, quat, col = g.size_m[sel], g.pos_m[sel], g.quat_wxyz[sel], colors[sel]
        common = {"quaternions": xyzw(quat), "colors": col, "fill_mode": "solid"}
        if kind in ("box", "plane"):
            half = size.copy()
            if kind == "plane":  # infinite planes (size 0) become a thin slab below their surface
                half[:, :2] = np.where(half[:, :2] > 0, half[:, :2], _FLOOR_HALF_M)
                half[:, 2] = 0.005
                pos = pos - _rotate(quat, np.array([0.0, 0.0, 0.005]))
            shape = rr.Boxes3D(half_sizes=half, centers=pos, **common)
        elif kind == "cylinder":  # both: axis along the geom's z; MuJoCo size = (radius, half length)
            shape = rr.Cylinders3D(lengths=2 * size[:, 1], radii=size[:, 0], centers=pos, **common)
        elif kind == "capsule":  # rerun's capsule starts at its translation and runs along +z
            half_axis = np.column_stack([np.zeros_like(size[:, 1]), np.zeros_like(size[:, 1]), size[:, 1]])
            shape = rr.Capsules3D(lengths=2 * size[:, 1], radii=size[:, 0],
                                  translations=pos - _rotate(quat, half_axis), **common)
        else:  # sphere
            shape = rr.Ellipsoids3D(half_sizes=np.repeat(size[:, :1], 3, axis=1), centers=pos, **common)
        out.setdefault(body, {})[kind] = shape
    return out


#: The plots of each wheel: entity ``/rig/<corner>/<plot>`` -> (unit, its series in order).
#: Series names: the source ("road", "rig", "corrected") or the quantity ("drive", "p1"...).
PLOTS: dict[str, tuple[str, tuple[str, ...]]] = {
    "displacement": ("m", ("drive", "pan road", "pan rig")),
    "tire_force": ("N", ("road", "rig", "corrected")),
    "pressure": ("Pa", ("p1", "p2")),
    "spool": ("1", ("spool",)),
}


def case_series(runs, corrected: np.ndarray | None = None) -> dict[str, dict[str, np.ndarray]]:
    """The time series of one scenario grouped by plot: ``{plot: {series: (N, 4) array}}``.

    ``runs`` maps a mode ("road", "rig") to its result. Plots and series follow
    :data:`PLOTS`; the road run's pan is left out when it equals the drive (a plain road
    test), and signals of unknown names get a plot of their own with one series per mode.
    """
    out: dict[str, dict[str, np.ndarray]] = {}
    first = next(iter(runs.values()))
    out["displacement"] = {"drive": np.asarray(first.signals["profile_m"])}
    for mode, r in runs.items():
        sig = r.signals
        if "pan_m" in sig and not (mode == "road" and np.array_equal(sig["pan_m"], sig["profile_m"])):
            out["displacement"][f"pan {mode}"] = np.asarray(sig["pan_m"])
        if "tire_force_N" in sig:
            out.setdefault("tire_force", {})[mode] = np.asarray(sig["tire_force_N"])
        for key, (plot, name) in {"p1_Pa": ("pressure", "p1"), "p2_Pa": ("pressure", "p2"),
                                  "spool": ("spool", "spool")}.items():
            if key in sig:
                out.setdefault(plot, {})[name if len(runs) == 1 or mode == "rig" else f"{name} {mode}"] = \
                    np.asarray(sig[key])
        for key in sig.keys() - {"profile_m", "pan_m", "tire_force_N", "p1_Pa", "p2_Pa", "spool"}:
            out.setdefault(key, {})[mode] = np.asarray(sig[key])
    if corrected is not None:
        out.setdefault("tire_force", {})["corrected"] = np.asarray(corrected)
    return out


def log_case(rec, name: str, runs, *, track, corrected=None, dlc_table: str | None = None) -> None:
    """Log one scenario into the recording stream ``rec``: its series, scene and text.

    Parameters
    ----------
    rec : rerun.RecordingStream
    name : str
        The scenario, also the recording's name.
    runs : mapping of str to RunResult
        Mode -> result, on one time axis.
    track : rigsim.scenarios.core.poses.PoseTrack
        The poses and geoms of the 3D scene.
    corrected : numpy.ndarray, N, optional
        (N, 4) corrected tire forces.
    dlc_table : str, optional
        A DLC table as text, shown as it is.
    """
    rec.send_recording_name(name)
    first = next(iter(runs.values()))
    n = first.t_s.size
    time = [_time_column(first.t_s)]
    for plot, series in case_series(runs, corrected).items():
        names = list(series)
        style = series_lines(names, PLOTS.get(plot, ("", ()))[0])
        for i, c in enumerate(first.corners):
            path = f"/rig/{c}/{plot}"
            values = np.column_stack([series[k][:, i] for k in names])  # (N, k): one row per time
            rec.log(path, style, static=True)
            rec.send_columns(path, indexes=time,
                             columns=rr.Scalars.columns(scalars=values.ravel()).partition([len(names)] * n))

    rec.log("/scene", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for body, shapes in geom_shapes(track.geoms).items():
        for kind, shape in shapes.items():
            rec.log(f"/scene/{body}/{kind}", shape, static=True)
    time = [_time_column(track.t_s)]
    for b, body in enumerate(track.bodies):
        rec.send_columns(f"/scene/{body}", indexes=time, columns=rr.Transform3D.columns(
            translation=track.position_m[:, b], quaternion=xyzw(track.quat_wxyz[:, b])))
    road = road_lines(first, track)
    if road is not None:
        strips, shift_x = road
        for side, pts in strips.items():
            rec.log(f"/scene/road/{side}", rr.LineStrips3D([pts], colors=[ROAD_COLOR], radii=0.02), static=True)
        rec.send_columns("/scene/road", indexes=time, columns=rr.Transform3D.columns(
            translation=np.column_stack([shift_x, np.zeros((shift_x.size, 2))])))

    stats = {m: r.statistics() for m, r in runs.items()}
    if corrected is not None:
        st = force_statistics(corrected, axis=0)
        stats["corrected"] = {c: {k: float(v[i]) for k, v in st.items()} for i, c in enumerate(first.corners)}
    rec.log("/info/dlc", rr.TextDocument(dlc_markdown(name, stats), media_type="text/markdown"), static=True)
    rec.log("/info/parameters", rr.TextDocument(parameters_markdown(name, runs), media_type="text/markdown"),
            static=True)
    if dlc_table is not None:
        rec.log("/info/dlc_table", rr.TextDocument(dlc_table), static=True)


def road_lines(result, track) -> tuple[dict[str, np.ndarray], np.ndarray] | None:
    """The road profile under each track, and how far it has moved at each pose frame.

    The left track (fl, rl) and the right track (fr, rr) are lines of points (distance along
    x = speed * t, lateral position between the two pans of that side, elevation = the drive)
    in a road frame; at time t that frame is shifted by ``shift_x = x_front - speed * t``, so
    the road passes under the standing truck and the point under each pan is that pan's drive.
    The rear wheel runs a wheelbase behind the front one: the first wheelbase of road comes
    from the rear drive, the rest from the front drive.

    Returns
    -------
    ({"left": (P, 3), "right": (P, 3)} in m, shift_x (M,) in m at ``track.t_s``), or None when
    the speed or the pans are unknown.
    """
    speed = float(result.info.get("speed_kmh", 0.0)) / 3.6
    pans = [pan_body(c) for c in result.corners]
    if speed <= 0 or not all(p in track.bodies for p in pans) or track.t_s.size == 0:
        return None
    fl, fr, rl, rr_ = (track.position_m[0, track.bodies.index(p)] for p in pans)
    wheelbase = float(fl[0] - rl[0])
    prof = np.asarray(result.signals["profile_m"])
    s = speed * np.asarray(result.t_s, dtype=float)
    step = max(1, int(round(_ROAD_DX_M * result.rate_hz / speed)))
    behind = s < wheelbase
    strips = {}
    for side, front, rear, y in (("left", 0, 2, 0.5 * (fl[1] + rl[1])), ("right", 1, 3, 0.5 * (fr[1] + rr_[1]))):
        x = np.concatenate([s[behind] - wheelbase, s])[::step]
        z = np.concatenate([prof[behind, rear], prof[:, front]])[::step]
        strips[side] = np.column_stack([x, np.full_like(x, y), z])
    return strips, fl[0] - speed * np.asarray(track.t_s, dtype=float)


def _time_column(t_s) -> rr.TimeColumn:
    """The ``time`` column (s): rounded to whole ns (rerun truncates float seconds, which
    would put 1 ms at 999 999 ns)."""
    ns = np.round(np.asarray(t_s, dtype=float) * 1e9).astype(np.int64)
    return rr.TimeColumn("time", duration=ns.astype("timedelta64[ns]"))


def _wheel_grid(plot: str, corners) -> rrb.Grid:
    name = plot.replace("_", " ")
    window = rrb.VisibleTimeRange("time", start=rrb.TimeRangeBoundary.cursor_relative(seconds=PLOT_WINDOW_S[0]),
                                  end=rrb.TimeRangeBoundary.cursor_relative(seconds=PLOT_WINDOW_S[1]))
    views = [rrb.TimeSeriesView(origin=f"/rig/{c}/{plot}", name=f"{c} {name}", time_ranges=window,
                                plot_legend=rrb.PlotLegend(corner="RightTop", visible=True))
             for c in corners]
    return rrb.Grid(*views, grid_columns=2, name=name)


def review_blueprint(corners, plots=("tire_force", "displacement", "pressure", "spool")) -> rrb.Blueprint:
    """The review layout for recordings whose wheels are ``corners`` (fl fr rl rr).

    Parameters
    ----------
    corners : sequence of str
        Wheel names, in :data:`rigsim.mjcf.names.CORNERS` order (two per axle, left first).
    plots : sequence of str
        The per-wheel plots ``/rig/<corner>/<plot>``, one tab each, the first one shown.
    """
    scene = rrb.Spatial3DView(origin="/scene", name="rig and truck",
                              eye_controls=rrb.EyeControls3D(**_EYE),
                              line_grid=rrb.LineGrid3D(visible=False))
    texts = rrb.Tabs(
        rrb.TextDocumentView(origin="/info/dlc", name="DLC"),
        rrb.TextDocumentView(origin="/info/parameters", name="parameters"),
        rrb.TextDocumentView(origin="/info/dlc_table", name="DLC table"),
    )
    tabs = rrb.Tabs(*(_wheel_grid(plot, corners) for plot in plots), active_tab=0)
    return rrb.Blueprint(
        rrb.Horizontal(rrb.Vertical(scene, texts, row_shares=[3, 1]), tabs, column_shares=[1, 1]),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline="time"),
        collapse_panels=False,
    )


def dlc_markdown(name: str, stats: Mapping[str, Mapping[str, Mapping[str, float]]]) -> str:
    """The DLC table of one scenario: ``stats[source][corner]`` holds ``mean_force_N`` and
    ``dlc`` (as :meth:`rigsim.scenarios.core.results.RunResult.statistics`)."""
    head = "| wheel | " + " | ".join(f"{m} mean (N) | {m} DLC" for m in stats) + " |"
    lines = [f"# DLC: {name}", "", head, "|---" * (1 + 2 * len(stats)) + "|"]
    for c in next(iter(stats.values())):
        cells = " | ".join(f"{s[c]['mean_force_N']:.0f} | {s[c]['dlc']:.4f}" for s in stats.values())
        lines.append(f"| {c} | {cells} |")
    lines += ["", "DLC = standard deviation / mean of the tire force."]
    return "\n".join(lines)


def parameters_markdown(name: str, runs) -> str:
    """The facts of each run of one scenario (``runs``: mode -> RunResult)."""
    lines = [f"# Scenario {name}", ""]
    for mode, r in runs.items():
        lines += [f"## {mode} mode", "", f"- vehicle mass: {r.vehicle_mass_kg:.1f} kg",
                  f"- samples: {r.t_s.size} at {r.rate_hz:.6g} Hz"]
        lines += [f"- {k}: {v}" for k, v in r.info.items()]
        lines += [f"- event {ev}: {per}" for ev, per in r.events.items()]
        lines.append("")
    return "\n".join(lines)
