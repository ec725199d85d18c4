"""The tracking search's compiled criterion (numba): :func:`posterior_values`.

Each super arm's sum of its channels' terms is what ``np.einsum("bamn,bkmnij->bkaij",
selected, terms)`` gives for 0/1 channel masks ``selected`` and finite ``terms``, number for
number: numpy's einsum adds each output's products in ``(m, n)`` order, a product with a 0
mask adds a signed zero (which changes no sum that starts at +0) and one with a 1 mask adds
the term itself, so the kernel adds the selected channels' terms in the same order and skips
the rest. From those sums it goes on to each super arm's posterior position covariance and
its trace or determinant, with the operations of the numpy path.
"""

from __future__ import annotations

import numpy as np

from ..core.compiled import CHUNK, numba, twins

if numba is not None:  # pragma: no branch
    # error_model numpy: a division by a zero determinant or count gives inf or NaN, as in numpy
    def _posterior_values(tx_masks, rx_masks, terms, prior_info, centralized, trace, out):
        """Each super arm's predicted posterior position covariance, reduced to its trace
        (``trace``) or its determinant, written into ``out`` (B, K, A): the numbers
        ``selection.super_arm_criterion``'s numpy path computes before its ``log`` and its sum
        over targets. The channel sum runs in (m, n) order from +0 (the module's docstring); then
        ``centralized``: the closed-form inverse of ``prior_info + sum`` (its entries divided by
        the determinant, as ``information.inverse_2x2``), else eq22's mean ``sum / count``."""
        batch, targets, num_tx, num_rx = terms.shape[:4]
        arms = tx_masks.shape[1]
        for chunk in numba.prange((batch + CHUNK - 1) // CHUNK):
            tx_sel = np.empty(num_tx, dtype=np.int64)
            rx_sel = np.empty(num_rx, dtype=np.int64)
            for b in range(chunk * CHUNK, min(batch, (chunk + 1) * CHUNK)):
                for a in range(arms):
                    ntx = 0
                    for m in range(num_tx):
                        if tx_masks[b, a, m]:
                            tx_sel[ntx] = m
                            ntx += 1
                    nrx = 0
                    for n in range(num_rx):
                        if rx_masks[b, a, n]:
                            rx_sel[nrx] = n
                            nrx += 1
                    count = float(ntx * nrx)
                    for k in range(targets):
                        s00 = 0.0
                        s01 = 0.0
                        s10 = 0.0
                        s11 = 0.0
                        for i in range(ntx):
                            m = tx_sel[i]
                            for j in range(nrx):
                                n = rx_sel[j]
                                s00 += terms[b, k, m, n, 0, 0]
                                s01 += terms[b, k, m, n, 0, 1]
                                s10 += terms[b, k, m, n, 1, 0]
                                s11 += terms[b, k, m, n, 1, 1]
                        if centralized:
                            a00 = prior_info[b, k, 0, 0] + s00
                            a01 = prior_info[b, k, 0, 1] + s01
                            a10 = prior_info[b, k, 1, 0] + s10
                            a11 = prior_info[b, k, 1, 1] + s11
                            det = a00 * a11 - a01 * a10
                            p00 = a11 / det
                            p01 = -a01 / det
                            p10 = -a10 / det
                            p11 = a00 / det
                        else:
                            p00 = s00 / count
                            p01 = s01 / count
                            p10 = s10 / count
                            p11 = s11 / count
                        out[b, k, a] = p00 + p11 if trace else p00 * p11 - p01 * p10

    #: The kernel, serial and over threads (:func:`~mimo_radar_env.core.compiled.twins`).
    posterior_values, posterior_values_threaded = twins(_posterior_values, error_model="numpy")
