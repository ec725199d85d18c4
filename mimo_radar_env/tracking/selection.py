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

That is the posterior of centralised fusion, which adds the channels' information. Each
fusion says what its posterior is (:meth:`~.fusion.Fusion.channel_terms` and
:meth:`~.fusion.Fusion.posterior_from_sum`): the paper's eq22 fusion averages the channels'
single-channel posteriors instead, the mean over its channels of ``(S^-1 + I_mn)^-1``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..core.arrays import namespace
from ..core.compiled import HAVE_NUMBA, LazyKernels
from ..core.superarm import all_super_arms, super_arm_count
from .fusion import Fusion, fusion_class
from .information import det_2x2, inverse_2x2

CRITERIA: tuple[str, ...] = ("trace", "logdet")
#: Super arms :func:`select_for_tracking` enumerates at most (exact search); greedy beyond.
MAX_ENUMERATED_SUPER_ARMS = 5_000


#: The most bytes of swap candidates :func:`greedy_super_arm` builds at once (a block of
#: trials), below glibc's largest threshold for serving an allocation from fresh pages (32 MiB).
GREEDY_BLOCK_BYTES = 8 * 2**20


def selection_memory_per_trial(
    num_tx: int, num_rx: int, num_targets: int, tx_count: int, rx_count: int, starts: int = 8
) -> int:
    """Bytes :func:`select_for_tracking` needs per trial at its peak, roughly (an upper estimate):
    every super arm's channel mask and posterior when it enumerates, the starts' row and column
    sums and swap candidates when it searches greedily."""
    count = super_arm_count(num_tx, num_rx, tx_count, rx_count)
    channels = 8 * 4 * num_targets * num_tx * num_rx * 3  # information, single posteriors, scratch
    if count <= MAX_ENUMERATED_SUPER_ARMS:
        return channels + 8 * count * (num_tx * num_rx + 3 * 4 * num_targets)
    return channels * (starts + 1) + 4 * _swap_bytes(num_tx, num_rx, num_targets, starts)


def _swap_bytes(num_tx: int, num_rx: int, num_targets: int, starts: int) -> int:
    """One trial's swap candidates and station sums in the greedy search, one copy: every start's
    (K, 2, 2) sum for each swap and each station (float64)."""
    return starts * 8 * 4 * num_targets * (num_tx**2 + num_rx**2 + num_tx + num_rx)


def selection_operations_per_trial(
    num_tx: int, num_rx: int, num_targets: int, tx_count: int, rx_count: int, starts: int = 8
) -> float:
    """Arithmetic operations of :func:`select_for_tracking` per trial, roughly (an upper
    estimate): the channels' information, then every super arm's posterior when it
    enumerates, or each start's greedy additions and swaps (each scoring every candidate
    station through row and column sums, then choosing among every swap) when it searches
    greedily."""
    count = super_arm_count(num_tx, num_rx, tx_count, rx_count)
    channels = 60.0 * num_targets * num_tx * num_rx
    if count <= MAX_ENUMERATED_SUPER_ARMS:
        return channels + count * num_targets * (8.0 * num_tx * num_rx + 60)
    candidates = (tx_count + rx_count) * (num_tx + num_rx)
    swaps = starts * (num_tx**2 + num_rx**2) * 60.0  # each start's swap masks and minimum, any K
    return channels * (starts + 1) + starts * num_targets * 3 * candidates * 200.0 + swaps


