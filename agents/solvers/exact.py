"""The exact solver: enumerate the smaller side, take the top sums of the other ."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env.core.superarm import exact_super_arm

from ..random_streams import TrialRandom
from .base import SuperArmSolver


class ExactSolver(SuperArmSolver):
    """The optimum, by enumerating ``C(M, Ms)`` (or ``C(N, Ns)``) subsets.

    For each transmitter subset the best receivers are the ``Ns`` largest column
    sums, so only the smaller side is enumerated. Refuses layouts with more than
    200,000 subsets on the smaller side (use ``"alternating"`` there).
    """

    name = "exact"

    def solve(
        self, index: NDArray[np.float64], random: TrialRandom
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        tx, rx, _ = exact_super_arm(self.check(index), self.tx_count, self.rx_count)
        return tx, rx
