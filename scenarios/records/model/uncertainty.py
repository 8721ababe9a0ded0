"""The fitted parameters' uncertainties from a least-squares fit's Jacobian and residual."""

from __future__ import annotations

import numpy as np

__all__ = ["uncertainties"]


def uncertainties(jac, residual, block: int, mapping=None, rows: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """1-sigma of the fitted values: formal, from (J^T J)^-1 s^2 with s^2 the residual variance on
    m - n degrees of freedom (white residual), and block-robust, from the sandwich
    (J^T J)^-1 (sum_b J_b^T r_b r_b^T J_b) (J^T J)^-1 over blocks of ``block`` samples (``rows``
    residual rows each: one per wheel fitted), which holds for a residual correlated over less than a block. Each
    covariance of the fitted (scaled) parameters theta is carried to the values through
    ``mapping``, d value_i / d theta_j (n x n; None: the identity, the sigmas of theta), as
    M C M^T."""
    m, p = jac.shape
    mat = np.eye(p) if mapping is None else np.asarray(mapping, float)
    bread = np.linalg.pinv(jac.T @ jac)
    formal = bread * float(residual @ residual) / max(m - p, 1)
    labels = (np.arange(m) // rows) // max(int(block), 1)
    scores = np.zeros((int(labels[-1]) + 1, p))
    np.add.at(scores, labels, jac * residual[:, None])
    robust = bread @ (scores.T @ scores) @ bread
    return tuple(np.sqrt(np.clip(np.diag(mat @ c @ mat.T), 0.0, None)) for c in (formal, robust))
