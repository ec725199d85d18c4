"""Alternating maximisation with restarts, for arrays too large to enumerate."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env.core.counter_hash import Stream
from mimo_radar_env.core.streams import TrialRandom
from mimo_radar_env.core.superarm import (
    SEARCH_SECONDS_PER_OPERATION,
    alternating_operations,
    alternating_super_arm,
    top_mask,
)

from ..parameters import check_integer
from .base import SuperArmSolver


class AlternatingSolver(SuperArmSolver):
    """Coordinate ascent on the two sides, from deterministic and random starts.

    Given transmitters, the best receivers are the ``Ns`` largest column sums; given
    receivers, the best transmitters are the ``Ms`` largest row sums. Each start
    alternates the two until nothing changes (the value never decreases); the best
    local optimum over the starts is returned. Starts: the ``N + 2`` deterministic
    ones of :func:`mimo_radar_env.core.superarm.alternating_super_arm` (the routine the
    env's oracle uses beyond exact enumeration) and ``restarts`` uniformly random
    transmitter subsets. Cost per round is ``O(B * starts * M * N)``, so it scales to
    hundreds of stations.

    Parameters
    ----------
    restarts : int
        Random starts besides the deterministic ones (default 8).
    max_rounds : int
        Bound on the alternations per start (default 50).
    """

    name = "alternating"
    seconds_per_operation = SEARCH_SECONDS_PER_OPERATION["alternating"]

    def __init__(self, tx_count: int, rx_count: int, restarts: int = 8, max_rounds: int = 50) -> None:
        super().__init__(tx_count, rx_count)
        check_integer("restarts", restarts, 0, 1_000)
        check_integer("max_rounds", max_rounds, 1, 10_000)
        self.restarts = restarts
        self.max_rounds = max_rounds

    def memory_per_trial(self, num_tx: int, num_rx: int) -> int:
        """Every start's masks and the index sums over the other side."""
        return 8 * 4 * (self.restarts + 1) * (num_tx + num_rx) + super().memory_per_trial(num_tx, num_rx)

    def operations_per_trial(self, num_tx: int, num_rx: int) -> float:
        return alternating_operations(num_tx, num_rx, self.restarts, rounds=min(self.max_rounds, 2))

    def solve(
        self, index: NDArray[np.float64], random: TrialRandom
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        index = self.check(index)
        batch, num_tx, _ = index.shape
        starts = (
            top_mask(random.uniform(Stream.ALTERNATING_STARTS, (self.restarts, num_tx)), self.tx_count)
            if self.restarts
            else None
        )
        tx, rx, _ = alternating_super_arm(index, self.tx_count, self.rx_count, self.max_rounds, starts)
        return tx, rx
