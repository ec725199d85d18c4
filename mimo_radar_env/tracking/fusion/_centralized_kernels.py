"""The compiled (numba) twin of the centralised fusion's numpy path (:mod:`.centralized`).

The kernel :func:`update` loops over trials, targets and models; for each it stacks the
selected channels' predicted (range sum, azimuth) of the sigma points into one ``2 Ms Ns``
measurement and does what :func:`mimo_radar_env.tracking.unscented.unscented_update` does:

- the sigma points' geometry and the channels' predicted measurements come from the helpers of
  the average fusion's kernels (``station_geometry``, ``measurement_mean``, ``wrap_residual``),
  each the scalar twin of a numpy function;
- the innovation covariance ``S`` is factored ``S = L L'`` (Cholesky, written out: the numpy
  path inverts it by LAPACK); the gain, the Mahalanobis distance and ``log det S`` come from
  ``L``. A covariance that is not positive definite gives NaN in that trial and target, which
  the tracker repairs (keeps its prediction) as it does the numpy path's;
- the model probabilities and the moment-matched mixture are :func:`~..imm.combine`'s.

Only the order of floating-point sums differs from the numpy path: the two agree to
round-off (tested at 1e-10). Stacked measurements of
:data:`~mimo_radar_env.tracking.unscented.WOODBURY_MIN_DIMENSION` dimensions or more stay on
the numpy path (its Woodbury inverse). Importing this module needs numba (the ``fast`` extra).
"""

from __future__ import annotations

import math

import numpy as np

from ...core.compiled import CHUNK, numba, twins
from ._average_kernels import logsumexp, measurement_mean, station_geometry, symmetrize, wrap_residual

_LOG_2PI = math.log(2.0 * math.pi)
# numpy's error model, as the average fusion's kernels (a division by zero gives inf or NaN)
njit = numba.njit(cache=True, error_model="numpy")


@njit
def stacked_moments(sigmas, means, b, k, r, wm, wc, tx, rx, h, z, dz, pxz, innovation, h0, h1, sn, cs):
    """The stacked measurement of every channel (TX-major, ``2 c`` the range sum and ``2 c + 1``
    the azimuth of channel ``c``) of the sigma points ``sigmas[b, k, r]``: their mean ``z``
    (D,), residuals ``dz`` (S, D), the cross covariance ``pxz`` (n, D) and the lower triangle
    of the innovation covariance before the noise ``innovation`` (D, D)."""
    S, n = sigmas.shape[3], sigmas.shape[4]
    num_tx, num_rx = tx.shape[1], rx.shape[1]
    D = z.shape[0]
    for i in range(num_tx):
        for j in range(num_rx):
            c = i * num_rx + j
            station_geometry(
                sigmas, b, k, r, tx[b, i, 0], tx[b, i, 1], rx[b, j, 0], rx[b, j, 1], h0, h1, sn, cs
            )
            z0, z1 = measurement_mean(wm, h0, sn, cs)
            z[2 * c] = z0
            z[2 * c + 1] = z1
            for s in range(S):
                h[s, 2 * c] = h0[s]
                h[s, 2 * c + 1] = h1[s]
    for s in range(S):
        for d in range(D):
            diff = h[s, d] - z[d]
            dz[s, d] = wrap_residual(diff) if d % 2 == 1 else diff
    for q in range(n):
        for d in range(D):
            acc = 0.0
            for s in range(S):
                acc += (sigmas[b, k, r, s, q] - means[b, k, r, q]) * (dz[s, d] * wc[s])
            pxz[q, d] = acc
    for d in range(D):
        for e in range(d + 1):  # the lower triangle: all the Cholesky factorisation reads
            acc = 0.0
            for s in range(S):
                acc += (dz[s, d] * wc[s]) * dz[s, e]
            innovation[d, e] = acc


@njit
def cholesky(a):
    """The lower Cholesky factor of a symmetric positive definite ``a`` (D, D), in place (its
    lower triangle), and ``log det a``; ``-inf``... NaN where ``a`` is not positive definite."""
    D = a.shape[0]
    logdet = 0.0
    for j in range(D):
        acc = a[j, j]
        for p in range(j):
            acc -= a[j, p] * a[j, p]
        if not acc > 0.0:
            return np.nan
        root = math.sqrt(acc)
        a[j, j] = root
        logdet += 2.0 * math.log(root)
        for i in range(j + 1, D):
            acc = a[i, j]
            for p in range(j):
                acc -= a[i, p] * a[j, p]
            a[i, j] = acc / root
    return logdet


@njit
def forward(lower, x):
    """``x <- L^-1 x`` for the lower factor ``L`` in ``lower``'s lower triangle."""
    for i in range(x.shape[0]):
        acc = x[i]
        for p in range(i):
            acc -= lower[i, p] * x[p]
        x[i] = acc / lower[i, i]


@njit
def backward(lower, x):
    """``x <- L^-T x``."""
    for i in range(x.shape[0] - 1, -1, -1):
        acc = x[i]
        for p in range(i + 1, x.shape[0]):
            acc -= lower[p, i] * x[p]
        x[i] = acc / lower[i, i]


