"""The model-correction study's tables and goals, from its rows (one per case and plant).

A row (``benchmarks/model_correction.py``'s ``analyse``) holds ``case``, ``plant`` (a readable
name, :func:`rigsim.scenarios.studies.model_suite.plants.plant_name`), ``plant_key`` (rigid / cab / tire
/ smooth), ``mismatch`` ("off": the plant inside the calibrated model family, "on": outside),
``method`` and ``reason`` (the model correction or the fallback to the linear one, and why),
``calibration`` (:class:`rigsim.scenarios.records.model.result.Calibration` or None), ``truth`` (the
plant's values of the fitted fields, SI), per-wheel figures under ``wheels`` (``floor``,
``linear``, ``linear_dlc_error``, ``rig``, and ``model``, ``model_dlc_error`` unless it fell back;
NRMSE and DLC errors, 1), their ``mean``, ``scored_s`` (s), ``cpu_s`` and ``wall_s`` (s,
calibration plus correction).

The study's goals: the delivered NRMSE at most half the linear floor where the plant lies inside
the model family (mismatch off), below it where outside (on); every wheel within 1 % of the road
DLC; calibration plus correction of a 60 s case within :data:`GOAL_S` on 2 cores.
"""

from __future__ import annotations

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.studies.model_suite.goals import DLC_GOOD, FLOOR_RATIO

__all__ = ["GOAL_S", "FLOOR_GOALS", "wheels", "delivered", "plants_of", "cab_cell", "table", "summary", "goals",
           "suite_cells", "plants_line", "suite_table"]

#: Wall-time goal of calibration plus correction of a 60 s case, s.
GOAL_S = 300.0
#: Per mismatch: the bound on delivered NRMSE / linear floor (1) and its words (off: at most, on: below).
FLOOR_GOALS = {"off": (FLOOR_RATIO, "at most half"), "on": (1.0, "below")}


def wheels(row: dict, key: str) -> np.ndarray:
    """Per wheel (fl, fr, rl, rr) figure ``key`` of one row."""
    return np.array([row["wheels"][key][c] for c in CORNERS])


def delivered(row: dict) -> tuple[np.ndarray, np.ndarray]:
    """Per wheel: NRMSE and DLC error (1) of what the method delivers: the model correction, or the
    linear correction where it falls back."""
    m = "model" if "model" in row["wheels"] else "linear"
    return wheels(row, m), wheels(row, f"{m}_dlc_error")


def plants_of(rows: list[dict]) -> dict[str, dict]:
    """The rows' plants in their order: plant key -> its first row."""
    out = {}
    for r in rows:
        out.setdefault(r["plant_key"], r)
    return out


def cab_cell(row: dict) -> str:
    """The calibrated model's cab, short: "held" (rigid), "fitted 2.01 Hz" (its mount), "-" (no calibration)."""
    cal = row.get("calibration")
    if cal is None:
        return "-"
    return "held" if cal.fitted_cab_hz is None else f"fitted {cal.fitted_cab_hz:.3g} Hz"


def table(rows: list[dict]) -> str:
    """One markdown table per case: per wheel and plant, floor, linear and model correction; then per
    plant the method, the calibration's cab choice and its fit."""
    lines = []
    for case in dict.fromkeys(r["case"] for r in rows):
        mine = [r for r in rows if r["case"] == case]
        lines += [f"\n### {case} ({mine[0]['scored_s']:.1f} s scored)\n",
                  "| plant (mismatch) | wheel | rig | linear floor | linear correction | model correction "
                  "| model / floor | DLC error linear | DLC error model | fit NRMSE (model error) |", "|" + " --- |" * 10]
        for r in mine:
            w, cal = r["wheels"], r["calibration"]
            for i, c in enumerate(CORNERS + ("mean",)):
                get = (lambda k: r["mean"].get(k)) if c == "mean" else (lambda k: w[k][c] if k in w else None)
                fit = (float(np.mean(cal.fit_nrmse)) if c == "mean" else cal.fit_nrmse[i]) if cal else None
                err = (float(np.mean(cal.excess_nrmse)) if c == "mean" else cal.excess_nrmse[i]) if cal else None
                model = get("model")
                cells = [f"{r['plant_key']} ({r['mismatch']})", c, f"{get('rig'):.4f}", f"{get('floor'):.4f}",
                         f"{get('linear'):.4f}", "-" if model is None else f"{model:.4f}",
                         "-" if model is None else f"{model / get('floor'):.2f}",
                         f"{get('linear_dlc_error'):+.2%}",
                         "-" if model is None else f"{get('model_dlc_error'):+.2%}", "-" if fit is None else f"{fit:.3f} ({err:.3f})"]
                lines.append("| " + " | ".join(cells) + " |")
        for r in mine:
            cal = r["calibration"]
            lines.append(f"\n{r['plant_key']}, {r['plant']} (mismatch {r['mismatch']}): {r['method']} correction"
                         + (f" ({r['reason']})" if r["reason"] else "")
                         + f"; calibration + correction {r['wall_s']:.0f} s wall, {r['cpu_s']:.0f} s CPU"
                         + (f"; calibration {cal.evaluations} model evaluations, converged {cal.converged}, "
                            f"{cal.wall_time_s:.0f} s" if cal else ""))
            for said in cal.choices if cal else ():
                lines.append("\n" + said[0].upper() + said[1:])
            if cal and cal.second_start:
                lines.append("\n" + cal.second_start[0].upper() + cal.second_start[1:])
            if cal:
                lines.append("\n" + cal.table(r["truth"]))
    return "\n".join(lines)


