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

from ..core.arrays import namespace
from ..core.superarm import all_super_arms, masks_to_actions, super_arm_count, top_mask
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
        self.actions = masks_to_actions(tx, rx)
        self._on_device: dict[Any, Any] = {}

    @property
    def size(self) -> int:
        return len(self.actions)

    def to_action(self, index: Any) -> NDArray[np.int8]:
        """Env action(s) ``(..., M + N)`` for super-arm index(es); for a torch tensor of indices,
        a tensor on its device."""
        xp = namespace(index)
        if xp.is_torch:
            if bool(((index < 0) | (index >= self.size)).any()):
                raise ValueError(f"super-arm index must be in [0, {self.size}), got {xp.to_numpy(index)}")
            if index.device not in self._on_device:
                self._on_device[index.device] = xp.asarray(self.actions)
            return self._on_device[index.device][index.long()]
        index = np.asarray(index, dtype=np.int64)
        if np.any((index < 0) | (index >= self.size)):
            raise ValueError(f"super-arm index must be in [0, {self.size}), got {index}")
        return self.actions[index]

    def to_index(self, action: Any) -> NDArray[np.int64]:
        """The super-arm index(es) ``(...)`` of env action(s) ``(..., M + N)``, the inverse of
        :meth:`to_action`; ``ValueError`` for an action that is not a valid super arm. A torch
        tensor gives a tensor on its device."""
        xp = namespace(action)
        if xp.is_torch:
            return xp.asarray(self.to_index(xp.to_numpy(action)))
        action = np.asarray(action)
        if action.shape[-1:] != (self.num_tx + self.num_rx,):
            bits = self.num_tx + self.num_rx
            raise ValueError(f"actions must end in {bits} bits (M + N), got shape {action.shape}")
        keys = _row_keys(self.actions)
        order = np.argsort(keys)
        query = _row_keys(action.reshape(-1, action.shape[-1]).astype(np.int8))
        found = np.minimum(np.searchsorted(keys, query, sorter=order), self.size - 1)
        index = order[found]
        if not np.array_equal(keys[index], query):
            raise ValueError("an action is not a valid super arm (exactly Ms transmitters and Ns receivers)")
        return index.reshape(action.shape[:-1])


def shown(value: Any, limit: int = 120) -> str:
    """``value`` as an error message shows it: its repr on one line, cut at ``limit`` characters."""
    text = " ".join(repr(value).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def check_discrete_actions(actions: Any, size: int, shape: tuple[int, ...] = ()) -> NDArray[np.int64]:
    """Validate ``Discrete(size)`` actions of ``shape`` (``()`` for one): integers only (no
    floats, booleans or strings, not even integral ones), in ``[0, size)``. Raises ``ValueError``
    showing the value as given; returns them as int64 (a torch tensor stays one, where it is).
    The single env's wrapper and the Flat vector env both validate with it."""
    xp = namespace(actions)
    arr = actions if xp.is_torch else np.asarray(actions)
    if xp.dtype_kind(arr) not in "iu" or isinstance(actions, bool | np.bool_):
        raise ValueError(
            f"a Discrete action must be an integer super-arm index in [0, {size}), got {shown(actions)}"
        )
    if tuple(arr.shape) != shape:
        raise ValueError(
            f"Discrete actions must have shape {shape}, got shape {tuple(arr.shape)} ({shown(actions)})"
        )
    outside = (arr < 0) | (arr >= size)
    if bool(outside.any()):
        bad = xp.to_numpy(arr[outside]).ravel()[:5].tolist()
        raise ValueError(f"a Discrete action's super-arm index must be in [0, {size}), got {bad}")
    return xp.astype(arr, np.int64)


def check_score_actions(scores: Any, size: int, shape: tuple[int, ...] = ()) -> NDArray[np.float64]:
    """Validate station-score actions, ``Box(-1, 1, (size,))`` of leading ``shape``: real
    numbers, finite, within [-1, 1] (refused outside, not clipped). Raises ``ValueError`` showing
    the values as given; returns float64 (a torch tensor stays one, where it is)."""
    xp = namespace(scores)
    arr = scores if xp.is_torch else np.asarray(scores)
    if xp.dtype_kind(arr) not in "iuf" or isinstance(scores, bool | np.bool_):
        raise ValueError(f"station scores must be real numbers in [-1, 1], got {shown(scores)}")
    if tuple(arr.shape) != (*shape, size):
        raise ValueError(f"station scores must have shape {(*shape, size)}, got shape {tuple(arr.shape)}")
    outside = ~xp.isfinite(arr) | (arr < -1) | (arr > 1)
    if bool(outside.any()):
        bad = xp.to_numpy(arr[outside]).ravel()[:5].tolist()
        raise ValueError(f"station scores must be finite and in [-1, 1], got {bad}")
    return xp.astype(arr, np.float64)


def _row_keys(bits: NDArray[np.int8]) -> NDArray[np.void]:
    """One comparable key per row of 0/1 bits (their packed bytes)."""
    packed = np.ascontiguousarray(np.packbits(bits.astype(bool), axis=-1))
    return packed.view(np.dtype((np.void, packed.shape[-1])))[:, 0]


class SuperArmDiscreteAction(gym.ActionWrapper, gym.utils.RecordConstructorArgs):
    """``Discrete(C(M, Ms) * C(N, Ns))``: every action is one valid super arm (a bijection)."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ActionWrapper.__init__(self, env)
        self.index = SuperArmIndex(scenario_of(env))
        self.action_space = spaces.Discrete(self.index.size)

    def action(self, action: Any) -> NDArray[np.int8]:
        return self.index.to_action(check_discrete_actions(action, self.index.size))

    def oracle_action(self) -> int:
        """The optimal super arm of the coming step as this wrapper's ``Discrete`` action (reads
        the truth: oracle only; ``env.get_wrapper_attr("oracle_action")()`` from outside)."""
        return int(self.index.to_index(self.env.unwrapped.oracle_action()))

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
    xp = namespace(scores)
    scores = xp.astype(scores if xp.is_torch else np.asarray(scores), np.float64)
    if not bool(xp.all(xp.isfinite(scores))):
        raise ValueError("station scores must be finite")
    tx = top_mask(scores[..., :num_tx], tx_count)
    rx = top_mask(scores[..., num_tx:], rx_count)
    return masks_to_actions(tx, rx)


class StationScoreAction(gym.ActionWrapper, gym.utils.RecordConstructorArgs):
    """``Box(-1, 1, (M + N,))``: a score per station; the top-``Ms`` TX and top-``Ns`` RX are used."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ActionWrapper.__init__(self, env)
        sc = scenario_of(env)
        self._sizes = (sc.num_tx, sc.tx_per_step, sc.rx_per_step)
        self.action_space = spaces.Box(-1.0, 1.0, (sc.num_tx + sc.num_rx,), np.float32)

    def action(self, action: Any) -> NDArray[np.int8]:
        size = self.action_space.shape[0]
        return scores_to_action(check_score_actions(action, size), *self._sizes)

    def oracle_action(self) -> NDArray[np.float32]:
        """The optimal super arm of the coming step as station scores (+1 the selected stations,
        -1 the others), which :meth:`action` maps back to it (reads the truth: oracle only)."""
        return (2.0 * self.env.unwrapped.oracle_action() - 1.0).astype(np.float32)
