"""The figures of ``rigsim validate`` (matplotlib Agg, rendered to PNG bytes in memory).

Bode overlays of the three routes per wheel, coherence and cross-coupling, the Figure 7 step
responses, and where eq. 4 departs from the plant; all from a
:class:`~rigsim.scenarios.studies.validate.result.ValidateResult`.
"""

from __future__ import annotations

import io

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.studies.validate.result import ValidateResult
from rigsim.scenarios.studies.validate.routes import err_db_deg, freqresp
from rigsim.scenarios.studies.validate.settings import BODE_RANGE_HZ, COHERENCE_MIN, COMPARE_MAX_HZ

__all__ = ["phase_deg", "render_figures"]


def phase_deg(h) -> np.ndarray:
    """Phase in degrees, unwrapped along the finite values (NaN stays NaN)."""
    h = np.asarray(h)
    out = np.full(h.shape, np.nan)
    ok = np.isfinite(h)
    out[ok] = np.degrees(np.unwrap(np.angle(h[ok])))
    return out


def _png(fig) -> bytes:
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    return buf.getvalue()


def _bode(plt, cv, i: int, c: str) -> bytes:
    fb, f3 = cv.f_bode_hz, cv.f_ident_hz
    fig, ax = plt.subplots(3, 1, figsize=(8, 9), sharex=True)
    h2 = cv.h_route2[:, i, i]
    h1 = cv.h_route1[c]
    h3 = cv.h_ident[:, i, i]
    good = cv.coherence[:, i] > COHERENCE_MIN
    hf = freqresp(cv.fits[i], fb)
    for h, style, label in ((h1, "C0--", "route 1: eq. 4"), (h2, "k-", "route 2: linearized plant"),
                            (hf, "C2-", "route 3: rational fit")):
        ax[0].semilogx(fb, 20 * np.log10(np.abs(h)), style, label=label)
        ax[1].semilogx(fb, phase_deg(h), style)
    ax[0].semilogx(f3, 20 * np.log10(np.abs(h3)), "C1.", ms=3, label="route 3: H1 estimate")
    ax[1].semilogx(f3, phase_deg(h3), "C1.", ms=3)
    d1db, d1deg = err_db_deg(h1, h2)
    ax[2].semilogx(fb, d1db, "C0--", label="route 1 - route 2, dB")
    ax[2].semilogx(fb, d1deg / 10, "C0:", label="route 1 - route 2, deg/10")
    d3db, d3deg = err_db_deg(h3, cv.h_route2_at_ident[:, i, i])
    ax[2].semilogx(f3[good], d3db[good], "C1.", ms=3, label="route 3 (H1) - route 2, dB")
    ax[2].semilogx(f3[good], d3deg[good] / 10, "C3.", ms=3, label="route 3 (H1) - route 2, deg/10")
    for a in ax:
        a.axvline(COMPARE_MAX_HZ, color="0.7", lw=0.8)
        a.grid(True, which="both", lw=0.3)
    ax[0].set_ylabel("|x_a / x_ref| (dB)")
    ax[1].set_ylabel("phase (deg)")
    ax[2].set_ylabel("difference")
    ax[2].set_xlabel("frequency (Hz)")
    ax[2].set_xlim(*BODE_RANGE_HZ)
    ax[2].set_ylim(-6, 6)
    ax[0].set_ylim(-16, 3)
    ax[1].set_ylim(-240, 20)
    ax[0].legend(fontsize=8, loc="lower left")
    ax[2].legend(fontsize=7, loc="lower left", ncol=2)
    fig.suptitle(f"T_a of wheel {c}: three routes (grey line: {COMPARE_MAX_HZ:g} Hz)")
    fig.tight_layout()
    return _png(fig)


def _coherence_coupling(plt, cv) -> bytes:
    fig, ax = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for i, c in enumerate(CORNERS):
        ax[0].semilogx(cv.f_ident_hz, cv.coherence[:, i], label=c)
    ax[0].axhline(COHERENCE_MIN, color="k", lw=0.8)
    ax[0].set_ylabel("multiple coherence")
    ax[0].set_ylim(0.8, 1.005)
    ax[0].set_xlim(*BODE_RANGE_HZ)
    ax[0].legend(fontsize=8)
    for i in range(len(CORNERS)):
        for j in range(len(CORNERS)):
            if i != j:
                ax[1].semilogx(cv.f_bode_hz, 20 * np.log10(np.abs(cv.h_route2[:, i, j]) + 1e-12), lw=0.8)
    ax[1].set_ylabel("|x_a,i / x_ref,j|, i != j (dB)")
    ax[1].set_title("cross-coupling between wheels, route 2 (one line per path)", fontsize=9)
    ax[1].set_xlabel("frequency (Hz)")
    ax[1].set_ylim(-80, 0)
    for a in ax:
        a.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    return _png(fig)


def _steps(plt, cv, steps: dict) -> bytes:
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.5))
    for a, key in zip(ax, ("small", "large")):
        cur = cv.steps[key]
        t = cur["t_s"]
        for i, c in ((0, "fl"), (2, "rl")):
            a.plot(t, 1e3 * cur["nonlinear"][:, i], "k-" if i == 0 else "k-.", label=f"nonlinear rig {c}")
            a.plot(t, 1e3 * cur["route2"][:, i], "C3--", lw=1, label=f"route 2 {c}")
            a.plot(t, 1e3 * cur["route1"][:, i], "C0:", lw=1.2, label=f"eq. 4 {c}")
        a.set_xlim(0, 0.6)
        a.set_xlabel("time (s)")
        a.set_ylabel("pan displacement (mm)")
        e = steps[key]
        a.set_title(f"{1e3 * e['step_m']:g} mm step: nonlinear vs route 2 max "
                    f"{e['route2']['max_error_mm']:.3f} mm ({e['route2']['max_error_pct']:.2f} %)", fontsize=9)
        a.grid(True, lw=0.3)
    ax[0].legend(fontsize=7)
    fig.tight_layout()
    return _png(fig)


def _departure(plt, cv) -> bytes:
    fig, ax = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    fc = cv.f_compare_hz
    for name, style in (("eq4", "C0--"), ("two_chamber_static_valve", "C1:"), ("plus_spool_dynamics", "C2-")):
        db, deg = err_db_deg(cv.budget["fl"][name], cv.h_route2_compare[:, 0, 0])
        ax[0].semilogx(fc, db, style, label=name)
        ax[1].semilogx(fc, deg, style)
    ax[0].set_ylabel("minus route 2 (dB)")
    ax[1].set_ylabel("minus route 2 (deg)")
    ax[1].set_xlabel("frequency (Hz)")
    ax[0].legend(fontsize=8)
    for a in ax:
        a.grid(True, which="both", lw=0.3)
    fig.suptitle("Where eq. 4 departs from the plant (wheel fl)")
    fig.tight_layout()
    return _png(fig)


def render_figures(result: ValidateResult) -> dict[str, bytes]:
    """Every PNG of the report: ``bode_<c>.png`` per wheel, ``coherence_coupling.png``,
    ``steps.png`` and ``departure_fl.png``, as file name -> PNG bytes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cv = result.curves
    out = {f"bode_{c}.png": _bode(plt, cv, i, c) for i, c in enumerate(CORNERS)}
    out["coherence_coupling.png"] = _coherence_coupling(plt, cv)
    out["steps.png"] = _steps(plt, cv, result.steps)
    out["departure_fl.png"] = _departure(plt, cv)
    return out