def summary(rows: list[dict]) -> dict:
    """Per mismatch ("off" / "on"): its plants, the share of wheels meeting each goal, the worst wheel,
    the runs and fallbacks; CPU and wall time of calibration plus correction (s, median and largest)."""
    out = {}
    for mismatch, (bound, _) in FLOOR_GOALS.items():
        rs = [r for r in rows if r["mismatch"] == mismatch]
        if not rs:
            continue
        ratio = np.concatenate([delivered(r)[0] / wheels(r, "floor") for r in rs])
        dl = np.abs(np.concatenate([delivered(r)[1] for r in rs]))
        out[mismatch] = {"plants": list(dict.fromkeys(r["plant"] for r in rs)), "runs": len(rs),
                         "wheels": int(ratio.size), "fallbacks": sum(r["method"] != "model" for r in rs),
                         "floor_goal_share": float(np.mean(ratio <= bound if mismatch == "off" else ratio < bound)),
                         "worst_ratio": float(ratio.max()), "dlc_within_1pct_share": float(np.mean(dl <= DLC_GOOD)),
                         "worst_dlc_error": float(dl.max())}
    for k in ("cpu_s", "wall_s"):
        v = [r[k] for r in rows]
        out[k] = {"median": float(np.median(v)), "max": float(np.max(v))}
    return out


def goals(rows: list[dict], duration_s: float) -> str:
    """One line per goal of the study: the share of wheels that meet it, met or not, the worst wheel
    (``duration_s``, s: the records' length)."""
    s, out = summary(rows), []
    for mismatch, (_, word) in FLOOR_GOALS.items():
        g = s.get(mismatch)
        if g is None:
            out.append(f"- mismatch {mismatch}: not run (no plant {'outside' if mismatch == 'on' else 'inside'} "
                       "the calibrated model family among those run)")
            continue
        out.append(f"- mismatch {mismatch} ({', '.join(g['plants'])}; {g['wheels']} wheels, {g['fallbacks']} of "
                   f"{g['runs']} runs fell back to the linear correction): NRMSE {word} the linear floor: "
                   f"{g['floor_goal_share']:.0%} of wheels, {'met' if g['floor_goal_share'] == 1 else 'NOT met'} "
                   f"(worst wheel delivered / floor {g['worst_ratio']:.2f}); within {100 * DLC_GOOD:g} % of the road DLC: "
                   f"{g['dlc_within_1pct_share']:.0%} of wheels, "
                   f"{'met' if g['dlc_within_1pct_share'] == 1 else 'NOT met'} (worst {g['worst_dlc_error']:.2%})")
    c, w = s["cpu_s"], s["wall_s"]
    out.append(f"- calibration + correction within {GOAL_S:.0f} s on 2 cores (records of {duration_s:g} s; the goal "
               f"is for 60 s): CPU per run median {c['median']:.0f} s, largest {c['max']:.0f} s, i.e. >= "
               f"{c['max'] / 2:.0f} s on 2 dedicated cores ({'met' if c['max'] / 2 <= GOAL_S else 'NOT met'}); "
               f"wall median {w['median']:.0f} s, largest {w['max']:.0f} s (shared machine)")
    return "\n".join(out)


def suite_cells(rows: list[dict]) -> tuple[list[str], list[list[str]]]:
    """The header and cells of :func:`suite_table`: two rows per case (front, rear: the worse wheel of
    the axle), the plants side by side in the rows' order ("a / b / c")."""
    plants = plants_of(rows)
    keys = " / ".join(plants)
    heads = ["case", "wheels", f"linear floor, {keys}", f"linear correction, {keys}", f"model (x floor), {keys}",
             f"DLC error delivered, {keys}", f"cab, {keys}", f"CPU s, {keys}", "fallback"]
    cells = []
    for case in dict.fromkeys(r["case"] for r in rows):
        by = {r["plant_key"]: r for r in rows if r["case"] == case}

        def each(fn):
            return " / ".join(fn(by[p]) if p in by else "-" for p in plants)

        for axle, sel in (("front", [0, 1]), ("rear", [2, 3])):
            def model(r):
                if "model" not in r["wheels"]:
                    return "fallback"
                m = wheels(r, "model")
                return f"{m[sel].max():.3f} ({(m / wheels(r, 'floor'))[sel].max():.2f} x)"

            def dlc_err(r):
                e = delivered(r)[1][sel]
                return f"{e[np.argmax(np.abs(e))]:+.2%}"

            first = axle == "front"
            cells.append([case if first else "", axle, each(lambda r: f"{wheels(r, 'floor')[sel].max():.3f}"),
                          each(lambda r: f"{wheels(r, 'linear')[sel].max():.3f}"), each(model), each(dlc_err),
                          each(cab_cell) if first else "", each(lambda r: f"{r['cpu_s']:.0f}") if first else "",
                          "; ".join(f"{p}: {r['reason']}" for p, r in by.items() if r["reason"]) if first else ""])
    return heads, cells


def plants_line(rows: list[dict]) -> str:
    """Which plant is which: "Plants: rigid, rigid cab (mismatch off); ..."."""
    return ("Plants: " + "; ".join(f"{k}, {r['plant']} (mismatch {r['mismatch']})" for k, r in plants_of(rows).items())
            + ".")


def suite_table(rows: list[dict]) -> str:
    """One markdown table, two rows per case (front, rear: the worse wheel of the axle), the plants side
    by side in the rows' order ("a / b / c"), then which plant is which (:func:`suite_cells`,
    :func:`plants_line`)."""
    heads, cells = suite_cells(rows)
    lines = ["| " + " | ".join(heads) + " |", "|" + " --- |" * len(heads)]
    lines += ["| " + " | ".join(c) + " |" for c in cells]
    lines.append("\n" + plants_line(rows))
    return "\n".join(lines)
