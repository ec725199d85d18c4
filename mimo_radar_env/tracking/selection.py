"""Selecting for tracking: the predicted posterior position error of a super arm, and the
searches for the super arm that minimises it (docs/model.md, section 14).

For target k with the tracker's one-step prediction (mean ``x_bar``, covariance ``P_bar``),
each channel's measurement Jacobian ``H_mn`` at ``x_bar`` (eq6; it involves the position only)
and measurement covariance ``R_mn = Sigma0 / lambda_mn`` (eq32), the posterior information of
super arm ``A`` is ``J_A = P_bar^-1 + sum_{(m, n) in A} H_mn' R_mn^-1 H_mn``. Because the
measurements see the position only, the position block of ``J_A^-1`` is
``(S^-1 + I_A)^-1`` with ``S`` the predicted position covariance (the 2 x 2 block of
``P_bar``) and ``I_A`` the channels' position information: every super arm costs one 2 x 2
inverse. The criterion is ``sum_k Omega_k trace`` of that block (the predicted posterior
position MSE, m^2), or ``sum_k Omega_k log det`` of it; smaller is better.

That is the posterior of centralised fusion, which adds the channels' information. The
paper's eq22 fusion (``"average"``) averages the channels' single-channel posteriors instead,
so under it the predicted position covariance of a super arm is the mean over its channels of
``(S^-1 + I_mn)^-1`` (the spread of the channels' means left out); ``fusion="average"`` scores
that.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ..core.superarm import all_super_arms, super_arm_count
from .fusion import FUSIONS
from .information import det_2x2, inverse_2x2

CRITERIA: tuple[str, ...] = ("trace", "logdet")
#: Super arms :func:`select_for_tracking` enumerates at most (exact search); greedy beyond.
MAX_ENUMERATED_SUPER_ARMS = 5_000


def _centralized_posterior(prior_info: NDArray, information: NDArray, selected: NDArray) -> NDArray:
    """The channels' information adds: ``(S^-1 + sum_A I_mn)^-1``, (B, K, A, 2, 2)."""
    gained = np.einsum("bamn,bkmnij->bkaij", selected, information)
    return inverse_2x2(prior_info[:, :, None] + gained)[0]


def _average_posterior(prior_info: NDArray, information: NDArray, selected: NDArray) -> NDArray:
    """eq22: the mean over the super arm's channels of ``(S^-1 + I_mn)^-1``, (B, K, A, 2, 2)."""
    single, _ = inverse_2x2(prior_info[:, :, None, None] + information)  # (B, K, M, N, 2, 2)
    channels = selected.sum(axis=(2, 3))  # (B, A)
    return np.einsum("bamn,bkmnij->bkaij", selected, single) / channels[:, None, :, None, None]


#: The predicted posterior position covariance of a super arm under each fusion of the registry.
POSTERIORS: dict[str, Callable[[NDArray, NDArray, NDArray], NDArray]] = {
    "centralized": _centralized_posterior,
    "average": _average_posterior,
}
if set(POSTERIORS) != set(FUSIONS):  # a new fusion must say what it does to the posterior
    raise ImportError(
        f"selection knows the posteriors of {sorted(POSTERIORS)}, the fusions are {sorted(FUSIONS)}"
    )


def super_arm_criterion(
    position_cov: NDArray[np.float64],
    information: NDArray[np.float64],
    tx_masks: NDArray[np.bool_],
    rx_masks: NDArray[np.bool_],
    weights: NDArray[np.float64],
    criterion: str = "trace",
    fusion: str = "centralized",
) -> NDArray[np.float64]:
    """The criterion of every super arm in every trial: (B, A).

    ``position_cov`` (B, K, 2, 2) the predicted position covariance; ``information``
    (B, K, M, N, 2, 2) from :func:`channel_information`; ``tx_masks`` (A, M) and ``rx_masks``
    (A, N) the super arms, or (B, A, M), (B, A, N) for per-trial ones (partial selections
    allowed); ``weights`` (K,) ``Omega``; ``fusion`` a fusion of the registry
    (:data:`POSTERIORS`: ``"centralized"``, the channels' information adds, or ``"average"``,
    eq22, their posteriors are averaged).
    """
    if criterion not in CRITERIA:
        raise ValueError(f"criterion must be one of {list(CRITERIA)}, got {criterion!r}")
    if fusion not in POSTERIORS:
        raise ValueError(f"fusion must be one of {list(FUSIONS)}, got {fusion!r}")
    prior_info, _ = inverse_2x2(position_cov)  # (B, K, 2, 2)
    selected = tx_masks[..., :, None].astype(float) * rx_masks[..., None, :]  # ([B,] A, M, N)
    if selected.ndim == 3:
        selected = np.broadcast_to(selected, (position_cov.shape[0], *selected.shape))
    posterior = POSTERIORS[fusion](prior_info, information, selected)  # (B, K, A, 2, 2)
    if criterion == "trace":
        per_target = posterior[..., 0, 0] + posterior[..., 1, 1]
    else:
        per_target = np.log(det_2x2(posterior))
    return np.einsum("k,bka->ba", np.asarray(weights, dtype=np.float64), per_target)


