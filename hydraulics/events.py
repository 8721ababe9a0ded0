"""Saturation, cavitation and over-pressure events, derived after a run from recorded states.

The MuJoCo callbacks are pure functions of (model, data) and cannot log; instead the recorded
activation states are classified afterwards:

* ``spool_saturation``: ``|spool| >= CLIP_KNEE * ksv * command_limit``, i.e. the spool sits
  where the command clip is no longer linear (it is clipping the controller output);
* ``cavitation``: a chamber pressure below ``cavitation_pressure_Pa + 0.1 cavitation_band_Pa``,
  where the effective bulk modulus has fallen below ~4 % of nominal (gas release/vapour);
* ``overpressure``: a chamber pressure above ``relief_pressure_Pa`` (relief valve flowing).
"""

from __future__ import annotations

import numpy as np

from .model import CLIP_KNEE, MPA
from .packing import NSTATE
from .params import ActuatorParams

__all__ = ["events", "event_summary", "CAVITATION_BAND_FRACTION"]

#: Cavitation is flagged within this fraction of the band above the cavitation floor.
CAVITATION_BAND_FRACTION = 0.1


def events(states, params: ActuatorParams) -> dict[str, np.ndarray]:
    """Per-sample boolean event masks.

    Parameters
    ----------
    states : array_like, shape (..., 5)
        Activation states in ``STATE_NAMES`` order (e.g. ``(n_samples, 5)`` for one actuator or
        ``(n_samples, n_corners, 5)``).
    params : ActuatorParams

    Returns
    -------
    dict of str -> ndarray of bool, shape ``states.shape[:-1]``
        ``"spool_saturation"``, ``"cavitation"``, ``"overpressure"``.
    """
    x = np.asarray(states, dtype=np.float64)
    if x.shape[-1:] != (NSTATE,):
        raise ValueError(f"states must have a last axis of {NSTATE} (STATE_NAMES), got shape {x.shape}")
    p = params
    spool_lim = CLIP_KNEE * p.ksv * p.command_limit
    p_lo = (p.cavitation_pressure_Pa + CAVITATION_BAND_FRACTION * p.cavitation_band_Pa) / MPA
    p_hi = p.relief_pressure_Pa / MPA
    pressures = x[..., 2:4]
    return {
        "spool_saturation": np.abs(x[..., 0]) >= spool_lim,
        "cavitation": np.any(pressures < p_lo, axis=-1),
        "overpressure": np.any(pressures > p_hi, axis=-1),
    }


def event_summary(masks: dict[str, np.ndarray], t) -> dict[str, dict]:
    """Count and first time of each event (``t``: sample times in s along axis 0 of the masks).

    Returns ``{name: {"samples": int, "first_time_s": float | None}}``.
    """
    t = np.asarray(t, dtype=np.float64)
    out = {}
    for name, mask in masks.items():
        m = np.asarray(mask, dtype=bool)
        rows = m.reshape(m.shape[0], -1).any(axis=1) if m.ndim > 1 else m
        hits = np.nonzero(rows)[0]
        out[name] = {"samples": int(hits.size),
                     "first_time_s": float(t[hits[0]]) if hits.size else None}
    return out
