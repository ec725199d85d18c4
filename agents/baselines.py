"""Reference policies: a fixed super arm, the Best oracle, and uniform random."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario

from .base import Agent, Observation

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

    def __init__(
        self, scenario: Scenario | str, tx: Sequence[int], rx: Sequence[int], seed: int | None = None
    ) -> None:
        super().__init__(scenario, seed)
        tx, rx = sorted(int(i) for i in tx), sorted(int(i) for i in rx)
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

    def _reset(self, obs: Observation) -> None:
        pass

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        return np.tile(self.action, (self.batch_size, 1))


class BestAgent(Agent):
    """The Best oracle: the optimal super arm for the true mean SINR of each step.

    It reads the truth, through the ``oracle_action()`` of the env it is attached to
    (:meth:`attach`); it has zero regret by construction.
    """

    name = "best"
    needs_oracle = True

    def __init__(self, scenario: Scenario | str, seed: int | None = None, env: Any = None) -> None:
        super().__init__(scenario, seed)
        self._oracle: Callable[[], NDArray[np.int8]] | None = None
        if env is not None:
            self.attach(env)

    def attach(self, env: Any) -> None:
        """Read the optimal super arm from ``env.oracle_action()`` (single or vector env)."""
        target = env if hasattr(env, "oracle_action") else getattr(env, "unwrapped", env)
        if not hasattr(target, "oracle_action"):
            raise TypeError(f"{type(env).__name__} has no oracle_action(); attach a MimoRadarSelect env")
        self._oracle = target.oracle_action

    def _reset(self, obs: Observation) -> None:
        if self._oracle is None:
            raise RuntimeError("the best oracle needs the env: call agent.attach(env) first")

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        assert self._oracle is not None
        return np.asarray(self._oracle(), dtype=np.int8).reshape(self.batch_size, -1)


class RandomAgent(Agent):
    """A uniformly random valid super arm every step, independently per trial."""

    name = "random"

    def _reset(self, obs: Observation) -> None:
        pass

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        return self.random_super_arms(self.batch_size)