def super_arm_criterion(
    position_cov: NDArray[np.float64],
    information: NDArray[np.float64],
    tx_masks: NDArray[np.bool_],
    rx_masks: NDArray[np.bool_],
    weights: NDArray[np.float64],
    criterion: str = "trace",
    fusion: str = "centralized",
    use_numba: bool = True,
) -> NDArray[np.float64]:
    """The criterion of every super arm in every trial: (B, A).

    ``position_cov`` (B, K, 2, 2) the predicted position covariance; ``information``
    (B, K, M, N, 2, 2) from :func:`channel_information`; ``tx_masks`` (A, M) and ``rx_masks``
    (A, N) the super arms, or (B, A, M), (B, A, N) for per-trial ones (partial selections
    allowed); ``weights`` (K,) ``Omega``; ``fusion`` a name of the fusion registry
    (:data:`~.fusion.FUSIONS`), whose posterior is scored; ``use_numba`` the compiled path, when
    numba is installed, the fusion has one and the channels' terms are finite: each super arm's
    sum over its channels (in
    the numpy path's einsum order), its posterior and that posterior's trace or determinant
    in one pass (:mod:`._selection_kernels`), with the same numbers (a 0 mask times an
    infinite term is NaN in the einsum, so infinite terms take the numpy path).
    """
    posterior = _check_choices(criterion, fusion)
    xp = namespace(position_cov)
    tx_masks, rx_masks = xp.asarray(tx_masks), xp.asarray(rx_masks)
    prior_info, _ = inverse_2x2(position_cov)  # (B, K, 2, 2)
    batch = position_cov.shape[0]
    if tx_masks.ndim == 2:
        tx_masks = xp.broadcast_to(tx_masks, (batch, *tx_masks.shape))
        rx_masks = xp.broadcast_to(rx_masks, (batch, *rx_masks.shape))
    terms = posterior.channel_terms(prior_info, information)
    compiled = posterior.compiled_posterior
    numba_path = use_numba and HAVE_NUMBA and compiled is not None and not xp.is_torch
    if numba_path and np.isfinite(terms).all():
        # the channel sums, the posteriors and their traces or determinants in one pass: the same
        # numbers as the numpy path below, without its (B, K, A, 2, 2) intermediates
        values = np.empty((batch, terms.shape[1], tx_masks.shape[1]))
        _KERNELS.for_batch("_compiled_posteriors", batch)(
            tx_masks,
            rx_masks,
            np.ascontiguousarray(terms, dtype=np.float64),
            np.ascontiguousarray(prior_info),
            compiled == "information",
            criterion == "trace",
            values,
        )
        per_target = values if criterion == "trace" else np.log(values)
    else:
        selected = xp.astype(tx_masks[..., :, None], np.float64) * rx_masks[..., None, :]  # (B, A, M, N)
        total = xp.einsum("bamn,bkmnij->bkaij", selected, terms)
        count = xp.astype(tx_masks.sum(axis=-1) * rx_masks.sum(axis=-1), np.float64)[:, None, :, None, None]
        covariance = posterior.posterior_from_sum(prior_info[:, :, None], total, count)  # (B, K, A, 2, 2)
        per_target = _per_target(covariance, criterion)
    return xp.einsum("k,bka->ba", xp.asarray(weights, dtype=np.float64), per_target)


def _check_choices(criterion: str, fusion: str) -> type[Fusion]:
    """The fusion class of ``fusion``, after checking both choices."""
    if criterion not in CRITERIA:
        raise ValueError(f"criterion must be one of {list(CRITERIA)}, got {criterion!r}")
    return fusion_class(fusion)


def _per_target(posterior: NDArray[np.float64], criterion: str) -> NDArray[np.float64]:
    """The criterion of each target's posterior position covariance (..., 2, 2): trace or log det."""
    if criterion == "trace":
        return posterior[..., 0, 0] + posterior[..., 1, 1]
    return namespace(posterior).log(det_2x2(posterior))


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
        if namespace(position_cov).is_torch:
            raise NotImplementedError(
                f"the greedy tracking search (layouts of more than {MAX_ENUMERATED_SUPER_ARMS:,} super "
                "arms) runs on numpy only: make the env with device=None"
            )
        return greedy_super_arm(position_cov, information, weights, tx_count, rx_count, criterion, fusion)
    xp = namespace(position_cov)
    tx_masks, rx_masks = (xp.asarray(m) for m in all_super_arms(num_tx, num_rx, tx_count, rx_count))
    scores = super_arm_criterion(position_cov, information, tx_masks, rx_masks, weights, criterion, fusion)
    if sinr_weight > 0:
        if sinr_index is None:
            raise ValueError("sinr_weight > 0 needs the SINR index of the channels (sinr_index)")
        value = xp.einsum(
            "am,bmn,an->ba", xp.astype(tx_masks, np.float64), sinr_index, xp.astype(rx_masks, np.float64)
        )
        scores = (1.0 - sinr_weight) * _unit_range(scores) - sinr_weight * _unit_range(value)
    best = xp.argmin(scores, axis=1)
    return tx_masks[best], rx_masks[best]


