"""Super arms: selections of exactly ``Ms`` transmitters and ``Ns`` receivers.

A super arm is represented by two boolean masks, ``tx`` (B, M) and ``rx`` (B, N);
the env's action is their concatenation. Its value for a channel-weight matrix
``W`` (B, M, N) is ``sum_{m in tx, n in rx} W[m, n]`` (eq13, eq19 without the
penalty).

The exact optimum (SPEC 7): for each subset of the smaller side, the best subset
of the other side is the one with the largest row/column sums, so only
``C(M, Ms)`` (or ``C(N, Ns)``) subsets are enumerated. For layouts too large to
enumerate, :func:`local_search_super_arm` runs alternating maximisation from
deterministic starts.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.typing import NDArray

#: Largest number of subsets :func:`exact_super_arm` enumerates before refusing.
MAX_EXACT_SUBSETS = 200_000


def subset_masks(size: int, chosen: int) -> NDArray[np.bool_]:
    """All ``C(size, chosen)`` subsets as boolean masks, shape (C, size), lexicographic."""
    combos = np.array(list(itertools.combinations(range(size), chosen)), dtype=np.int64)
    masks = np.zeros((len(combos), size), dtype=bool)
    np.put_along_axis(masks, combos, True, axis=1)
    return masks


def top_mask(scores: NDArray[np.float64], count: int) -> NDArray[np.bool_]:
    """Boolean mask of the ``count`` largest entries along the last axis (ties: lowest index)."""
    order = np.argsort(-scores, axis=-1, kind="stable")[..., :count]
    mask = np.zeros(scores.shape, dtype=bool)
    np.put_along_axis(mask, order, True, axis=-1)
    return mask


def super_arm_value(
    weights: NDArray[np.float64], tx: NDArray[np.bool_], rx: NDArray[np.bool_]
) -> NDArray[np.float64]:
    """``sum_{m in tx, n in rx} weights[..., m, n]``; shapes (..., M, N), (..., M), (..., N)."""
    return np.einsum("...m,...mn,...n->...", tx.astype(weights.dtype), weights, rx.astype(weights.dtype))


def exact_super_arm(
    weights: NDArray[np.float64], tx_count: int, rx_count: int
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.float64]]:
    """The optimal super arm for each weight matrix in the batch.

    Parameters
    ----------
    weights : array (B, M, N)
    tx_count, rx_count : int
        ``Ms`` and ``Ns``.

    Returns
    -------
    tx, rx : bool arrays (B, M), (B, N)
    value : array (B,)
    """
    weights = np.asarray(weights, dtype=np.float64)
    num_tx, num_rx = weights.shape[-2:]
    if math.comb(num_rx, rx_count) < math.comb(num_tx, tx_count):
        rx, tx, value = exact_super_arm(np.swapaxes(weights, -1, -2), rx_count, tx_count)
        return tx, rx, value
    num_subsets = math.comb(num_tx, tx_count)
    if num_subsets > MAX_EXACT_SUBSETS:
        raise ValueError(
            f"exact super-arm search would enumerate {num_subsets} subsets (> {MAX_EXACT_SUBSETS}) for "
            f"M={num_tx}, N={num_rx}, Ms={tx_count}, Ns={rx_count}; use the local-search solver instead"
        )
    tx_subsets = subset_masks(num_tx, tx_count)  # (S, M)
    column_sums = np.einsum("sm,bmn->bsn", tx_subsets.astype(np.float64), weights)  # (B, S, N)
    # the best Ns columns for each TX subset: their sum is the subset's value
    top = -np.partition(-column_sums, rx_count - 1, axis=-1)[..., :rx_count]
    subset_value = top.sum(axis=-1)  # (B, S)
    best = np.argmax(subset_value, axis=-1)
    batch = np.arange(weights.shape[0])
    tx = tx_subsets[best]
    rx = top_mask(column_sums[batch, best], rx_count)
    return tx, rx, subset_value[batch, best]


def local_search_super_arm(
    weights: NDArray[np.float64], tx_count: int, rx_count: int, max_rounds: int = 50
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.float64]]:
    """Alternating maximisation from ``M + 2`` deterministic starts, best kept.

    Starts: the top-``Ms`` rows by row sum, by row maximum, and, for each receiver
    ``n``, the top-``Ms`` rows of column ``n``. Each round picks the best
    receivers for the current transmitters, then the best transmitters for those
    receivers; the value never decreases, and a round that changes nothing ends
    the search. The result is a local optimum (a lower bound on the optimum).
    """
    weights = np.asarray(weights, dtype=np.float64)
    starts = np.concatenate(
        [
            weights.sum(axis=-1)[:, None, :],
            weights.max(axis=-1)[:, None, :],
            np.swapaxes(weights, -1, -2),
        ],
        axis=1,
    )  # (B, S, M) scores to start from
    tx = top_mask(starts, tx_count)  # (B, S, M)
    for _ in range(max_rounds):
        rx = top_mask(np.einsum("bsm,bmn->bsn", tx.astype(np.float64), weights), rx_count)
        new_tx = top_mask(np.einsum("bmn,bsn->bsm", weights, rx.astype(np.float64)), tx_count)
        if np.array_equal(new_tx, tx):
            break
        tx = new_tx
    value = super_arm_value(weights[:, None], tx, rx)  # (B, S)
    best = np.argmax(value, axis=-1)
    batch = np.arange(weights.shape[0])
    return tx[batch, best], rx[batch, best], value[batch, best]


def best_super_arm(
    weights: NDArray[np.float64], tx_count: int, rx_count: int
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.float64]]:
    """Exact optimum where enumeration is affordable, local search beyond."""
    num_tx, num_rx = weights.shape[-2:]
    if min(math.comb(num_tx, tx_count), math.comb(num_rx, rx_count)) <= MAX_EXACT_SUBSETS:
        return exact_super_arm(weights, tx_count, rx_count)
    return local_search_super_arm(weights, tx_count, rx_count)


def is_exact_affordable(num_tx: int, num_rx: int, tx_count: int, rx_count: int) -> bool:
    """True when :func:`exact_super_arm` can run for this layout."""
    return min(math.comb(num_tx, tx_count), math.comb(num_rx, rx_count)) <= MAX_EXACT_SUBSETS