def _update(sigmas, pred_means, pred_covs, log_c, wm, wc, tx, rx, measurement, variance):
    """Returns ``(model_means, model_covs, log_probs, estimate, covariance)``.

    Shapes: sigmas (B, K, R, S, 4), pred_means (B, K, R, 4), pred_covs (B, K, R, 4, 4),
    log_c (B, K, R), tx (B, Ms, 2), rx (B, Ns, 2), measurement and variance (B, K, C, 2).
    """
    B, K, R, S, n = sigmas.shape
    C = measurement.shape[2]
    D = 2 * C
    model_means = np.empty((B, K, R, n))
    model_covs = np.empty((B, K, R, n, n))
    log_probs = np.empty((B, K, R))
    estimate = np.empty((B, K, n))
    covariance = np.empty((B, K, n, n))
    for chunk in numba.prange((B + CHUNK - 1) // CHUNK):
        # the chunk's scratch (each trial overwrites what it reads)
        h, dz = np.empty((S, D)), np.empty((S, D))
        z, residual = np.empty(D), np.empty(D)
        pxz, gain = np.empty((n, D)), np.empty((n, D))
        innovation = np.empty((D, D))
        h0, h1, sn, cs = np.empty(S), np.empty(S), np.empty(S), np.empty(S)
        for b in range(chunk * CHUNK, min(B, (chunk + 1) * CHUNK)):
            for k in range(K):
                for r in range(R):
                    stacked_moments(
                        sigmas, pred_means, b, k, r, wm, wc, tx, rx, h, z, dz, pxz, innovation, h0, h1, sn, cs
                    )
                    for c in range(C):
                        innovation[2 * c, 2 * c] += variance[b, k, c, 0]
                        innovation[2 * c + 1, 2 * c + 1] += variance[b, k, c, 1]
                        residual[2 * c] = measurement[b, k, c, 0] - z[2 * c]
                        residual[2 * c + 1] = wrap_residual(measurement[b, k, c, 1] - z[2 * c + 1])
                    logdet = cholesky(innovation)  # in place: the lower factor L, S = L L'
                    if not math.isfinite(logdet):
                        model_means[b, k, r, :] = np.nan
                        model_covs[b, k, r, :, :] = np.nan
                        log_probs[b, k, r] = np.nan
                        continue
                    # the gain P_xz S^-1 = (L^-T L^-1 P_xz')' and the whitened residual L^-1 y
                    for q in range(n):
                        for d in range(D):
                            gain[q, d] = pxz[q, d]
                        forward(innovation, gain[q])
                        backward(innovation, gain[q])
                    forward(innovation, residual)
                    mahalanobis = 0.0
                    for d in range(D):
                        mahalanobis += residual[d] * residual[d]
                    for c in range(C):  # the residual again, for the mean's update
                        residual[2 * c] = measurement[b, k, c, 0] - z[2 * c]
                        residual[2 * c + 1] = wrap_residual(measurement[b, k, c, 1] - z[2 * c + 1])
                    for q in range(n):
                        acc = 0.0
                        for d in range(D):
                            acc += gain[q, d] * residual[d]
                        model_means[b, k, r, q] = pred_means[b, k, r, q] + acc
                        for u in range(n):
                            acc = 0.0
                            for d in range(D):
                                acc += gain[q, d] * pxz[u, d]
                            model_covs[b, k, r, q, u] = pred_covs[b, k, r, q, u] - acc
                    symmetrize(model_covs[b, k, r])
                    log_probs[b, k, r] = -0.5 * (mahalanobis + logdet + D * _LOG_2PI) + log_c[b, k, r]
                if not np.isfinite(log_probs[b, k]).all():
                    log_probs[b, k, :] = np.nan
                    estimate[b, k, :] = np.nan
                    covariance[b, k, :, :] = np.nan
                    continue
                norm = logsumexp(log_probs[b, k])
                for r in range(R):
                    log_probs[b, k, r] -= norm
                # imm.combine: the moment-matched mixture of the models
                for q in range(n):
                    acc = 0.0
                    for r in range(R):
                        acc += math.exp(log_probs[b, k, r]) * model_means[b, k, r, q]
                    estimate[b, k, q] = acc
                for q in range(n):
                    for u in range(n):
                        acc = 0.0
                        for r in range(R):
                            dq = model_means[b, k, r, q] - estimate[b, k, q]
                            du = model_means[b, k, r, u] - estimate[b, k, u]
                            acc += math.exp(log_probs[b, k, r]) * (model_covs[b, k, r, q, u] + dq * du)
                        covariance[b, k, q, u] = acc
                symmetrize(covariance[b, k])
    return model_means, model_covs, log_probs, estimate, covariance


#: The kernel, serial and over threads (:func:`~mimo_radar_env.core.compiled.twins`).
update, update_threaded = twins(_update, error_model="numpy")
