"""The identification's Bode figure (data against fit, per corner) and its files, rendered in memory."""

from __future__ import annotations

import io

import numpy as np

__all__ = ["bode_png"]


def bode_png(fits, title: str) -> bytes:
    """Magnitude (dB), phase (deg) and coherence of the H1 estimate against the fitted T_a, per corner.

    ``fits``: ``{corner: rigsim.correction.identification.actuator_result.ActuatorFit}``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(9, 8.5), sharex=True, gridspec_kw={"height_ratios": [3, 3, 1.5]})
    colors = dict(zip(fits, ("tab:blue", "tab:orange", "tab:green", "tab:red")))
    for corner, fit in fits.items():
        f = np.asarray(fit.f_hz)
        sel = (f >= fit.band_hz[0]) & (f <= fit.band_hz[1])
        f_fine = np.geomspace(fit.band_hz[0], fit.band_hz[1], 400)
        model = fit.frequency_response(f_fine)
        c = colors[corner]
        axes[0].semilogx(f[sel], 20 * np.log10(np.abs(fit.h[sel])), ".", ms=2.5, color=c, alpha=0.5)
        axes[0].semilogx(f_fine, 20 * np.log10(np.abs(model)), "-", color=c,
                         label=f"{corner}: orders {fit.orders[0]}/{fit.orders[1]}, -3 dB at {fit.bandwidth_hz:.1f} Hz")
        axes[1].semilogx(f[sel], np.degrees(np.unwrap(np.angle(fit.h[sel]))), ".", ms=2.5, color=c, alpha=0.5)
        axes[1].semilogx(f_fine, np.degrees(np.unwrap(np.angle(model))), "-", color=c)
        axes[2].semilogx(f[sel], fit.coherence[sel], "-", color=c, lw=1.0)
    axes[0].set_ylabel("|T_a|, dB")
    axes[1].set_ylabel("phase, deg")
    axes[2].set_ylabel("coherence")
    axes[2].set_ylim(0.5, 1.01)
    axes[2].set_xlabel("frequency, Hz")
    axes[0].legend(fontsize=8, loc="lower left")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
    fig.suptitle(f"{title}: H1 estimate (dots) and fitted T_a (lines)", fontsize=11)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()
