"""The compiled (numba) twin of the average fusion's numpy path (:mod:`.average`).

The kernel :func:`update` loops over trials, targets, channels and models and calls small
helpers, each the scalar twin of one numpy function of the numpy path:

- ``station_geometry``: :func:`mimo_radar_env.core.geometry.station_geometry`;
- ``measurement_mean``: :func:`mimo_radar_env.tracking.unscented.measurement_mean`;
- ``wrap_residual``: the azimuth wrap of ``unscented.measurement_residual``;
- ``innovation_moments``: the innovation and cross covariances of ``unscented.unscented_update``;
- ``kalman_update``: its gain, posterior mean and log-likelihood;
- ``logsumexp``: :func:`mimo_radar_env.tracking.imm.logsumexp`;
- ``symmetrize``: :func:`mimo_radar_env.tracking.unscented.symmetrize`;
- ``average_channels``: :func:`mimo_radar_env.tracking.fusion.average.average_channels`.

Only the order of floating-point sums differs from the numpy path: the two agree to
round-off (tested at 1e-10). Importing this module needs numba (the ``fast`` extra).
"""

from __future__ import annotations

import math

import numpy as np

from ...core.compiled import CHUNK, numba, twins

_TWO_PI = 2.0 * math.pi
_LOG_2PI = math.log(2.0 * math.pi)
# The helpers are serial (a threaded kernel spreads whole chunks of trials). numpy's error model: a
# division by zero (a singular innovation covariance, a target on a receiver) gives inf or NaN
# as the numpy path does, and the update's finiteness check falls back to the prediction in
# that trial, where Python's would raise ZeroDivisionError out of the env's step
njit = numba.njit(cache=True, error_model="numpy")


@njit
def station_geometry(sigmas, b, k, r, tx_x, tx_y, rx_x, rx_y, h0, h1, sn, cs):
    """Range sums, azimuths and their sines and cosines of the sigma points ``sigmas[b, k, r]``
    (S, 4) seen by one channel's stations, written into ``h0, h1, sn, cs`` (S,).

    (The helpers take whole arrays and indices: a view per call costs more than its loop.)"""
    for s in range(h0.shape[0]):
        px = sigmas[b, k, r, s, 0]
        py = sigmas[b, k, r, s, 2]
        dxt = px - tx_x
        dyt = py - tx_y
        dxr = px - rx_x
        dyr = py - rx_y
        rr = math.sqrt(dxr * dxr + dyr * dyr)
        h0[s] = math.sqrt(dxt * dxt + dyt * dyt) + rr
        h1[s] = math.atan2(dyr, dxr)
        sn[s] = dyr / rr
        cs[s] = dxr / rr


@njit
def measurement_mean(wm, h0, sn, cs):
    """The predicted (range sum, azimuth): the weighted range sum and the circular mean azimuth."""
    z0 = 0.0
    ssum = 0.0
    csum = 0.0
    for s in range(h0.shape[0]):
        z0 += wm[s] * h0[s]
        ssum += wm[s] * sn[s]
        csum += wm[s] * cs[s]
    return z0, math.atan2(ssum, csum)


@njit
def wrap_residual(angle):
    """An azimuth difference wrapped into [-pi, pi]."""
    return angle - _TWO_PI * np.rint(angle / _TWO_PI)


@njit
def innovation_moments(sigmas, means, b, k, r, wc, h0, h1, z0, z1, p0, p1):
    """The innovation covariance ``(s00, s01, s11)`` before the noise, and the cross
    covariance of the state and the measurement, written into ``p0, p1`` (n,), of the sigma
    points ``sigmas[b, k, r]`` around ``means[b, k, r]``."""
    n = p0.shape[0]
    s00 = 0.0
    s01 = 0.0
    s11 = 0.0
    for q in range(n):
        p0[q] = 0.0
        p1[q] = 0.0
    for s in range(h0.shape[0]):
        d0 = h0[s] - z0
        d1 = wrap_residual(h1[s] - z1)
        w0 = wc[s] * d0
        w1 = wc[s] * d1
        s00 += w0 * d0
        s01 += w0 * d1
        s11 += w1 * d1
        for q in range(n):
            dx = sigmas[b, k, r, s, q] - means[b, k, r, q]
            p0[q] += dx * w0
            p1[q] += dx * w1
    return s00, s01, s11


@njit
def kalman_update(prior, b, k, r, p0, p1, s00, s01, s11, y0, y1, c, gain, cross, posterior):
    """Gain ``P_xz S^-1`` (closed-form 2 x 2 inverse), the posterior mean of ``prior[b, k, r]``
    and the measurement's log-likelihood; writes channel ``c``'s ``gain[c, r]``,
    ``cross[c, r]`` (n, 2) and ``posterior[c, r]`` (n,)."""
    det = s00 * s11 - s01 * s01
    i00 = s11 / det
    i01 = -s01 / det
    i11 = s00 / det
    for q in range(p0.shape[0]):
        g0 = p0[q] * i00 + p1[q] * i01
        g1 = p0[q] * i01 + p1[q] * i11
        gain[c, r, q, 0] = g0
        gain[c, r, q, 1] = g1
        cross[c, r, q, 0] = p0[q]
        cross[c, r, q, 1] = p1[q]
        posterior[c, r, q] = prior[b, k, r, q] + g0 * y0 + g1 * y1
    maha = y0 * y0 * i00 + 2.0 * y0 * y1 * i01 + y1 * y1 * i11
    return -0.5 * (maha + math.log(det) + 2.0 * _LOG_2PI)


