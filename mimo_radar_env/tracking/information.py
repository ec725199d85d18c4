"""The information a channel's measurement carries about a target's position (eq6, eq32).

Each channel ``(m, n)`` measures the range sum and azimuth of a target (eq6) with covariance
``R_mn = Sigma0 / lambda_mn`` (eq32). Linearised at a position, its Fisher information in
position coordinates is ``H_mn' R_mn^-1 H_mn`` with ``H_mn`` eq6's Jacobian: a 2 x 2 matrix
per target and channel. The selection criterion (:mod:`~mimo_radar_env.tracking.selection`)
and the posterior Cramer-Rao bound (:mod:`~mimo_radar_env.tracking.bound`) are built on it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..core.arrays import namespace
from ..core.geometry import measurement_jacobian
from ..core.motion import POSITION


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
    return jacobian_information(measurement_jacobian(positions, tx, rx), variance)


def jacobian_information(jacobian: NDArray[np.float64], variance: NDArray[np.float64]) -> NDArray[np.float64]:
    """``H' R^-1 H`` of Jacobians (..., 2, 2) (rows: range sum, azimuth) with diagonal ``R``,
    variances (..., 2): shape (..., 2, 2)."""
    xp = namespace(jacobian)
    return xp.einsum("...ji,...jk->...ik", jacobian, jacobian / variance[..., :, None])


def det_2x2(a: NDArray[np.float64]) -> NDArray[np.float64]:
    """Determinants of (..., 2, 2) matrices, in closed form."""
    return a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]


def position_determinant(covariance: NDArray[np.float64]) -> NDArray[np.float64]:
    """``det`` of the position block of state covariances (..., 4, 4) (``[x, vx, y, vy]``)."""
    return det_2x2(covariance[..., POSITION, POSITION])


def inverse_2x2(a: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Inverse and determinant of (..., 2, 2) matrices, in closed form."""
    xp = namespace(a)
    det = det_2x2(a)
    inv = xp.stack(
        [xp.stack([a[..., 1, 1], -a[..., 0, 1]], -1), xp.stack([-a[..., 1, 0], a[..., 0, 0]], -1)], -2
    )
    return inv / det[..., None, None], det


def woodbury_gain(information: NDArray[np.float64], position_cov: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(I + J P)^-1 J`` of position information ``J`` and a prior's position block ``P``
    (..., 2, 2): what Woodbury's identity subtracts, ``(P^-1 + E J E')^-1 = P - P E G E' P``
    (``E`` picks the position), symmetrised; no inverse of a 4 x 4 matrix, and ``J`` may be
    singular."""
    xp = namespace(information)
    j00, j01, j10, j11 = (information[..., i, k] for i, k in ((0, 0), (0, 1), (1, 0), (1, 1)))
    p00, p01, p10, p11 = (position_cov[..., i, k] for i, k in ((0, 0), (0, 1), (1, 0), (1, 1)))
    # M = I + J P, written out (products of 2 x 2 matrices by matmul are slower than this)
    m00, m01 = 1.0 + j00 * p00 + j01 * p10, j00 * p01 + j01 * p11
    m10, m11 = j10 * p00 + j11 * p10, 1.0 + j10 * p01 + j11 * p11
    det = m00 * m11 - m01 * m10
    g00, g11 = (m11 * j00 - m01 * j10) / det, (m00 * j11 - m10 * j01) / det
    g01 = 0.5 * ((m11 * j01 - m01 * j11) + (m00 * j10 - m10 * j00)) / det
    return xp.stack([xp.stack([g00, g01], -1), xp.stack([g01, g11], -1)], -2)
