"""The goals the corrections are judged by, a suite of model corrections' table and their text.

The goals' one home: DLC within 1 % of the road's (:data:`DLC_GOOD`, the lab's own
:data:`~rigsim.scenarios.records.model.fallback.DLC_GOAL`) on :data:`SHARE` of the wheels and within
2 % (:data:`DLC_ALL`) on all, NRMSE at most :data:`FLOOR_RATIO` times the linear floor, at most
:data:`ABOVE_LINEAR` above the linear correction; read by every benchmark that judges a correction
(``generalization.py``, ``generalization_blame.py``, ``dyntrac_fit.py``, ``model_correction.py``
through :mod:`rigsim.scenarios.studies.model_suite.report`). The table and the goals' text are
shared by the mismatch suite (``benchmarks/mismatch_suite.py``) and the fleet suite
(``benchmarks/fleet_suite.py``): per plant the worse wheel's figures; over the wheels, the share
within 1 % of the road DLC at NRMSE at most half the plant's linear floor, the worst DLC error,
the worst NRMSE above the linear correction, and the fallbacks with their reasons.
"""

from __future__ import annotations

import numpy as np

from rigsim.scenarios.records.model.fallback import DLC_GOAL, HYBRID_LIMIT

__all__ = ["pct", "DLC_GOOD", "DLC_ALL", "FLOOR_RATIO", "SHARE", "ABOVE_LINEAR", "limit_evidence", "rows_and_goals",
           "good_wheels", "good_on_linear", "share_interval"]

#: The goals, 1: DLC within 1 % of the road's (95 % of wheels; the lab's fallback guards the same
#: figure) and 2 % (all), NRMSE at most half the linear floor (95 %), at most 0.05 above the linear
#: correction (all).
DLC_GOOD = DLC_GOAL
DLC_ALL, FLOOR_RATIO, SHARE, ABOVE_LINEAR = 0.02, 0.5, 0.95, 0.05


def pct(x: float) -> str:
    return f"{100 * x:+.2f} %"


def limit_evidence(scores) -> dict:
    """Where a limit on the model error would belong, wheel by wheel: each wheel's model error
    against whether the hybrid model correction, forced, beat the linear correction's NRMSE there. ``beats_up_to``: the largest model error of a wheel where it beat; ``loses_from``: the
    smallest where it did not (None where no wheel did not); a limit between them (when the first is
    below the second) separates the wheels; otherwise the wheels between them overlap, counted in
    ``overlap``."""
    err, beat = [], []
    for s in scores:
        if s.model_error is None or "hybrid" not in s.nrmse:
            continue
        err.extend(np.asarray(s.model_error, float))
        beat.extend(np.asarray(s.nrmse["hybrid"]) < np.asarray(s.nrmse["linear"]))
    err, beat = np.asarray(err), np.asarray(beat, bool)
    if not err.size:
        return {"wheels": 0, "beats_up_to": None, "loses_from": None, "overlap": 0}
    up_to = float(err[beat].max()) if beat.any() else None
    loses = float(err[~beat].min()) if (~beat).any() else None
    overlap = 0 if up_to is None or loses is None else int(np.sum((err >= loses) & (err <= up_to)))
    return {"wheels": int(err.size), "beats_up_to": up_to, "loses_from": loses, "overlap": overlap,
            "beats": int(beat.sum())}


def _limit_text(ev: dict) -> str:
    if not ev["wheels"]:
        return "- the model error against the hybrid's gain: no calibrated wheel to read it from"
    where = (f"beat the linear correction on {ev['beats']} of {ev['wheels']} wheels; the largest model error where it "
             f"beat: {ev['beats_up_to']:.3f}" if ev["beats_up_to"] is not None else
             f"beat the linear correction on none of {ev['wheels']} wheels")
    where += (f", the smallest where it did not: {ev['loses_from']:.3f}" if ev["loses_from"] is not None else
              ", on every wheel")
    if ev["loses_from"] is not None and ev["beats_up_to"] is not None:
        where += (f" ({ev['overlap']} wheels between them)" if ev["overlap"] else ": a limit between them separates them")
    return (f"- the forced hybrid {where} (past {HYBRID_LIMIT:g} a fit is searched again; the fallback is weighed on "
            "each record)")


def _error_text(score) -> str:
    """The worst model error on the calibration's windows and, where read, over the whole record."""
    if score.model_error is None:
        return ""
    rec = score.record_error
    return f"{np.max(score.model_error):.3f}" + ("" if rec is None else f" / {np.max(rec):.3f}")


