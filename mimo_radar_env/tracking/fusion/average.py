"""The paper's average fusion (eq22), with a numpy path and a compiled (numba) path.

Every selected channel runs one IMM-UKF update from the common fused prior with its own
measurement; the fused per-model means, covariances and model probabilities are the means
over the ``Ms * Ns`` channels, and the fused estimate and covariance the means of the
channels' combined estimates and covariances (eq22).

The numba path does for every trial, target, channel and model what the numpy path does with
arrays: the same arithmetic, only the order of floating-point sums differs, so the two agree
to round-off (tested at 1e-10). numba is optional (``pip install numba``); without it the
numpy path runs.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ...core.compiled import HAVE_NUMBA, numba
from ...core.geometry import station_geometry
from ..imm import logsumexp
from ..unscented import symmetrize, unscented_update
from .base import Fusion, Posterior, Prior

_TWO_PI = 2.0 * math.pi
_LOG_2PI = math.log(2.0 * math.pi)


class AverageFusion(Fusion):
    """eq22: the mean over channels of per-channel IMM-UKF updates of one prior."""

    name = "average"

    def update(
        self,
        prior: Prior,
        tx_positions: NDArray[np.float64],
        rx_positions: NDArray[np.float64],
        measurement: NDArray[np.float64],
        noise_variance: NDArray[np.float64],
    ) -> Posterior:
        path = _update_numba if self.use_numba else _update_numpy
        return Posterior(
            *path(
                prior.sigmas,
                prior.means,
                prior.covs,
                prior.log_c,
                prior.wm,
                prior.wc,
                tx_positions,
                rx_positions,
                measurement,
                noise_variance,
            )
        )


def _update_numpy(
    sigmas: NDArray[np.float64],
    pred_means: NDArray[np.float64],
    pred_covs: NDArray[np.float64],
    log_c: NDArray[np.float64],
    wm: NDArray[np.float64],
    wc: NDArray[np.float64],
    tx_positions: NDArray[np.float64],
    rx_positions: NDArray[np.float64],
    measurement: NDArray[np.float64],
    noise_variance: NDArray[np.float64],
) -> tuple[NDArray[np.float64], ...]:
    """The numpy path (the reference of the numba path); same arguments and results."""
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
        return np.broadcast_to(a, full).reshape(B, K, C, R, S)

    h = np.stack([per_channel(tx_range + rx_range), per_channel(azimuth)], axis=-1)
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
        pred_covs, result.mean, np.exp(log_post), result.gain, result.cross_cov
    )
    log_post = logsumexp(log_post, axis=2) - np.log(C)
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
    B, K, C, R, n = means.shape
    d = gain.shape[-1]

    def fold(a: NDArray[np.float64]) -> NDArray[np.float64]:  # (B, K, C, R, n, d) -> (B, K, R, n, C*d)
        return np.moveaxis(a, 2, -2).reshape(B, K, R, n, C * d)

    folded_cross_t = np.swapaxes(fold(cross_cov), -1, -2)
    model_covs = symmetrize(prior_covs - (fold(gain) @ folded_cross_t) / C)
    weights = probs / C  # each channel's combined estimate enters the mean with 1/C
    channel_mean = np.einsum("bkcr,bkcri->bkci", probs, means)
    spread = (means - channel_mean[..., None, :]).reshape(B, K, C * R, n)
    weighted_spread = spread * weights.reshape(B, K, C * R, 1)
    covariance = np.einsum("bkr,bkrij->bkij", weights.sum(axis=2), prior_covs)
    covariance -= (fold(gain * weights[..., None, None]) @ folded_cross_t).sum(axis=2)
    covariance += np.swapaxes(weighted_spread, -1, -2) @ spread
    return means.mean(axis=2), model_covs, channel_mean.mean(axis=2), symmetrize(covariance)


if HAVE_NUMBA:  # pragma: no branch

    @numba.njit(cache=True)  # serial: numba threads contend with OpenBLAS's spinning threads here
    def _update_numba(
        sigmas,
        pred_means,
        pred_covs,
        log_c,
        wm,
        wc,
        tx,
        rx,
        measurement,
        variance,
    ):
        """Returns ``(model_means, model_covs, log_probs, estimate, covariance)``.

        Shapes: sigmas (B, K, R, S, 4), pred_means (B, K, R, 4), pred_covs (B, K, R, 4, 4),
        log_c (B, K, R), tx (B, Ms, 2), rx (B, Ns, 2), measurement and variance (B, K, C, 2).
        """
        B, K, R, S, n = sigmas.shape
        num_rx = rx.shape[1]
        C = measurement.shape[2]
        model_means = np.zeros((B, K, R, n))
        model_covs = np.empty((B, K, R, n, n))
        log_probs = np.empty((B, K, R))
        estimate = np.zeros((B, K, n))
        covariance = np.empty((B, K, n, n))
        for b in range(B):
            h0 = np.empty(S)
            h1 = np.empty(S)
            sn = np.empty(S)
            cs = np.empty(S)
            means = np.empty((C, R, n))
            gain = np.empty((C, R, n, 2))
            cross = np.empty((C, R, n, 2))
            log_post = np.empty((C, R))
            p0 = np.empty(n)
            p1 = np.empty(n)
            chan = np.empty(n)
            for k in range(K):
                for c in range(C):
                    i = c // num_rx
                    j = c - i * num_rx
                    for r in range(R):
                        for s in range(S):
                            px = sigmas[b, k, r, s, 0]
                            py = sigmas[b, k, r, s, 2]
                            dxt = px - tx[b, i, 0]
                            dyt = py - tx[b, i, 1]
                            dxr = px - rx[b, j, 0]
                            dyr = py - rx[b, j, 1]
                            rr = math.sqrt(dxr * dxr + dyr * dyr)
                            h0[s] = math.sqrt(dxt * dxt + dyt * dyt) + rr
                            h1[s] = math.atan2(dyr, dxr)
                            sn[s] = dyr / rr
                            cs[s] = dxr / rr
                        z0 = 0.0
                        ssum = 0.0
                        csum = 0.0
                        for s in range(S):
                            z0 += wm[s] * h0[s]
                            ssum += wm[s] * sn[s]
                            csum += wm[s] * cs[s]
                        z1 = math.atan2(ssum, csum)
                        s00 = 0.0
                        s01 = 0.0
                        s11 = 0.0
                        for q in range(n):
                            p0[q] = 0.0
                            p1[q] = 0.0
                        for s in range(S):
                            d0 = h0[s] - z0
                            d1 = h1[s] - z1
                            d1 -= _TWO_PI * np.rint(d1 / _TWO_PI)
                            w0 = wc[s] * d0
                            w1 = wc[s] * d1
                            s00 += w0 * d0
                            s01 += w0 * d1
                            s11 += w1 * d1
                            for q in range(n):
                                dx = sigmas[b, k, r, s, q] - pred_means[b, k, r, q]
                                p0[q] += dx * w0
                                p1[q] += dx * w1
                        s00 += variance[b, k, c, 0]
                        s11 += variance[b, k, c, 1]
                        det = s00 * s11 - s01 * s01
                        i00 = s11 / det
                        i01 = -s01 / det
                        i11 = s00 / det
                        y0 = measurement[b, k, c, 0] - z0
                        y1 = measurement[b, k, c, 1] - z1
                        y1 -= _TWO_PI * np.rint(y1 / _TWO_PI)
                        for q in range(n):
                            g0 = p0[q] * i00 + p1[q] * i01
                            g1 = p0[q] * i01 + p1[q] * i11
                            gain[c, r, q, 0] = g0
                            gain[c, r, q, 1] = g1
                            cross[c, r, q, 0] = p0[q]
                            cross[c, r, q, 1] = p1[q]
                            means[c, r, q] = pred_means[b, k, r, q] + g0 * y0 + g1 * y1
                        maha = y0 * y0 * i00 + 2.0 * y0 * y1 * i01 + y1 * y1 * i11
                        log_post[c, r] = -0.5 * (maha + math.log(det) + 2.0 * _LOG_2PI) + log_c[b, k, r]
                    top = log_post[c, 0]
                    for r in range(1, R):
                        top = max(top, log_post[c, r])
                    total = 0.0
                    for r in range(R):
                        total += math.exp(log_post[c, r] - top)
                    norm = top + math.log(total)
                    for r in range(R):
                        log_post[c, r] -= norm
                # eq22 fusion over channels
                for r in range(R):
                    top = log_post[0, r]
                    for c in range(1, C):
                        top = max(top, log_post[c, r])
                    total = 0.0
                    for c in range(C):
                        total += math.exp(log_post[c, r] - top)
                    log_probs[b, k, r] = top + math.log(total) - math.log(C)
                    for q in range(n):
                        acc = 0.0
                        for c in range(C):
                            acc += means[c, r, q]
                        model_means[b, k, r, q] = acc / C
                    for q in range(n):
                        for u in range(n):
                            acc = 0.0
                            for c in range(C):
                                acc += (
                                    gain[c, r, q, 0] * cross[c, r, u, 0]
                                    + gain[c, r, q, 1] * cross[c, r, u, 1]
                                )
                            model_covs[b, k, r, q, u] = pred_covs[b, k, r, q, u] - acc / C
                for q in range(n):
                    for u in range(q + 1, n):
                        for r in range(R):
                            v = 0.5 * (model_covs[b, k, r, q, u] + model_covs[b, k, r, u, q])
                            model_covs[b, k, r, q, u] = v
                            model_covs[b, k, r, u, q] = v
                # the mean over channels of each channel's combined estimate and covariance
                for q in range(n):
                    for u in range(n):
                        covariance[b, k, q, u] = 0.0
                for c in range(C):
                    for q in range(n):
                        chan[q] = 0.0
                    for r in range(R):
                        p = math.exp(log_post[c, r])
                        for q in range(n):
                            chan[q] += p * means[c, r, q]
                    for q in range(n):
                        estimate[b, k, q] += chan[q] / C
                    for r in range(R):
                        w = math.exp(log_post[c, r]) / C
                        for q in range(n):
                            dq = means[c, r, q] - chan[q]
                            for u in range(n):
                                post = pred_covs[b, k, r, q, u] - (
                                    gain[c, r, q, 0] * cross[c, r, u, 0]
                                    + gain[c, r, q, 1] * cross[c, r, u, 1]
                                )
                                covariance[b, k, q, u] += w * (post + dq * (means[c, r, u] - chan[u]))
                for q in range(n):
                    for u in range(q + 1, n):
                        v = 0.5 * (covariance[b, k, q, u] + covariance[b, k, u, q])
                        covariance[b, k, q, u] = v
                        covariance[b, k, u, q] = v
        return model_means, model_covs, log_probs, estimate, covariance
