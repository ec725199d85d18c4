"""The super-arm solver interface.

A solver picks, for each trial of a batch, the super arm (exactly ``Ms``
transmitters and ``Ns`` receivers) that maximises ``sum_{m in tx, n in rx} I[m, n]``
for an index matrix ``I`` (B, M, N) (Section III-B).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env.core.arrays import namespace
from mimo_radar_env.core.streams import TrialRandom


class SuperArmSolver(ABC):
    """Base class of super-arm solvers.

    Parameters
    ----------
    tx_count, rx_count : int
        ``Ms`` and ``Ns``.
    """

    #: Registry name.
    name: str = ""
    #: Seconds per declared operation (:meth:`operations_per_trial`) on the developers' machine,
    #: fitted to ``benchmarks.speed.policy_cost``'s measurements (the harness's time estimates).
    seconds_per_operation: float = 1e-9
    #: Its selection runs in a compiled kernel that spreads the trials over threads.
    threaded: bool = False
    #: The form of its work on torch (:data:`~mimo_radar_env.envs.device_forms.DEVICE_MODES`; an
    #: agent sets its env's, :meth:`~agents.base.Agent.use_device_mode`): the same selections in
    #: every form.
    device_mode: str = "eager"

    def __init__(self, tx_count: int, rx_count: int) -> None:
        if tx_count < 1 or rx_count < 1:
            raise ValueError(f"tx_count and rx_count must be >= 1, got {tx_count}, {rx_count}")
        self.tx_count = tx_count
        self.rx_count = rx_count

    def check_layout(self, num_tx: int, num_rx: int) -> None:
        """Raise ``ValueError`` if the solver cannot serve an ``M x N`` layout (checked when an
        agent is made, before anything runs)."""
        if num_tx < self.tx_count or num_rx < self.rx_count:
            raise ValueError(
                f"the layout has {num_tx} TX and {num_rx} RX, fewer than "
                f"Ms={self.tx_count}, Ns={self.rx_count}"
            )

    def memory_per_trial(self, num_tx: int, num_rx: int) -> int:
        """Bytes one trial's selection needs at its peak, roughly (an upper estimate)."""
        return 8 * 4 * num_tx * num_rx

    def operations_per_trial(self, num_tx: int, num_rx: int) -> float:
        """Arithmetic operations of one trial's selection, roughly (an upper estimate)."""
        return 4.0 * num_tx * num_rx

    def check(self, index: NDArray[np.float64]) -> NDArray[np.float64]:
        xp = namespace(index)
        index = xp.asarray(index, dtype=np.float64)
        if index.ndim != 3:
            raise ValueError(f"index must have shape (B, M, N), got {index.shape}")
        if index.shape[1] < self.tx_count or index.shape[2] < self.rx_count:
            raise ValueError(
                f"index of shape {index.shape} has fewer stations than Ms={self.tx_count}, Ns={self.rx_count}"
            )
        if not xp.all(xp.isfinite(index)):
            raise ValueError("index contains NaN or infinite values")
        return index

    @abstractmethod
    def solve(
        self, index: NDArray[np.float64], random: TrialRandom
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Best super arm per trial: boolean masks (B, M) and (B, N)."""
