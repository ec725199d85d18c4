"""The compiled sum over a super arm's channels of the tracking search (numba).

:func:`selected_sums` gives, number for number, what ``np.einsum("bamn,bkmnij->bkaij",
selected, terms)`` gives for 0/1 channel masks ``selected`` and finite ``terms``: numpy's
einsum adds each output's products in ``(m, n)`` order, a product with a 0 mask adds a
signed zero (which changes no sum that starts at +0) and one with a 1 mask adds the term
itself, so the kernel adds the selected channels' terms in the same order and skips the rest.
"""

from __future__ import annotations

from ..core.compiled import numba

if numba is not None:  # pragma: no branch

    @numba.njit(cache=True)
    def selected_sums(tx_masks, rx_masks, terms, out):
        """``out[b, k, a] = sum over (m, n) with tx_masks[b, a, m] and rx_masks[b, a, n] of
        terms[b, k, m, n]`` (2 x 2 blocks), in (m, n) order; ``out`` zeros (B, K, A, 2, 2)."""
        batch, targets, num_tx, num_rx = terms.shape[:4]
        arms = tx_masks.shape[1]
        for b in range(batch):
            for a in range(arms):
                for m in range(num_tx):
                    if tx_masks[b, a, m]:
                        for n in range(num_rx):
                            if rx_masks[b, a, n]:
                                for k in range(targets):
                                    for i in range(2):
                                        for j in range(2):
                                            out[b, k, a, i, j] += terms[b, k, m, n, i, j]
