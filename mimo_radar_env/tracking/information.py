"""The predicted information of a super arm: how much its channels would shrink the position
uncertainty of the tracker's prediction (docs/model.md, section 14).

For target k with the tracker's one-step prediction (mean ``x_bar``, covariance ``P_bar``),
each channel's measurement Jacobian ``H_mn`` at ``x_bar`` (eq6; it involves the position only)
and measurement covariance ``R_mn = Sigma0 / lambda_mn`` (eq32), the posterior information of
super arm ``A`` is ``J_A = P_bar^-1 + sum_{(m, n) in A} H_mn' R_mn^-1 H_mn``. Because the
measurements see the position only, the position block of ``J_A^-1`` is
``(S^-1 + I_A)^-1`` with ``S`` the predicted position covariance (the 2 x 2 block of
``P_bar``) and ``I_A`` the channels' position information: every super arm costs one 2 x 2
inverse. The criterion is ``sum_k Omega_k trace`` of that block (the predicted posterior
position MSE, m^2), or ``sum_k Omega_k log det`` of it; smaller is better.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import NDArray

from ..core.geometry import measurement_jacobian

Criterion = Literal["trace", "logdet"]
CRITERIA: tuple[str, ...] = ("trace", "logdet")


def channel_information(
    positions: NDArray[np.float64],
    tx: NDArray[np.float64],
    rx: NDArray[np.float64],
    variance: NDArray[np.float64],
) -> NDArray[np.float64]:
    """``H_mn' R_mn^-1 H_mn`` in position coordinates for every target and channel.

    ``positions`` (..., K, 2) where the Jacobians are taken; stations (M, 2), (N, 2);
    ``variance`` (..., K, M, N, 2) the diagonal of ``R_mn`` (range sum, azimuth).
    Returns (..., K, M, N, 2, 2).
    """
    jac = measurement_jacobian(positions, tx, rx)  # (..., K, M, N, 2, 2): rows = measurements
    weighted = jac / variance[..., :, None]
    return np.einsum("...ji,...jk->...ik", jac, weighted)


def _inverse_2x2(a: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Inverse and determinant of (..., 2, 2) matrices, in closed form."""
    det = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    inv = np.stack(
        [np.stack([a[..., 1, 1], -a[..., 0, 1]], -1), np.stack([-a[..., 1, 0], a[..., 0, 0]], -1)], -2
    )
    return inv / det[..., None, None], det


def super_arm_criterion(
    position_cov: NDArray[np.float64],
    information: NDArray[np.float64],
    tx_masks: NDArray[np.bool_],
    rx_masks: NDArray[np.bool_],
    weights: NDArray[np.float64],
    criterion: str = "trace",
) -> NDArray[np.float64]:
    """The criterion of every super arm in every trial: (B, A).

    ``position_cov`` (B, K, 2, 2) the predicted position covariance; ``information``
    (B, K, M, N, 2, 2) from :func:`channel_information`; ``tx_masks`` (A, M) and ``rx_masks``
    (A, N) the super arms; ``weights`` (K,) ``Omega``.
    """
    if criterion not in CRITERIA:
        raise ValueError(f"criterion must be one of {list(CRITERIA)}, got {criterion!r}")
    prior_info, _ = _inverse_2x2(position_cov)  # (B, K, 2, 2)
    selected = tx_masks[:, :, None].astype(float) * rx_masks[:, None, :]  # (A, M, N)
    gained = np.einsum("amn,bkmnij->bkaij", selected, information)  # (B, K, A, 2, 2)
    posterior, _ = _inverse_2x2(prior_info[:, :, None] + gained)
    if criterion == "trace":
        per_target = posterior[..., 0, 0] + posterior[..., 1, 1]
    else:
        _, det = _inverse_2x2(posterior)
        per_target = np.log(det)
    return np.einsum("k,bka->ba", np.asarray(weights, dtype=np.float64), per_target)
