"""Fixed selections: a given super arm every step (the paper's fix1 and fix2)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario

from .base import Agent, Observation
from .costs import Needs

#: The paper's fixed selections (Section IV), 0-based: fix1 = {TX3, TX4; RX1, RX3, RX4},
#: fix2 = {TX3, TX4; RX4, RX5, RX6}.
PAPER_FIXED = {"fix1": ((2, 3), (0, 2, 3)), "fix2": ((2, 3), (3, 4, 5))}


class FixedAgent(Agent):
    """Plays the same super arm every step.

    Parameters
    ----------
    tx, rx : sequences of int
        0-based indices of the transmitters and receivers (exactly Ms and Ns of them).
    """

    name = "fixed"
    needs = Needs(device=True)

    def __init__(
        self, scenario: Scenario | str, tx: Sequence[int], rx: Sequence[int], seed: int | None = None
    ) -> None:
        super().__init__(scenario, seed)
        tx, rx = _indices("tx", tx), _indices("rx", rx)
        if len(set(tx)) != self.tx_count or not all(0 <= i < self.num_tx for i in tx):
            raise ValueError(
                f"tx must be {self.tx_count} distinct transmitter indices in 0..{self.num_tx - 1}, got {tx}"
            )
        if len(set(rx)) != self.rx_count or not all(0 <= i < self.num_rx for i in rx):
            raise ValueError(
                f"rx must be {self.rx_count} distinct receiver indices in 0..{self.num_rx - 1}, got {rx}"
            )
        self.action = np.zeros(self.num_tx + self.num_rx, dtype=np.int8)
        self.action[tx] = 1
        self.action[self.num_tx + np.array(rx)] = 1

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        return self.xp.tile(self.xp.asarray(self.action), (self.batch_size, 1))


def _indices(name: str, value: Any) -> list[int]:
    """A sorted list of station indices, or a ``ValueError`` naming ``name``."""
    if isinstance(value, str) or not isinstance(value, Sequence | np.ndarray):
        raise ValueError(f"{name} must be a list of 0-based station indices, got {value!r}")
    if not all(isinstance(i, int | np.integer) and not isinstance(i, bool) for i in value):
        raise ValueError(f"{name} must hold integer station indices, got {list(value)!r}")
    return sorted(int(i) for i in value)
