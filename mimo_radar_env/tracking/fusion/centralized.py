"""Centralised fusion: one IMM-UKF update per target with the stacked measurements of all
selected channels (the project's improvement on the paper's averaging)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...core.geometry import station_geometry
from ..imm import combine, logsumexp
from ..unscented import symmetrize, unscented_update
from .base import Fusion, Posterior, Prior


class CentralizedFusion(Fusion):
    """One unscented update with the ``2 Ms Ns`` stacked measurement, then IMM model probabilities."""

    name = "centralized"

    def update(
        self,
        prior: Prior,
        tx_positions: NDArray[np.float64],
        rx_positions: NDArray[np.float64],
        measurement: NDArray[np.float64],
        noise_variance: NDArray[np.float64],
    ) -> Posterior:
        sigmas = prior.sigmas
        B, K, R, S = sigmas.shape[:4]
        C = tx_positions.shape[1] * rx_positions.shape[1]
        # (B, K, R, S, Ms, Ns): channels innermost, stacked TX-major into one 2C measurement
        tx_range, rx_range, azimuth, sin, cos = station_geometry(
            sigmas[..., None, None, :],
            tx_positions[:, None, None, None, :, None],
            rx_positions[:, None, None, None, None, :],
        )
        range_sum = tx_range + rx_range
        full = range_sum.shape
        h = np.stack([range_sum, np.broadcast_to(azimuth, full)], axis=-1)
        result = unscented_update(
            prior.means,
            prior.covs,
            sigmas,
            h.reshape(B, K, R, S, 2 * C),
            measurement.reshape(B, K, 1, 2 * C),
            noise_variance.reshape(B, K, 1, 2 * C),
            prior.wm,
            prior.wc,
            (
                np.broadcast_to(sin, full).reshape(B, K, R, S, C),
                np.broadcast_to(cos, full).reshape(B, K, R, S, C),
            ),
        )
        log_post = result.log_likelihood + prior.log_c
        log_post -= logsumexp(log_post, axis=-1, keepdims=True)
        means, covs = result.mean, symmetrize(result.covariance)
        estimate, covariance = combine(means, covs, np.exp(log_post))
        return Posterior(means, covs, log_post, estimate, covariance)
