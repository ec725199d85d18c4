"""The agent interface: batch-native selection policies.

An agent acts on the single env and on the vector env alike. It is reset from the
reset observation, chooses actions from an observation and learns from the step's
observation and reward::

    agent = agents.make_agent("mg-crb-cl", scenario, seed=0)
    obs, info = env.reset(seed=0)
    agent.reset(obs)
    while True:
        action = agent.act(obs)
        obs, reward, terminated, truncated, info = env.step(action)
        agent.update(obs, reward)

Observations with a leading trial axis (vector env) give actions (B, M + N);
unbatched observations (single env) give actions (M + N,). An agent sees only the
observation and the scenario's public geometry (station positions, Ms, Ns, target
weights, the radar constants); only the oracle reads the truth, through
``oracle_action()`` of the env it is attached to.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario, load_scenario
from mimo_radar_env.core.superarm import random_super_arms

from .solvers import SuperArmSolver, make_solver

Observation = dict[str, NDArray[Any]]


def check_parameter(
    name: str, value: float, low: float, high: float = np.inf, low_open: bool = False
) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``value`` is in [low, high] (or (low, high])."""
    inside = (value > low if low_open else value >= low) and value <= high
    if not inside:
        bracket = "(" if low_open else "["
        upper = "inf)" if high == np.inf else f"{high:g}]"
        raise ValueError(f"{name} must be in {bracket}{low:g}, {upper}, got {value}")


class Agent(ABC):
    """Base class of selection policies.

    Parameters
    ----------
    scenario : Scenario or str
        The scenario (its public geometry is all an agent may use).
    seed : int, optional
        Seed of the agent's own random generator (exploration, BPSO).
    """

    #: Registry name.
    name: str = ""
    #: True for agents that read the truth through the env (the oracle).
    needs_oracle: bool = False

    def __init__(self, scenario: Scenario | str, seed: int | None = None) -> None:
        self.scenario = load_scenario(scenario) if not isinstance(scenario, Scenario) else scenario
        self.rng = np.random.default_rng(seed)
        self.num_tx = self.scenario.num_tx
        self.num_rx = self.scenario.num_rx
        self.tx_count = self.scenario.tx_per_step
        self.rx_count = self.scenario.rx_per_step
        self.weights = self.scenario.weights
        self.batch_size = 0
        self.t = 0

    # -------------------------------------------------------- public API
    def reset(self, obs: Observation) -> None:
        """Start an episode from the reset observation (every channel probed once)."""
        batch, batched = self._batch(obs)
        self.batch_size = batch.get("sinr").shape[0]
        self._batched = batched
        self.t = 0
        self._reset(batch)

    def act(self, obs: Observation) -> NDArray[np.int8]:
        """The action for the coming step."""
        if self.batch_size == 0:
            raise RuntimeError(f"{type(self).__name__}.act() called before reset(obs)")
        batch, batched = self._batch(obs)
        self.t += 1
        actions = self._act(batch)
        return actions if batched else actions[0]

    def update(self, obs: Observation, reward: Any) -> None:
        """Learn from the observation and reward of the step just taken."""
        batch, _ = self._batch(obs)
        self._update(batch, np.atleast_1d(np.asarray(reward, dtype=np.float64)))

    # ------------------------------------------------------- to implement
    @abstractmethod
    def _reset(self, obs: Observation) -> None: ...

    @abstractmethod
    def _act(self, obs: Observation) -> NDArray[np.int8]: ...

    def _update(self, obs: Observation, reward: NDArray[np.float64]) -> None:  # noqa: B027
        """Default: nothing to learn."""

    # ------------------------------------------------------------ helpers
    def _batch(self, obs: Observation) -> tuple[Observation, bool]:
        sinr = np.asarray(obs["sinr"])
        if sinr.ndim == 3:
            return {key: np.asarray(value)[None] for key, value in obs.items()}, False
        if sinr.ndim == 4:
            return obs, True
        raise ValueError(f"observation 'sinr' must have shape (K, M, N) or (B, K, M, N), got {sinr.shape}")

    def actions_from_masks(self, tx: NDArray[np.bool_], rx: NDArray[np.bool_]) -> NDArray[np.int8]:
        return np.concatenate([tx, rx], axis=1).astype(np.int8)

    def random_super_arms(self, count: int) -> NDArray[np.int8]:
        """``count`` uniformly random valid super arms, (count, M + N)."""
        return random_super_arms(self.rng, count, self.num_tx, self.num_rx, self.tx_count, self.rx_count)


class IndexPolicy(Agent):
    """An agent that plays the super arm maximising ``sum_{(m, n) in A} I[m, n]``.

    Subclasses compute the fused index ``I`` (B, M, N); the pluggable solver picks
    the super arm (SPEC 7).

    Parameters
    ----------
    solver : str or SuperArmSolver
        ``"exact"`` (default for the baselines), ``"bpso"`` or ``"alternating"``.
    solver_params : dict, optional
        Parameters of the solver (``{"population": 50}``...).
    """

    default_solver = "exact"

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(scenario, seed)
        self.solver = make_solver(
            solver or self.default_solver, self.tx_count, self.rx_count, **(solver_params or {})
        )

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        tx, rx = self.solver.solve(self.index(obs), self.rng)
        return self.actions_from_masks(tx, rx)

    @abstractmethod
    def index(self, obs: Observation) -> NDArray[np.float64]:
        """The fused index (B, M, N) for the coming step ``self.t``."""

    def fuse(self, per_target: NDArray[np.float64]) -> NDArray[np.float64]:
        """eq34: ``I[m, n] = sum_k Omega_k I[k, m, n]``."""
        return np.einsum("k,bkmn->bmn", self.weights, per_target)
