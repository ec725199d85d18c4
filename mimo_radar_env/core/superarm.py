"""Super arms: selections of exactly ``Ms`` transmitters and ``Ns`` receivers.

A super arm is represented by two boolean masks, ``tx`` (B, M) and ``rx`` (B, N);
the env's action is their concatenation. Its value for a channel-weight matrix
``W`` (B, M, N) is ``sum_{m in tx, n in rx} W[m, n]`` (eq13, eq19 without the
penalty).

The exact optimum (docs/model.md): for each subset of the smaller side, the best subset
of the other side is the one with the largest row/column sums, so only
``C(M, Ms)`` (or ``C(N, Ns)``) subsets are enumerated. For layouts too large to
enumerate, :func:`alternating_super_arm` runs alternating maximisation from
deterministic starts.
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np
from numpy.typing import NDArray

from .arrays import namespace

#: Largest number of subsets :func:`exact_super_arm` enumerates before refusing.
MAX_EXACT_SUBSETS = 200_000
#: Largest number of subsets :func:`best_super_arm` enumerates; beyond, alternating maximisation is used
#: (32 x 32 with Ms = 4, 35,960 subsets, already costs about a second per step at B = 20).
AUTO_EXACT_SUBSETS = 20_000


def subset_masks(size: int, chosen: int) -> NDArray[np.bool_]:
    """All ``C(size, chosen)`` subsets as boolean masks, shape (C, size), lexicographic."""
    combos = np.array(list(itertools.combinations(range(size), chosen)), dtype=np.int64)
    masks = np.zeros((len(combos), size), dtype=bool)
    np.put_along_axis(masks, combos, True, axis=1)
    return masks


@functools.cache
def subset_rows(size: int, chosen: int) -> tuple[tuple[int, ...], ...]:
    """:func:`subset_masks` as nested tuples of 0 and 1, made once: what ``xp.constant`` keeps on
    a device, so that a step copies no table from the host."""
    return tuple(tuple(int(bit) for bit in row) for row in subset_masks(size, chosen))


def masks_to_actions(tx: NDArray[np.bool_], rx: NDArray[np.bool_]) -> NDArray[np.int8]:
    """The env's actions (..., M + N) int8 of transmitter and receiver masks (..., M), (..., N)."""
    xp = namespace(tx)
    return xp.astype(xp.concatenate([tx, rx], axis=-1), np.int8)


def super_arm_count(num_tx: int, num_rx: int, tx_count: int, rx_count: int) -> int:
    """``C(M, Ms) C(N, Ns)``: the number of super arms."""
    return math.comb(num_tx, tx_count) * math.comb(num_rx, rx_count)