def select_for_tracking(
    position_cov: NDArray[np.float64],
    information: NDArray[np.float64],
    weights: NDArray[np.float64],
    tx_count: int,
    rx_count: int,
    criterion: str = "trace",
    fusion: str = "centralized",
    sinr_index: NDArray[np.float64] | None = None,
    sinr_weight: float = 0.0,
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """The super arm of each trial with the smallest criterion: masks (B, M), (B, N).

    Exact over all super arms up to :data:`MAX_ENUMERATED_SUPER_ARMS`, greedy plus swap
    search (:func:`greedy_super_arm`) beyond. With ``sinr_weight`` ``w`` in (0, 1] and a
    fused SINR index ``sinr_index`` (B, M, N), it minimises the scalarised score
    ``(1 - w) c(A) - w s(A)`` instead, where ``c`` is the criterion and ``s`` the super arm's
    index sum ``sum_{(m, n) in A} I[m, n]``, each rescaled to [0, 1] by its range over the
    trial's super arms (``w = 1``: the index maximiser; exact enumeration only).
    """
    num_tx, num_rx = information.shape[2:4]
    if super_arm_count(num_tx, num_rx, tx_count, rx_count) > MAX_ENUMERATED_SUPER_ARMS:
        if sinr_weight > 0:
            raise ValueError(
                f"sinr_weight > 0 scores every super arm, so it needs at most {MAX_ENUMERATED_SUPER_ARMS:,} "
                f"of them; this layout has {super_arm_count(num_tx, num_rx, tx_count, rx_count):,}"
            )
        return greedy_super_arm(position_cov, information, weights, tx_count, rx_count, criterion, fusion)
    tx_masks, rx_masks = all_super_arms(num_tx, num_rx, tx_count, rx_count)
    scores = super_arm_criterion(position_cov, information, tx_masks, rx_masks, weights, criterion, fusion)
    if sinr_weight > 0:
        if sinr_index is None:
            raise ValueError("sinr_weight > 0 needs the SINR index of the channels (sinr_index)")
        value = np.einsum("am,bmn,an->ba", tx_masks.astype(float), sinr_index, rx_masks.astype(float))
        scores = (1.0 - sinr_weight) * _unit_range(scores) - sinr_weight * _unit_range(value)
    best = np.argmin(scores, axis=1)
    return tx_masks[best], rx_masks[best]


def _unit_range(scores: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each row rescaled to [0, 1] by its range (a constant row becomes 0)."""
    low = scores.min(axis=1, keepdims=True)
    span = scores.max(axis=1, keepdims=True) - low
    return np.divide(scores - low, span, out=np.zeros_like(scores), where=span > 0)


def greedy_super_arm(
    position_cov: NDArray[np.float64],
    information: NDArray[np.float64],
    weights: NDArray[np.float64],
    tx_count: int,
    rx_count: int,
    criterion: str = "trace",
    fusion: str = "centralized",
    starts: int = 8,
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """A good super arm without enumerating them all, per trial: (B, M), (B, N) masks.

    From each of the ``starts`` best single channels it adds, one station at a time, the transmitter
    or receiver whose addition gives the lowest criterion, until ``tx_count`` and
    ``rx_count`` are reached (``Ms + Ns - 2`` batched evaluations of ``M + N`` candidates);
    then swaps one selected station for an unselected one of the same kind while a swap
    lowers the criterion, and keeps the best of the starts. Not always optimal: tests measure
    how often it finds the exact optimum.
    """
    batch = position_cov.shape[0]
    num_tx, num_rx = information.shape[2:4]
    starts = min(starts, num_tx * num_rx)
    one_tx = np.repeat(np.eye(num_tx, dtype=bool), num_rx, axis=0)  # (M*N, M)
    one_rx = np.tile(np.eye(num_rx, dtype=bool), (num_tx, 1))
    single = super_arm_criterion(position_cov, information, one_tx, one_rx, weights, criterion, fusion)
    first = np.argsort(single, axis=1)[:, :starts].reshape(-1)  # (B * starts,), trial-major
    # every start is a trial of its own from here on
    position_cov = np.repeat(position_cov, starts, axis=0)
    information = np.repeat(information, starts, axis=0)
    tx, rx = one_tx[first], one_rx[first]  # (B * starts, M), (B * starts, N)
    rows = np.arange(batch * starts)
    eye_tx, eye_rx = np.eye(num_tx, dtype=bool)[None], np.eye(num_rx, dtype=bool)[None]
    for _ in range(tx_count + rx_count - 2):
        # every trial adds one station: a transmitter while it has fewer than tx_count, or a receiver
        cand_tx = np.concatenate([tx[:, None] | eye_tx, np.repeat(tx[:, None], num_rx, axis=1)], axis=1)
        cand_rx = np.concatenate([np.repeat(rx[:, None], num_tx, axis=1), rx[:, None] | eye_rx], axis=1)
        scores = super_arm_criterion(position_cov, information, cand_tx, cand_rx, weights, criterion, fusion)
        new_tx, new_rx = cand_tx.sum(2) > tx.sum(1)[:, None], cand_rx.sum(2) > rx.sum(1)[:, None]
        allowed = (new_tx & (tx.sum(1) < tx_count)[:, None]) | (new_rx & (rx.sum(1) < rx_count)[:, None])
        choice = np.argmin(np.where(allowed, scores, np.inf), axis=1)
        tx, rx = cand_tx[rows, choice], cand_rx[rows, choice]
    tx, rx = _swap_search(position_cov, information, weights, tx, rx, criterion, fusion)
    final = super_arm_criterion(
        position_cov, information, tx[:, None], rx[:, None], weights, criterion, fusion
    )
    best = np.argmin(final[:, 0].reshape(batch, starts), axis=1) + np.arange(batch) * starts
    return tx[best], rx[best]


def _swap_search(
    position_cov: NDArray[np.float64],
    information: NDArray[np.float64],
    weights: NDArray[np.float64],
    tx: NDArray[np.bool_],
    rx: NDArray[np.bool_],
    criterion: str,
    fusion: str,
    max_rounds: int = 50,
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Local search: while some swap of one selected station for an unselected one of the same
    kind lowers a trial's criterion, make the best such swap (all trials at once)."""
    batch, num_tx, num_rx = tx.shape[0], tx.shape[1], rx.shape[1]
    rows = np.arange(batch)
    current = super_arm_criterion(
        position_cov, information, tx[:, None], rx[:, None], weights, criterion, fusion
    )[:, 0]

    def swaps(mask: NDArray[np.bool_]) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        size = mask.shape[1]
        eye = np.eye(size, dtype=bool)
        out_in = (mask[:, None, None, :] & ~eye[None, :, None, :]) | eye[None, None, :, :]  # (B, out, in, S)
        allowed = mask[:, :, None] & ~mask[:, None, :]  # (B, out, in)
        return out_in.reshape(batch, size * size, size), allowed.reshape(batch, size * size)

    for _ in range(max_rounds):
        swap_tx, ok_tx = swaps(tx)
        swap_rx, ok_rx = swaps(rx)
        cand_tx = np.concatenate([swap_tx, np.repeat(tx[:, None], num_rx * num_rx, axis=1)], axis=1)
        cand_rx = np.concatenate([np.repeat(rx[:, None], num_tx * num_tx, axis=1), swap_rx], axis=1)
        scores = super_arm_criterion(position_cov, information, cand_tx, cand_rx, weights, criterion, fusion)
        scores = np.where(np.concatenate([ok_tx, ok_rx], axis=1), scores, np.inf)
        choice = np.argmin(scores, axis=1)
        better = scores[rows, choice] < current - 1e-12 * np.abs(current)
        if not better.any():
            break
        tx = np.where(better[:, None], cand_tx[rows, choice], tx)
        rx = np.where(better[:, None], cand_rx[rows, choice], rx)
        current = np.where(better, scores[rows, choice], current)
    return tx, rx
