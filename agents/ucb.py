"""UCB-family index policies: the paper's UCB1, CUCB, discounted and sliding-window UCB."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario
from mimo_radar_env.scenarios import MAX_HORIZON

from .base import IndexPolicy, Observation
from .costs import Needs
from .parameters import check_integer, check_parameter
from .solvers import SuperArmSolver

#: Index of an arm with no sample in the window: finite, larger than any SINR index.
UNEXPLORED_INDEX = 1e6


class UCB1(IndexPolicy):
    """The paper's UCB1 baseline (Section IV, eq29).

    State ``Y_hat[k, m, n]`` and counts ``d[m, n]`` from the reset probe. Played
    channels: ``Y_hat = (1 - alpha_star) Y_hat + alpha_star gamma`` (eq29), others
    frozen; index ``Y_hat + sqrt(beta ln t / d)`` fused over targets with eq34.

    Parameters
    ----------
    alpha_star : float
        ``alpha_bar*`` of eq29 (paper 0.998).
    beta : float
        Exploration constant (paper 2).
    """

    name = "ucb1"
    needs = Needs(device=True)

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        alpha_star: float = 0.998,
        beta: float = 2.0,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(scenario, seed, solver, solver_params)
        check_parameter("alpha_star", alpha_star, 0.0, 1.0)
        check_parameter("beta", beta, 0.0)
        self.alpha_star, self.beta = alpha_star, beta

    def step_size(self, counts: NDArray[np.float64]) -> float:
        return self.alpha_star  # eq29

    def compute_index(self, predicted: NDArray[np.float64], obs: Observation) -> NDArray[np.float64]:
        return self.fuse(predicted + self.bonus(self.beta)[:, None])


class CUCB(IndexPolicy):
    """CUCB (Chen, Wang, Yuan & Wang, "Combinatorial multi-armed bandit and its
    extension to probabilistically triggered arms", JMLR 2016).

    Base arms are the channels; the estimate is the sample mean of all SINR samples
    (stationary assumption), the index ``mean + scale * sqrt(3 ln t / (2 T_i))``
    (rewards are not in [0, 1] here, hence ``scale``), and the oracle is the solver.

    Parameters
    ----------
    scale : float
        Multiplies the confidence radius (default 1).
    """

    name = "cucb"
    needs = Needs(device=True)

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        scale: float = 1.0,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(scenario, seed, solver, solver_params)
        check_parameter("scale", scale, 0.0)
        self.scale = scale

    def compute_index(self, predicted: NDArray[np.float64], obs: Observation) -> NDArray[np.float64]:
        return self.fuse(predicted + self.scale * self.bonus(1.5)[:, None])


class DiscountedUCB(IndexPolicy):
    """Discounted UCB (Garivier & Moulines, "On upper-confidence bound policies for
    switching bandit problems", ALT 2011).

    Discounted counts ``N = sum_s discount^(t-s) 1[played]`` and the discounted mean of
    the samples (the base's sample mean with discounted counts); the index is
    ``mean + sqrt(beta ln(n) / N)`` with ``n`` the sum of ``N`` over channels (their
    ``2B sqrt(xi log n / N)`` with the paper's UCB1 exploration constant ``beta`` in place
    of ``4 B^2 xi``, rewards being unbounded SINRs).

    Parameters
    ----------
    discount : float
        ``gamma`` in (0, 1] (default 0.99: an effective memory of about 100 steps).
    beta : float
        Exploration constant (default 2).
    """

    name = "discounted-ucb"
    needs = Needs(device=True)

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        discount: float = 0.99,
        beta: float = 2.0,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(scenario, seed, solver, solver_params)
        check_parameter("discount", discount, 0.0, 1.0, low_open=True)
        check_parameter("beta", beta, 0.0)
        self.count_discount, self.beta = discount, beta

    def compute_index(self, predicted: NDArray[np.float64], obs: Observation) -> NDArray[np.float64]:
        xp = self.xp
        total = xp.maximum(xp.sum(self.counts, axis=(1, 2), keepdims=True), np.e)
        bonus = xp.sqrt(self.beta * xp.log(total) / self.counts)
        return self.fuse(predicted + bonus[:, None])


class SlidingWindowUCB(IndexPolicy):
    """Sliding-window UCB (Garivier & Moulines, ALT 2011).

    Means and counts over the last ``window`` steps only; index
    ``mean + sqrt(beta ln(min(t, window)) / N)``. A channel without a sample in the
    window gets the index ``UNEXPLORED_INDEX`` (1e6) so that it is probed next.
    Memory: a ring buffer of (B, window, K, M, N) samples.

    Parameters
    ----------
    window : int
        ``tau`` (default 100 steps).
    beta : float
        Exploration constant (default 2).
    """

    name = "sliding-window-ucb"
    needs = Needs(device=True)

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        window: int = 100,
        beta: float = 2.0,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(scenario, seed, solver, solver_params)
        check_integer("window", window, 1, MAX_HORIZON)  # a longer window never forgets a step
        check_parameter("beta", beta, 0.0)
        self.window, self.beta = int(window), beta

    def _reset(self, obs: Observation) -> None:
        xp = self.xp
        sinr = xp.astype(obs["sinr"], np.float64)
        self.samples = xp.zeros((sinr.shape[0], self.window) + tuple(sinr.shape[1:]))
        self.played = xp.zeros((sinr.shape[0], self.window) + tuple(sinr.shape[2:]))
        self.slot = 0
        self._store(obs)

    def _store(self, obs: Observation) -> None:
        """The step's samples into the ring buffer; counts and means over the window."""
        xp = self.xp
        played = xp.astype(obs["probed"], np.float64)
        self.samples[:, self.slot] = obs["sinr"] * played[:, None]
        self.played[:, self.slot] = played
        self.slot = (self.slot + 1) % self.window
        self.counts = self.played.sum(axis=1)
        self.estimate = self.samples.sum(axis=1) / xp.maximum(self.counts, 1.0)[:, None]
        self.predicted = self.estimate

    def compute_index(self, predicted: NDArray[np.float64], obs: Observation) -> NDArray[np.float64]:
        xp = self.xp
        safe = xp.maximum(self.counts, 1.0)
        bonus = xp.sqrt(self.beta * np.log(max(min(self.t, self.window), 1)) / safe)
        fused = self.fuse(predicted + bonus[:, None])
        return xp.where(self.counts > 0, fused, UNEXPLORED_INDEX)

    def _update(self, obs: Observation, reward: NDArray[np.float64]) -> None:
        self._store(obs)