@functools.lru_cache(maxsize=16)
def all_super_arms(
    num_tx: int, num_rx: int, tx_count: int, rx_count: int
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Every super arm as masks (A, M), (A, N): super arm ``i`` is the ``i // C(N, Ns)``-th
    transmitter subset with the ``i % C(N, Ns)``-th receiver subset (both lexicographic).
    Cached and read-only: policies that score every super arm call it every step."""
    tx, rx = subset_masks(num_tx, tx_count), subset_masks(num_rx, rx_count)
    masks = np.repeat(tx, len(rx), axis=0), np.tile(rx, (len(tx), 1))
    for mask in masks:
        mask.flags.writeable = False
    return masks


def top_mask(scores: NDArray[np.float64], count: int) -> NDArray[np.bool_]:
    """Boolean mask of the ``count`` largest entries along the last axis (ties: lowest index)."""
    xp = namespace(scores)
    order = xp.argsort(-scores, axis=-1, kind="stable")[..., :count]
    mask = xp.zeros(scores.shape, dtype=bool)
    xp.put_along_axis(mask, order, True, axis=-1)
    return mask


def random_super_arms(
    rng: np.random.Generator, count: int, num_tx: int, num_rx: int, tx_count: int, rx_count: int
) -> NDArray[np.int8]:
    """``count`` uniformly random valid super arms as actions (count, M + N)."""
    tx = np.argsort(rng.random((count, num_tx)), axis=1)[:, :tx_count]
    rx = np.argsort(rng.random((count, num_rx)), axis=1)[:, :rx_count]
    action = np.zeros((count, num_tx + num_rx), dtype=np.int8)
    np.put_along_axis(action, tx, 1, axis=1)
    np.put_along_axis(action, num_tx + rx, 1, axis=1)
    return action


def super_arm_value(
    weights: NDArray[np.float64], tx: NDArray[np.bool_], rx: NDArray[np.bool_]
) -> NDArray[np.float64]:
    """``sum_{m in tx, n in rx} weights[..., m, n]``; shapes (..., M, N), (..., M), (..., N)."""
    xp = namespace(weights)
    return xp.einsum(
        "...m,...mn,...n->...", xp.astype(tx, weights.dtype), weights, xp.astype(rx, weights.dtype)
    )


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
    xp = namespace(weights)
    weights = xp.asarray(weights, dtype=np.float64)
    num_tx, num_rx = weights.shape[-2:]
    if math.comb(num_rx, rx_count) < math.comb(num_tx, tx_count):
        rx, tx, value = exact_super_arm(xp.swapaxes(weights, -1, -2), rx_count, tx_count)
        return tx, rx, value
    num_subsets = math.comb(num_tx, tx_count)
    if num_subsets > MAX_EXACT_SUBSETS:
        raise ValueError(
            f"exact super-arm search would enumerate {num_subsets} subsets (> {MAX_EXACT_SUBSETS}) for "
            f"M={num_tx}, N={num_rx}, Ms={tx_count}, Ns={rx_count}; use the alternating solver instead"
        )
    tx_subsets = xp.constant(subset_rows(num_tx, tx_count))  # (S, M) of 0 and 1
    batch_size = weights.shape[0]
    # one BLAS product for the whole batch: (S, M) @ (M, B * N)
    flat = xp.ascontiguousarray(xp.moveaxis(weights, 1, 0)).reshape(num_tx, batch_size * num_rx)
    column_sums = (xp.astype(tx_subsets, np.float64) @ flat).reshape(-1, batch_size, num_rx)  # (S, B, N)
    # the best Ns columns for each TX subset: their sum is the subset's value
    top = xp.sort(column_sums, axis=-1)[..., num_rx - rx_count :]  # sort beats partition on short rows
    subset_value = top.sum(axis=-1).T  # (B, S)
    best = xp.argmax(subset_value, axis=-1)
    batch = xp.arange(batch_size)
    tx = xp.astype(tx_subsets[best], bool)
    rx = top_mask(column_sums[best, batch], rx_count)
    return tx, rx, subset_value[batch, best]


def alternating_super_arm(
    weights: NDArray[np.float64],
    tx_count: int,
    rx_count: int,
    max_rounds: int = 50,
    extra_starts: NDArray[np.bool_] | None = None,
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.float64]]:
    """Alternating maximisation from ``N + 2`` deterministic starts (and any extra ones), best kept.

    Deterministic starts: the top-``Ms`` rows by row sum, by row maximum, and, for each
    receiver ``n``, the top-``Ms`` rows of column ``n``. ``extra_starts`` (B, S', M) adds
    transmitter subsets to start from (the agents' solver adds random ones). Each round picks
    the best receivers for the current transmitters, then the best transmitters for those
    receivers; the value never decreases, and a round that changes nothing ends the search.
    The result is a local optimum (a lower bound on the optimum); on ties the earliest start
    wins, deterministic ones first.
    """
    weights = np.asarray(weights, dtype=np.float64)
    scores = np.concatenate(
        [
            weights.sum(axis=-1)[:, None, :],
            weights.max(axis=-1)[:, None, :],
            np.swapaxes(weights, -1, -2),
        ],
        axis=1,
    )  # (B, N + 2, M) scores to start from
    tx = top_mask(scores, tx_count)  # (B, S, M)
    if extra_starts is not None:
        tx = np.concatenate([tx, extra_starts], axis=1)
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


#: How the env finds the optimal super arm (its ``oracle_solver`` option): ``"auto"`` is exact
#: up to ``AUTO_EXACT_SUBSETS`` subsets on the smaller side, alternating maximisation beyond.
SUPER_ARM_METHODS = ("auto", "exact", "alternating")


def best_super_arm(
    weights: NDArray[np.float64], tx_count: int, rx_count: int, method: str = "auto"
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.float64]]:
    """The optimal super arm by ``method``, one of :data:`SUPER_ARM_METHODS`."""
    num_tx, num_rx = weights.shape[-2:]
    method = resolve_method(num_tx, num_rx, tx_count, rx_count, method)
    if method == "exact":
        return exact_super_arm(weights, tx_count, rx_count)
    if method == "alternating":
        return alternating_super_arm(weights, tx_count, rx_count)
    raise ValueError(f"method must be one of {SUPER_ARM_METHODS}, got {method!r}")


def resolve_method(num_tx: int, num_rx: int, tx_count: int, rx_count: int, method: str) -> str:
    """``method``, with ``"auto"`` resolved: exact up to ``AUTO_EXACT_SUBSETS`` subsets on the
    smaller side, alternating beyond."""
    if method != "auto":
        return method
    affordable = is_exact_affordable(num_tx, num_rx, tx_count, rx_count, AUTO_EXACT_SUBSETS)
    return "exact" if affordable else "alternating"


def exact_operations(num_tx: int, num_rx: int, tx_count: int, rx_count: int) -> float:
    """Arithmetic operations of :func:`exact_super_arm` per trial, roughly: for each subset of
    the smaller side, its sums over the other side and their top-k."""
    tx_subsets, rx_subsets = math.comb(num_tx, tx_count), math.comb(num_rx, rx_count)
    if tx_subsets <= rx_subsets:
        return 4.0 * tx_subsets * (tx_count + 2) * num_rx
    return 4.0 * rx_subsets * (rx_count + 2) * num_tx


def alternating_operations(num_tx: int, num_rx: int, starts: int, rounds: int = 2) -> float:
    """Arithmetic operations of :func:`alternating_super_arm` per trial, roughly: each of the
    ``N + 2 + starts`` starts' ``rounds`` alternations (a few until nothing changes, typically)
    of row and column sums."""
    return 2.0 * (num_rx + 2 + starts) * rounds * num_tx * num_rx


#: Seconds per declared operation of each search method on the developers' machine: the exact
#: search's large vectorised sums run several times faster per operation than the alternating
#: search's rounds of small arrays (fitted to ``benchmarks.speed.policy_cost``'s measurements).
SEARCH_SECONDS_PER_OPERATION = {"exact": 3.6e-10, "alternating": 1.3e-9}


def search_seconds(num_tx: int, num_rx: int, tx_count: int, rx_count: int, method: str = "auto") -> float:
    """One trial's time of :func:`best_super_arm` by ``method`` on the developers' machine,
    roughly: :func:`search_operations` at the method's :data:`SEARCH_SECONDS_PER_OPERATION`."""
    resolved = resolve_method(num_tx, num_rx, tx_count, rx_count, method)
    return (
        search_operations(num_tx, num_rx, tx_count, rx_count, resolved)
        * SEARCH_SECONDS_PER_OPERATION[resolved]
    )


def search_operations(num_tx: int, num_rx: int, tx_count: int, rx_count: int, method: str = "auto") -> float:
    """Arithmetic operations of :func:`best_super_arm` by ``method`` per trial, roughly."""
    if resolve_method(num_tx, num_rx, tx_count, rx_count, method) == "exact":
        return exact_operations(num_tx, num_rx, tx_count, rx_count)
    return alternating_operations(num_tx, num_rx, starts=0)


def is_exact_affordable(
    num_tx: int, num_rx: int, tx_count: int, rx_count: int, limit: int = MAX_EXACT_SUBSETS
) -> bool:
    """True when the smaller side has at most ``limit`` subsets to enumerate."""
    return min(math.comb(num_tx, tx_count), math.comb(num_rx, rx_count)) <= limit