@njit
def logsumexp(values):
    """``log(sum(exp(values)))`` of a 1-d array, stable for finite inputs."""
    top = values[0]
    for i in range(1, values.shape[0]):
        top = max(top, values[i])
    total = 0.0
    for i in range(values.shape[0]):
        total += math.exp(values[i] - top)
    return top + math.log(total)


@njit
def symmetrize(matrix):
    """``(A + A') / 2`` of a square matrix, in place."""
    n = matrix.shape[0]
    for q in range(n):
        for u in range(q + 1, n):
            v = 0.5 * (matrix[q, u] + matrix[u, q])
            matrix[q, u] = v
            matrix[u, q] = v


@njit
def average_channels(
    pred_covs, means, log_post, gain, cross, model_means, model_covs, log_probs, estimate, covariance, channel
):
    """eq22 for one trial and target: the means over channels of the per-model posteriors and
    model probabilities, and the mean of the channels' combined estimates and covariances.

    ``pred_covs`` (R, n, n); ``means`` (C, R, n), ``log_post`` (C, R) normalised per channel,
    ``gain``/``cross`` (C, R, n, 2); writes ``model_means`` (R, n), ``model_covs`` (R, n, n),
    ``log_probs`` (R,), ``estimate`` (n,) and ``covariance`` (n, n); ``channel`` (n,) is
    scratch space.
    """
    C, R, n = means.shape
    for r in range(R):
        log_probs[r] = logsumexp(log_post[:, r]) - math.log(C)
        for q in range(n):
            acc = 0.0
            for c in range(C):
                acc += means[c, r, q]
            model_means[r, q] = acc / C
        for q in range(n):
            for u in range(n):
                acc = 0.0
                for c in range(C):
                    acc += gain[c, r, q, 0] * cross[c, r, u, 0] + gain[c, r, q, 1] * cross[c, r, u, 1]
                model_covs[r, q, u] = pred_covs[r, q, u] - acc / C
        symmetrize(model_covs[r])
    for q in range(n):
        estimate[q] = 0.0
        for u in range(n):
            covariance[q, u] = 0.0
    for c in range(C):
        for q in range(n):
            channel[q] = 0.0
        for r in range(R):
            p = math.exp(log_post[c, r])
            for q in range(n):
                channel[q] += p * means[c, r, q]
        for q in range(n):
            estimate[q] += channel[q] / C
        for r in range(R):
            w = math.exp(log_post[c, r]) / C
            for q in range(n):
                dq = means[c, r, q] - channel[q]
                for u in range(n):
                    post = pred_covs[r, q, u] - (
                        gain[c, r, q, 0] * cross[c, r, u, 0] + gain[c, r, q, 1] * cross[c, r, u, 1]
                    )
                    covariance[q, u] += w * (post + dq * (means[c, r, u] - channel[u]))
    symmetrize(covariance)


def _update(sigmas, pred_means, pred_covs, log_c, wm, wc, tx, rx, measurement, variance):
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
    for chunk in numba.prange((B + CHUNK - 1) // CHUNK):
        # the chunk's scratch: a sigma point's geometry, a model's channel moments, the channels'
        # posteriors (each trial overwrites what it reads)
        h0, h1, sn, cs = np.empty(S), np.empty(S), np.empty(S), np.empty(S)
        p0, p1, channel = np.empty(n), np.empty(n), np.empty(n)
        means, log_post = np.empty((C, R, n)), np.empty((C, R))
        gain, cross = np.empty((C, R, n, 2)), np.empty((C, R, n, 2))
        for b in range(chunk * CHUNK, min(B, (chunk + 1) * CHUNK)):
            for k in range(K):
                for c in range(C):
                    i = c // num_rx
                    j = c - i * num_rx
                    for r in range(R):
                        station_geometry(
                            sigmas,
                            b,
                            k,
                            r,
                            tx[b, i, 0],
                            tx[b, i, 1],
                            rx[b, j, 0],
                            rx[b, j, 1],
                            h0,
                            h1,
                            sn,
                            cs,
                        )
                        z0, z1 = measurement_mean(wm, h0, sn, cs)
                        s00, s01, s11 = innovation_moments(
                            sigmas, pred_means, b, k, r, wc, h0, h1, z0, z1, p0, p1
                        )
                        y0 = measurement[b, k, c, 0] - z0
                        y1 = wrap_residual(measurement[b, k, c, 1] - z1)
                        s00 += variance[b, k, c, 0]
                        s11 += variance[b, k, c, 1]
                        log_likelihood = kalman_update(
                            pred_means, b, k, r, p0, p1, s00, s01, s11, y0, y1, c, gain, cross, means
                        )
                        log_post[c, r] = log_likelihood + log_c[b, k, r]
                    norm = logsumexp(log_post[c])
                    for r in range(R):
                        log_post[c, r] -= norm
                average_channels(
                    pred_covs[b, k],
                    means,
                    log_post,
                    gain,
                    cross,
                    model_means[b, k],
                    model_covs[b, k],
                    log_probs[b, k],
                    estimate[b, k],
                    covariance[b, k],
                    channel,
                )
    return model_means, model_covs, log_probs, estimate, covariance


#: The kernel, serial and over threads (:func:`~mimo_radar_env.core.compiled.twins`).
update, update_threaded = twins(_update, error_model="numpy")