def rows_and_goals(scores, describe) -> tuple[list[str], list[list], str, dict]:
    """The table (one row per plant, ``describe(score)`` its plant in words), the goals' text and their numbers."""
    head = ["case", "plant", "method", "model error (worst): windows / record", "worst DLC error", "NRMSE / floor (worst)",
            "linear NRMSE (worst)", "forced differential NRMSE (worst)", "hybrid NRMSE / floor (worst)",
            "hybrid worst DLC error", "wall s"]
    rows = []
    for s in scores:
        d, n = s.dlc_error["delivered"], s.nrmse["delivered"]
        forced = s.nrmse.get("forced")
        rows.append([s.name, describe(s), s.method,
                     _error_text(s), pct(d[np.argmax(np.abs(d))]),
                     f"{np.max(n / s.floor):.2f}", f"{np.max(s.nrmse['linear']):.3f}",
                     "" if forced is None else f"{np.max(forced):.3f}",
                     "" if forced is None else f"{np.max(s.nrmse['hybrid'] / s.floor):.2f}",
                     "" if forced is None else pct(s.dlc_error["hybrid"][np.argmax(np.abs(s.dlc_error["hybrid"]))]),
                     f"{s.wall_s:.0f}"])
    d = np.concatenate([s.dlc_error["delivered"] for s in scores])
    ratio = np.concatenate([s.nrmse["delivered"] / s.floor for s in scores])
    above = np.concatenate([s.nrmse["delivered"] - s.nrmse["linear"] for s in scores])
    lin = np.concatenate([s.dlc_error["linear"] for s in scores])
    good = np.mean((np.abs(d) <= DLC_GOOD) & (ratio <= FLOOR_RATIO))
    fallbacks = [s for s in scores if s.method != "model"]
    # the model correction the fallback refused is the hybrid (what --model delivers where the model holds)
    wrong = [s.name for s in fallbacks if "hybrid" in s.nrmse and np.all(s.nrmse["hybrid"] < s.nrmse["linear"])]
    numbers = {"wheels": int(d.size), "share_good": float(good), "worst_dlc_error": float(np.max(np.abs(d))),
               "worst_above_linear": float(np.max(above)), "fallbacks": len(fallbacks),
               "fallbacks_without_reason": sum(1 for s in fallbacks if not s.reason), "wrong_fallbacks": wrong,
               "median_wall_s": float(np.median([s.wall_s for s in scores])),
               "median_cpu_s": float(np.median([s.cpu_s for s in scores])), "limit": limit_evidence(scores)}
    met = {"share": good >= SHARE, "dlc": numbers["worst_dlc_error"] <= DLC_ALL,
           "linear": numbers["worst_above_linear"] <= ABOVE_LINEAR,
           "fallbacks": not wrong and not numbers["fallbacks_without_reason"]}
    text = "\n".join([
        f"- wheels within {100 * DLC_GOOD:g} % of the road DLC and at NRMSE <= {FLOOR_RATIO:g} x the linear floor: "
        f"{100 * good:.1f} % of {d.size} (goal >= {100 * SHARE:g} %): {'met' if met['share'] else 'NOT met'}",
        f"- worst DLC error: {100 * numbers['worst_dlc_error']:.2f} % (goal <= {100 * DLC_ALL:g} %): "
        f"{'met' if met['dlc'] else 'NOT met'}",
        f"- worst NRMSE above the linear correction: {numbers['worst_above_linear']:+.3f} (goal <= {ABOVE_LINEAR:g}): "
        f"{'met' if met['linear'] else 'NOT met'}",
        f"- fallbacks: {len(fallbacks)}, without a reason: {numbers['fallbacks_without_reason']}, where the forced "
        f"model correction (hybrid) was better on every wheel: {len(wrong)} ({', '.join(wrong) or 'none'}): "
        f"{'met' if met['fallbacks'] else 'NOT met'}",
        f"- within {100 * DLC_GOOD:g} % of the road DLC and at NRMSE <= {FLOOR_RATIO:g} x the linear correction's (not its "
        f"floor): {100 * np.mean(np.concatenate([good_on_linear(s, s.dlc_error['delivered'], s.nrmse['delivered']) for s in scores])):.1f} % of the wheels",
        f"- the two goals apart: within {100 * DLC_GOOD:g} % of the road DLC {100 * np.mean(np.abs(d) <= DLC_GOOD):.0f} % "
        f"of the wheels, at NRMSE <= {FLOOR_RATIO:g} x the floor {100 * np.mean(ratio <= FLOOR_RATIO):.0f} %",
        f"- DLC error over the wheels: median {pct(np.median(d))}, {100 * np.mean(d > 0):.0f} % above the road's "
        f"(the linear correction: median {pct(np.median(lin))}, {100 * np.mean(lin > 0):.0f} % above)",
        _limit_text(numbers["limit"]),
        f"- median wall time of a calibration and correction: {numbers['median_wall_s']:.0f} s"])
    return head, rows, text, numbers | {"met": met}




def good_wheels(score) -> np.ndarray:
    """Per wheel of one plant's score: within :data:`DLC_GOOD` of the road DLC and at NRMSE at most
    :data:`FLOOR_RATIO` times its linear floor (bool, (4,))."""
    d, n = np.abs(score.dlc_error["delivered"]), score.nrmse["delivered"] / score.floor
    return (d <= DLC_GOOD) & (n <= FLOOR_RATIO)


def good_on_linear(score, dlc_error, nrmse) -> np.ndarray:
    """Per wheel of one plant's ``score``, a correction's ``dlc_error`` and ``nrmse`` (1, (4,)) on the
    issue's terms: within :data:`DLC_GOOD` of the road DLC and at NRMSE at most :data:`FLOOR_RATIO`
    times the linear correction's (not its floor) (bool, (4,))."""
    return (np.abs(dlc_error) <= DLC_GOOD) & (np.asarray(nrmse) <= FLOOR_RATIO * score.nrmse["linear"])


def share_interval(scores, level: float = 0.95, resamples: int = 4000, seed: int = 0) -> tuple[float, float]:
    """A ``level`` confidence interval of the share of good wheels (:func:`good_wheels`) over trucks:
    the percentile bootstrap resampling whole trucks (a truck's four wheels are not independent),
    ``resamples`` draws from ``numpy.random.default_rng(seed)``."""
    good = np.array([good_wheels(s) for s in scores], dtype=float)  # trucks x 4
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, good.shape[0], size=(resamples, good.shape[0]))
    shares = good[picks].mean(axis=(1, 2))
    lo, hi = np.quantile(shares, [(1 - level) / 2, (1 + level) / 2])
    return float(lo), float(hi)
