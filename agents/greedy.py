"""Epsilon-greedy, the paper's second baseline."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario
from mimo_radar_env.core.counter_hash import Stream

from .base import IndexPolicy, Observation
from .costs import Needs
from .parameters import check_parameter
from .solvers import SuperArmSolver


class EpsilonGreedy(IndexPolicy):
    """Epsilon-greedy (Section IV): eq29 state; with probability ``epsilon`` a
    uniformly random valid super arm, otherwise the best super arm for the fused
    estimates ``sum_k Omega_k Y_hat[k, m, n]``. Each trial explores independently.

    Parameters
    ----------
    epsilon : float
        Exploration rate (paper 0.1).
    alpha_star : float
        ``alpha_bar*`` of eq29 (paper 0.998).
    """

    name = "epsilon-greedy"
    needs = Needs(device=True)

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        epsilon: float = 0.1,
        alpha_star: float = 0.998,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(scenario, seed, solver, solver_params)
        check_parameter("epsilon", epsilon, 0.0, 1.0)
        check_parameter("alpha_star", alpha_star, 0.0, 1.0)
        self.epsilon, self.alpha_star = epsilon, alpha_star
        self.explored = np.zeros(0, dtype=bool)

    def step_size(self, counts: NDArray[np.float64]) -> float:
        return self.alpha_star  # eq29

    def compute_index(self, predicted: NDArray[np.float64], obs: Observation) -> NDArray[np.float64]:
        return self.fuse(predicted)

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        greedy = super()._act(obs)
        self.explored = self.random.uniform(Stream.AGENT_EXPLORE) < self.epsilon
        return self.xp.where(self.explored[:, None], self.random_super_arms(self.batch_size), greedy)
