"""The fitted parameters' uncertainties from a least-squares fit's Jacobian and residual."""

from __future__ import annotations

import numpy as np

__all__ = ["uncertainties"]


def uncertainties(jac, residual, block: int) -> tuple[np.ndarray, np.ndarray]:
    """1-sigma of the fitted (scaled) parameters: formal, sqrt(diag((J^T J)^-1 s^2)) with s^2 the
    residual variance on m - n degrees of freedom (white residual), and block-robust, the sandwich
    (J^T J)^-1 (sum_b J_b^T r_b r_b^T J_b) (J^T J)^-1 over blocks of ``block`` samples (4 residual
    rows each: one per wheel), which holds for a residual correlated over less than a block."""
    m, p = jac.shape
    bread = np.linalg.pinv(jac.T @ jac)
    formal = np.diag(bread) * float(residual @ residual) / max(m - p, 1)
    labels = (np.arange(m) // 4) // max(int(block), 1)
    scores = np.zeros((int(labels[-1]) + 1, p))
    np.add.at(scores, labels, jac * residual[:, None])
    robust = np.diag(bread @ (scores.T @ scores) @ bread)
    return np.sqrt(np.clip(formal, 0.0, None)), np.sqrt(np.clip(robust, 0.0, None))