def _unit_range(scores: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each row rescaled to [0, 1] by its range (a constant row becomes 0)."""
    xp = namespace(scores)
    low = xp.min(scores, axis=1, keepdims=True)
    span = xp.max(scores, axis=1, keepdims=True) - low
    return xp.where(span > 0, (scores - low) / xp.where(span > 0, span, 1.0), 0.0)


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

    Both fusions' posteriors are functions of a sum over the super arm's channels (of the
    channels' information, or of their single-channel posteriors), so a candidate that adds or
    swaps one station is scored from the current sum and the station's row or column sum: the
    memory per trial is ``O(K (M^2 + N^2))``, never one array per candidate and channel.

    The trials are searched in blocks whose swap candidates take at most
    :data:`GREEDY_BLOCK_BYTES` (each trial's search is its own, so the blocks change no
    selection): larger arrays would be fresh memory from the operating system at every swap
    round, and at 64 x 64 stations the page faults cost more than the arithmetic.
    """
    num_tx, num_rx = information.shape[2:4]
    starts = min(starts, num_tx * num_rx)
    batch = position_cov.shape[0]
    block = max(1, GREEDY_BLOCK_BYTES // _swap_bytes(num_tx, num_rx, information.shape[1], starts))
    if batch > block:
        parts = [
            greedy_super_arm(
                position_cov[i : i + block],
                information[i : i + block],
                weights,
                tx_count,
                rx_count,
                criterion,
                fusion,
                starts,
            )
            for i in range(0, batch, block)
        ]
        return np.concatenate([tx for tx, _ in parts]), np.concatenate([rx for _, rx in parts])
    scorer = _Scorer(position_cov, information, weights, criterion, fusion)
    single = scorer.score(scorer.terms.transpose(0, 2, 3, 1, 4, 5), 1.0).reshape(batch, -1)  # (B, M * N)
    first = np.argsort(single, axis=1)[:, :starts].reshape(-1)  # (B * starts,), trial-major
    scorer = scorer.repeat(starts)  # every start is a trial of its own from here on
    tx = np.zeros((batch * starts, num_tx), dtype=bool)
    rx = np.zeros((batch * starts, num_rx), dtype=bool)
    rows = np.arange(batch * starts)
    tx[rows, first // num_rx] = True
    rx[rows, first % num_rx] = True
    for _ in range(tx_count + rx_count - 2):
        # every trial adds one station: a transmitter while it has fewer than tx_count, or a receiver
        total, by_tx, by_rx = scorer.sums(tx, rx)
        ntx, nrx = tx.sum(1), rx.sum(1)
        scores = np.concatenate(
            [
                scorer.score(total[:, None] + by_tx, ((ntx + 1) * nrx)[:, None]),
                scorer.score(total[:, None] + by_rx, (ntx * (nrx + 1))[:, None]),
            ],
            axis=1,
        )
        allowed = np.concatenate([~tx & (ntx < tx_count)[:, None], ~rx & (nrx < rx_count)[:, None]], axis=1)
        choice = np.argmin(np.where(allowed, scores, np.inf), axis=1)
        adds_tx = choice < num_tx
        tx[rows[adds_tx], choice[adds_tx]] = True
        rx[rows[~adds_tx], choice[~adds_tx] - num_tx] = True
    tx, rx = _swap_search(scorer, tx, rx)
    final = scorer.score(scorer.sums(tx, rx)[0], (tx.sum(1) * rx.sum(1)).astype(float))
    best = np.argmin(final.reshape(batch, starts), axis=1) + np.arange(batch) * starts
    return tx[best], rx[best]


class _Scorer:
    """The criterion of super arms given as sums over their channels of the fusion's
    per-channel term (B, K, M, N, 2, 2) (:meth:`~.fusion.Fusion.channel_terms`)."""

    def __init__(self, position_cov, information, weights, criterion, fusion) -> None:
        self.posterior = _check_choices(criterion, fusion)
        self.prior_info, _ = inverse_2x2(position_cov)  # (B, K, 2, 2)
        self.terms = self.posterior.channel_terms(self.prior_info, information)  # (B, K, M, N, 2, 2)
        self.weights = np.asarray(weights, dtype=np.float64)
        self.criterion = criterion

    def repeat(self, times: int) -> _Scorer:
        out = object.__new__(_Scorer)
        out.__dict__.update(self.__dict__)
        out.prior_info = np.repeat(self.prior_info, times, axis=0)
        out.terms = np.repeat(self.terms, times, axis=0)
        return out

    def sums(self, tx: NDArray[np.bool_], rx: NDArray[np.bool_]) -> tuple[NDArray, NDArray, NDArray]:
        """The super arm's sum (B, K, 2, 2) and each station's sum over the other side's selected
        stations: by transmitter (B, M, K, 2, 2), by receiver (B, N, K, 2, 2)."""
        by_tx = np.einsum("bn,bkmnij->bmkij", rx.astype(float), self.terms)
        by_rx = np.einsum("bm,bkmnij->bnkij", tx.astype(float), self.terms)
        total = np.einsum("bm,bmkij->bkij", tx.astype(float), by_tx)
        return total, by_tx, by_rx

    def score(self, total: NDArray[np.float64], count: NDArray[np.float64] | float) -> NDArray[np.float64]:
        """The criterion (B, ...) of sums ``total`` (B, ..., K, 2, 2) over ``count`` channels."""
        extra = total.ndim - self.prior_info.ndim  # candidate axes between trials and targets
        prior = self.prior_info.reshape(self.prior_info.shape[0], *([1] * extra), *self.prior_info.shape[1:])
        count = np.asarray(count, dtype=np.float64)
        count = count.reshape(*count.shape, *([1] * (total.ndim - count.ndim)))
        posterior = self.posterior.posterior_from_sum(prior, total, count)
        with np.errstate(invalid="ignore", divide="ignore"):  # disallowed swaps are masked later
            return _per_target(posterior, self.criterion) @ self.weights


def _swap_search(
    scorer: _Scorer, tx: NDArray[np.bool_], rx: NDArray[np.bool_], max_rounds: int = 50
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Local search: while some swap of one selected station for an unselected one of the same
    kind lowers a trial's criterion, make the best such swap (all trials at once)."""
    batch, num_tx, num_rx = tx.shape[0], tx.shape[1], rx.shape[1]
    rows = np.arange(batch)
    count = (tx.sum(1) * rx.sum(1)).astype(float)
    total, by_tx, by_rx = scorer.sums(tx, rx)
    current = scorer.score(total, count)
    for _ in range(max_rounds):
        # swapping station "out" for station "in": the sum loses out's row and gains in's
        swap_tx = total[:, None, None] - by_tx[:, :, None] + by_tx[:, None, :]  # (B, out, in, K, 2, 2)
        swap_rx = total[:, None, None] - by_rx[:, :, None] + by_rx[:, None, :]
        scores = np.concatenate(
            [
                scorer.score(swap_tx, count[:, None, None]).reshape(batch, -1),
                scorer.score(swap_rx, count[:, None, None]).reshape(batch, -1),
            ],
            axis=1,
        )
        ok_tx = (tx[:, :, None] & ~tx[:, None, :]).reshape(batch, -1)
        ok_rx = (rx[:, :, None] & ~rx[:, None, :]).reshape(batch, -1)
        scores = np.where(np.concatenate([ok_tx, ok_rx], axis=1), scores, np.inf)
        choice = np.argmin(scores, axis=1)
        better = scores[rows, choice] < current - 1e-12 * np.abs(current)
        if not better.any():
            break
        is_tx = better & (choice < num_tx * num_tx)
        is_rx = better & ~is_tx
        out_tx, in_tx = np.divmod(choice[is_tx], num_tx)
        tx[rows[is_tx], out_tx], tx[rows[is_tx], in_tx] = False, True
        out_rx, in_rx = np.divmod(choice[is_rx] - num_tx * num_tx, num_rx)
        rx[rows[is_rx], out_rx], rx[rows[is_rx], in_rx] = False, True
        total, by_tx, by_rx = scorer.sums(tx, rx)
        current = np.where(better, scores[rows, choice], current)
    return tx, rx


def compiled_kernels(threaded: bool = False) -> list:
    """The numba kernels the tracking search runs (its twin over threads with ``threaded``; none
    without numba)."""
    return (
        [_KERNELS.get("_compiled_posteriors_threaded" if threaded else "_compiled_posteriors")]
        if HAVE_NUMBA
        else []
    )


_KERNELS = LazyKernels(
    __name__,
    _compiled_posteriors="._selection_kernels:posterior_values",
    _compiled_posteriors_threaded="._selection_kernels:posterior_values_threaded",
)
__getattr__ = _KERNELS.module_getattr
