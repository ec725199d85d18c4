"""Centralised fusion: one IMM-UKF update per target with the stacked measurements of all
selected channels (the project's improvement on the paper's averaging), with a numpy path and
a compiled (numba) path.

The numba path (:mod:`._centralized_kernels`) does for every trial, target and model what the
numpy path does with arrays: the same arithmetic, only the order of floating-point sums
differs, so the two agree to round-off (tested at 1e-10). numba is optional (``pip install
numba``); without it, and for stacked measurements of
:data:`~mimo_radar_env.tracking.unscented.WOODBURY_MIN_DIMENSION` dimensions or more, the
numpy path runs.
"""

from __future__ import annotations

import numpy as np

from ...core.arrays import namespace
from ...core.compiled import HAVE_NUMBA, LazyKernels
from ...core.geometry import station_geometry
from .. import unscented
from ..imm import combine, logsumexp
from ..information import inverse_2x2, woodbury_gain
from ..unscented import symmetrize, unscented_update
from .base import CHANNEL_OPERATIONS, SIGMA_POINTS, Fusion


class CentralizedFusion(Fusion):
    """One unscented update with the ``2 Ms Ns`` stacked measurement, then IMM model probabilities.

    Its predicted posterior of a super arm adds the channels' information,
    ``(S^-1 + sum_A I_mn)^-1``, and so does its gain in the planner."""

    name = "centralized"
    compiled_posterior = "information"

    @staticmethod
    def channel_terms(prior_info, information):
        return information

    @staticmethod
    def posterior_from_sum(prior_info, total, count):
        return inverse_2x2(prior_info + total)[0]

    @staticmethod
    def planning_gain(information, position_cov, selected):
        return woodbury_gain(np.einsum("smn,skmnij->skij", selected, information), position_cov)

    @staticmethod
    def update_operations(channels):
        size = 2 * channels  # range and azimuth of every probed channel, stacked
        woodbury = size >= unscented.WOODBURY_MIN_DIMENSION
        inverse = SIGMA_POINTS**2 * size if woodbury else size**3 / 3
        # twice the arithmetic: it runs as many small numpy calls (the average fusion is compiled)
        return 2 * (channels * CHANNEL_OPERATIONS + SIGMA_POINTS * size**2 + 8 * size**2 + inverse)

    @classmethod
    def compiled_kernels(cls, threaded: bool = False) -> list:
        return [_KERNELS.get("_update_numba_threaded" if threaded else "_update_numba")] if HAVE_NUMBA else []

    @classmethod
    def compiled_update(cls, channels: int) -> bool:
        return HAVE_NUMBA and 2 * channels < unscented.WOODBURY_MIN_DIMENSION

    def update(self, prior, tx_positions, rx_positions, measurement, noise_variance):
        compiled = self.use_numba and self.compiled_update(tx_positions.shape[1] * rx_positions.shape[1])
        path = _KERNELS.for_batch("_update_numba", len(measurement)) if compiled else _update_numpy
        return self.run_path(path, prior, tx_positions, rx_positions, measurement, noise_variance)


def _update_numpy(
    sigmas, pred_means, pred_covs, log_c, wm, wc, tx_positions, rx_positions, measurement, noise_variance
):
    """The numpy path (the reference of the numba path); same arguments and results."""
    xp = namespace(sigmas)
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
    h = xp.stack([range_sum, xp.broadcast_to(azimuth, full)], axis=-1)
    result = unscented_update(
        pred_means,
        pred_covs,
        sigmas,
        h.reshape(B, K, R, S, 2 * C),
        measurement.reshape(B, K, 1, 2 * C),
        noise_variance.reshape(B, K, 1, 2 * C),
        wm,
        wc,
        (
            xp.broadcast_to(sin, full).reshape(B, K, R, S, C),
            xp.broadcast_to(cos, full).reshape(B, K, R, S, C),
        ),
    )
    log_post = result.log_likelihood + log_c
    log_post -= logsumexp(log_post, axis=-1, keepdims=True)
    means, covs = result.mean, symmetrize(result.covariance)
    estimate, covariance = combine(means, covs, xp.exp(log_post))
    return means, covs, log_post, estimate, covariance


_KERNELS = LazyKernels(
    __name__,
    _update_numba="._centralized_kernels:update",
    _update_numba_threaded="._centralized_kernels:update_threaded",
)
__getattr__ = _KERNELS.module_getattr
