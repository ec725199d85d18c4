"""Compiled (numba) update of the paper's average fusion, with the numpy path as fallback.

:func:`average_fusion_update` does for every trial, target, channel and model what
``unscented_update`` followed by ``average_channels`` do with numpy arrays: the
unscented update of the common prior with the channel's (range sum, azimuth), the
model probabilities of each channel, and their eq22 fusion. The arithmetic is the same;
only the order of floating-point sums differs, so the two agree to round-off (tested at
1e-10 relative). numba is optional (``pip install numba``); without it the numpy path runs.
"""

from __future__ import annotations

import math

import numpy as np

try:  # pragma: no cover - exercised when numba is installed
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    numba = None
    HAVE_NUMBA = False

_TWO_PI = 2.0 * math.pi
_LOG_2PI = math.log(2.0 * math.pi)

if HAVE_NUMBA:  # pragma: no branch

    @numba.njit(cache=True)  # serial: numba threads contend with OpenBLAS's spinning threads here
    def average_fusion_update(
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
        """Returns ``(model_means, model_covs, log_probs, estimate, covariance, finite)``.

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
