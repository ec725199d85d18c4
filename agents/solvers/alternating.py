"""Alternating maximisation with restarts, for arrays too large to enumerate."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env.core.superarm import local_search_super_arm, super_arm_value, top_mask

from .base import SuperArmSolver


class AlternatingSolver(SuperArmSolver):
    """Coordinate ascent on the two sides, from deterministic and random starts.

    Given transmitters, the best receivers are the ``Ns`` largest column sums; given
    receivers, the best transmitters are the ``Ms`` largest row sums. Each start
    alternates the two until nothing changes (the value never decreases); the best
    local optimum over the starts is returned. Starts: the ``M + 2`` deterministic
    ones of :func:`mimo_radar_env.core.superarm.local_search_super_arm` and
    ``restarts`` uniformly random transmitter subsets. Cost per round is
    ``O(B * starts * M * N)``, so it scales to hundreds of stations.

    Parameters
    ----------
    restarts : int
        Random starts besides the deterministic ones (default 8).
    max_rounds : int
        Bound on the alternations per start (default 50).
    """

    name = "alternating"

    def __init__(self, tx_count: int, rx_count: int, restarts: int = 8, max_rounds: int = 50) -> None:
        super().__init__(tx_count, rx_count)
        if restarts < 0 or max_rounds < 1:
            raise ValueError("restarts must be >= 0 and max_rounds >= 1")
        self.restarts = restarts
        self.max_rounds = max_rounds

    def solve(
        self, index: NDArray[np.float64], rng: np.random.Generator
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        index = self.check(index)
        tx, rx, value = local_search_super_arm(index, self.tx_count, self.rx_count, self.max_rounds)
        if self.restarts == 0:
            return tx, rx
        batch, num_tx, _ = index.shape
        start_tx = top_mask(rng.random((batch, self.restarts, num_tx)), self.tx_count)
        for _ in range(self.max_rounds):
            start_rx = top_mask(np.einsum("bsm,bmn->bsn", start_tx.astype(np.float64), index), self.rx_count)
            new_tx = top_mask(np.einsum("bmn,bsn->bsm", index, start_rx.astype(np.float64)), self.tx_count)
            if np.array_equal(new_tx, start_tx):
                break
            start_tx = new_tx
        start_value = super_arm_value(index[:, None], start_tx, start_rx)
        best = np.argmax(start_value, axis=1)
        rows = np.arange(batch)
        better = start_value[rows, best] > value
        tx = np.where(better[:, None], start_tx[rows, best], tx)
        rx = np.where(better[:, None], start_rx[rows, best], rx)
        return tx, rx
