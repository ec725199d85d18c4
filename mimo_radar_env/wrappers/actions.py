"""Valid actions for learning agents: every action a wrapper offers is a valid super arm, so a
policy never has to learn the ``Ms``/``Ns`` constraint.

* :class:`SuperArmDiscreteAction`: ``Discrete(C(M, Ms) * C(N, Ns))``, one action per super
  arm (:class:`SuperArmIndex`), for layouts where that number is small;
* :class:`StationScoreAction`: ``Box(-1, 1, (M + N,))`` scores; the top-``Ms`` transmitters
  and top-``Ns`` receivers are selected (:func:`scores_to_action`), for large arrays.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from ..core.superarm import all_super_arms, super_arm_count, top_mask
from ..scenarios import Scenario

#: Largest number of super arms :class:`SuperArmDiscreteAction` enumerates.
MAX_DISCRETE_SUPER_ARMS = 100_000


def scenario_of(env: gym.Env) -> Scenario:
    """The scenario of a (wrapped) env."""
    return env.unwrapped.scenario


class SuperArmIndex:
    """The bijection between ``0..C(M,Ms)*C(N,Ns)-1`` and valid super arms.

    Index ``i`` selects the ``i // C(N, Ns)``-th transmitter subset and the
    ``i % C(N, Ns)``-th receiver subset, subsets in lexicographic order.
    """

    def __init__(self, scenario: Scenario) -> None:
        sc = scenario
        self.num_tx, self.num_rx = sc.num_tx, sc.num_rx
        count = super_arm_count(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        if count > MAX_DISCRETE_SUPER_ARMS:
            raise ValueError(
                f"{count} super arms are too many for a Discrete action (limit {MAX_DISCRETE_SUPER_ARMS}); "
                "use StationScoreAction for this layout"
            )
        tx, rx = all_super_arms(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        self.actions = np.concatenate([tx, rx], axis=1).astype(np.int8)

    @property
    def size(self) -> int:
        return len(self.actions)

    def to_action(self, index: Any) -> NDArray[np.int8]:
        """Env action(s) ``(..., M + N)`` for super-arm index(es)."""
        index = np.asarray(index, dtype=np.int64)
        if np.any((index < 0) | (index >= self.size)):
            raise ValueError(f"super-arm index must be in [0, {self.size}), got {index}")
        return self.actions[index]


class SuperArmDiscreteAction(gym.ActionWrapper, gym.utils.RecordConstructorArgs):
    """``Discrete(C(M, Ms) * C(N, Ns))``: every action is one valid super arm (a bijection)."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ActionWrapper.__init__(self, env)
        self.index = SuperArmIndex(scenario_of(env))
        self.action_space = spaces.Discrete(self.index.size)

    def action(self, action: Any) -> NDArray[np.int8]:
        return self.index.to_action(action)

    def action_masks(self) -> NDArray[np.bool_]:
        """Which Discrete actions are allowed: all of them, since each is a valid super arm.

        Mask-aware learners call it (sb3-contrib's ``MaskablePPO`` through
        ``get_wrapper_attr("action_masks")``); a subclass may narrow it, e.g. to exclude
        failed stations.
        """
        return np.ones(self.index.size, dtype=bool)


def scores_to_action(
    scores: NDArray[np.float64], num_tx: int, tx_count: int, rx_count: int
) -> NDArray[np.int8]:
    """Top-``Ms`` transmitter and top-``Ns`` receiver scores (ties: lowest index), (..., M + N)."""
    scores = np.asarray(scores, dtype=np.float64)
    if not np.all(np.isfinite(scores)):
        raise ValueError("station scores must be finite")
    tx = top_mask(scores[..., :num_tx], tx_count)
    rx = top_mask(scores[..., num_tx:], rx_count)
    return np.concatenate([tx, rx], axis=-1).astype(np.int8)


class StationScoreAction(gym.ActionWrapper, gym.utils.RecordConstructorArgs):
    """``Box(-1, 1, (M + N,))``: a score per station; the top-``Ms`` TX and top-``Ns`` RX are used."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ActionWrapper.__init__(self, env)
        sc = scenario_of(env)
        self._sizes = (sc.num_tx, sc.tx_per_step, sc.rx_per_step)
        self.action_space = spaces.Box(-1.0, 1.0, (sc.num_tx + sc.num_rx,), np.float32)

    def action(self, action: Any) -> NDArray[np.int8]:
        return scores_to_action(action, *self._sizes)
