"""The paper's average fusion (eq22), with a numpy path and a compiled (numba) path.

Every selected channel runs one IMM-UKF update from the common fused prior with its own
measurement; the fused per-model means, covariances and model probabilities are the means
over the ``Ms * Ns`` channels, and the fused estimate and covariance the means of the
channels' combined estimates and covariances (eq22).

The numba path (:mod:`._average_kernels`, small compiled helpers each mirroring the numpy
function it replaces) does for every trial, target, channel and model what the numpy path
does with arrays: the same arithmetic, only the order of floating-point sums differs, so the
two agree to round-off (tested at 1e-10). numba is optional (``pip install numba``); without
it the numpy path runs.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...core.arrays import namespace
from ...core.compiled import HAVE_NUMBA, LazyKernels
from ...core.geometry import station_geometry
from ..imm import logsumexp
from ..information import inverse_2x2, woodbury_gain
from ..unscented import symmetrize, unscented_update
from .base import CHANNEL_OPERATIONS, Fusion


class AverageFusion(Fusion):
    """eq22: the mean over channels of per-channel IMM-UKF updates of one prior.

    Its predicted posterior of a super arm is the mean over the channels of their
    single-channel posteriors ``(S^-1 + I_mn)^-1`` (the spread of the channels' means left
    out), and in the planner each channel's Woodbury gain is averaged the same way."""

    name = "average"
    compiled_posterior = "mean"

    @staticmethod
    def channel_terms(prior_info, information):
        return inverse_2x2(prior_info[:, :, None, None] + information)[0]

    @staticmethod
    def posterior_from_sum(prior_info, total, count):
        return total / count

    @staticmethod
    def planning_gain(information, position_cov, selected):
        count = selected.sum(axis=(1, 2))
        if (count == 0).any():
            raise ValueError("the average fusion needs at least one selected channel in every state")
        each = woodbury_gain(information, position_cov[:, :, None, None])  # (S, K, M, N, 2, 2)
        return np.einsum("smn,skmnij->skij", selected / count[:, None, None], each)

    @staticmethod
    def update_operations(channels):
        return channels * (CHANNEL_OPERATIONS + 300)  # one update per channel, then eq22's average

    @classmethod
    def compiled_kernels(cls, threaded: bool = False) -> list:
        return [_KERNELS.get("_update_numba_threaded" if threaded else "_update_numba")] if HAVE_NUMBA else []

    @classmethod
    def compiled_update(cls, channels: int) -> bool:
        return HAVE_NUMBA

    def update(self, prior, tx_positions, rx_positions, measurement, noise_variance):
        path = _KERNELS.for_batch("_update_numba", len(measurement)) if self.use_numba else _update_numpy
        return self.run_path(path, prior, tx_positions, rx_positions, measurement, noise_variance)


def _update_numpy(
    sigmas, pred_means, pred_covs, log_c, wm, wc, tx_positions, rx_positions, measurement, noise_variance
):
    """The numpy path (the reference of the numba path); same arguments and results."""
    xp = namespace(sigmas)
    B, K, R, S = sigmas.shape[:4]
    num_tx, num_rx = tx_positions.shape[1], rx_positions.shape[1]
    C = num_tx * num_rx
    # (B, K, C, R, S): every channel updates the common prior on its own; geometry is
    # computed per station, then laid out per channel (contiguous arrays are fastest)
    tx_range, rx_range, azimuth, sin, cos = station_geometry(
        sigmas[:, :, None, None],
        tx_positions[:, None, :, None, None, None],
        rx_positions[:, None, None, :, None, None],
    )
    full = (B, K, num_tx, num_rx, R, S)

    def per_channel(a: NDArray[np.float64]) -> NDArray[np.float64]:
        return xp.broadcast_to(a, full).reshape(B, K, C, R, S)

    h = xp.stack([per_channel(tx_range + rx_range), per_channel(azimuth)], axis=-1)
    result = unscented_update(
        pred_means[:, :, None],
        pred_covs[:, :, None],
        sigmas[:, :, None],
        h,
        measurement[:, :, :, None],
        noise_variance[:, :, :, None],
        wm,
        wc,
        (per_channel(sin)[..., None], per_channel(cos)[..., None]),
        with_covariance=False,
    )
    log_post = result.log_likelihood + log_c[:, :, None]
    log_post -= logsumexp(log_post, axis=-1, keepdims=True)  # (B, K, C, R)
    post_means, post_covs, estimate, covariance = average_channels(
        pred_covs, result.mean, xp.exp(log_post), result.gain, result.cross_cov
    )
    log_post = logsumexp(log_post, axis=2) - float(np.log(C))
    return post_means, post_covs, log_post, estimate, covariance


def average_channels(
    prior_covs: NDArray[np.float64],
    means: NDArray[np.float64],
    probs: NDArray[np.float64],
    gain: NDArray[np.float64],
    cross_cov: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """eq22 fusion of per-channel IMM posteriors that share one prior.

    Parameters
    ----------
    prior_covs : (B, K, R, n, n) the common predicted covariances
    means : (B, K, C, R, n) per-channel, per-model posterior means
    probs : (B, K, C, R) per-channel model probabilities
    gain, cross_cov : (B, K, C, R, n, d) per-channel Kalman gains and cross covariances;
        channel c's posterior covariance is ``prior_covs - gain_c @ cross_cov_c'``.

    Returns
    -------
    model_means, model_covs : (B, K, R, n), (B, K, R, n, n) means over channels
    estimate, covariance : (B, K, n), (B, K, n, n) the mean over channels of each
        channel's combined estimate and covariance

    The channel axis is folded into the inner dimension of one matrix product, so
    no per-channel (n, n) covariance is ever formed.
    """
    xp = namespace(means)
    B, K, C, R, n = means.shape
    d = gain.shape[-1]

    def fold(a: NDArray[np.float64]) -> NDArray[np.float64]:  # (B, K, C, R, n, d) -> (B, K, R, n, C*d)
        return xp.moveaxis(a, 2, -2).reshape(B, K, R, n, C * d)

    folded_cross_t = xp.swapaxes(fold(cross_cov), -1, -2)
    model_covs = symmetrize(prior_covs - xp.matmul(fold(gain), folded_cross_t) / C)
    weights = probs / C  # each channel's combined estimate enters the mean with 1/C
    channel_mean = xp.einsum("bkcr,bkcri->bkci", probs, means)
    spread = (means - channel_mean[..., None, :]).reshape(B, K, C * R, n)
    weighted_spread = spread * weights.reshape(B, K, C * R, 1)
    covariance = xp.einsum("bkr,bkrij->bkij", weights.sum(axis=2), prior_covs)
    covariance -= xp.matmul(fold(gain * weights[..., None, None]), folded_cross_t).sum(axis=2)
    covariance += xp.matmul(xp.swapaxes(weighted_spread, -1, -2), spread)
    return means.mean(axis=2), model_covs, channel_mean.mean(axis=2), symmetrize(covariance)


_KERNELS = LazyKernels(
    __name__,
    _update_numba="._average_kernels:update",
    _update_numba_threaded="._average_kernels:update_threaded",
)
__getattr__ = _KERNELS.module_getattr
