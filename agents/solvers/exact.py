"""The exact solver: enumerate the smaller side, take the top sums of the other ."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env.core.streams import TrialRandom
from mimo_radar_env.core.superarm import (
    MAX_EXACT_SUBSETS,
    SEARCH_SECONDS_PER_OPERATION,
    exact_operations,
    exact_super_arm,
    is_exact_affordable,
)

from .base import SuperArmSolver


class ExactSolver(SuperArmSolver):
    """The optimum, by enumerating ``C(M, Ms)`` (or ``C(N, Ns)``) subsets.

    For each transmitter subset the best receivers are the ``Ns`` largest column
    sums, so only the smaller side is enumerated. Refuses layouts with more than
    200,000 subsets on the smaller side (use ``"alternating"`` there).
    """

    name = "exact"
    seconds_per_operation = SEARCH_SECONDS_PER_OPERATION["exact"]

    def memory_per_trial(self, num_tx: int, num_rx: int) -> int:
        """The smaller side's subsets, each with the other side's sums (a few float64 copies)."""
        subsets = min(math.comb(num_tx, self.tx_count), math.comb(num_rx, self.rx_count))
        return 8 * 4 * subsets * max(num_tx, num_rx) + super().memory_per_trial(num_tx, num_rx)

    def operations_per_trial(self, num_tx: int, num_rx: int) -> float:
        return exact_operations(num_tx, num_rx, self.tx_count, self.rx_count)

    def check_layout(self, num_tx: int, num_rx: int) -> None:
        super().check_layout(num_tx, num_rx)
        if not is_exact_affordable(num_tx, num_rx, self.tx_count, self.rx_count):
            subsets = min(math.comb(num_tx, self.tx_count), math.comb(num_rx, self.rx_count))
            raise ValueError(
                f"the exact solver would enumerate {subsets:,} subsets (more than {MAX_EXACT_SUBSETS:,}) on "
                f"a {num_tx} x {num_rx} layout with Ms={self.tx_count}, Ns={self.rx_count}; use "
                "solver='alternating' (or 'bpso') there"
            )

    def solve(
        self, index: NDArray[np.float64], random: TrialRandom
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        tx, rx, _ = exact_super_arm(self.check(index), self.tx_count, self.rx_count)
        return tx, rx
