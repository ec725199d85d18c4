"""Discounted Thompson sampling with a Gamma posterior, conjugate to exponential SINR samples."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario

from .base import IndexPolicy, Observation, check_parameter
from .solvers import SuperArmSolver


class DiscountedThompson(IndexPolicy):
    """Discounted Thompson sampling (Raj & Kalyani, "Taming non-stationary bandits:
    a Bayesian approach", 2017), with the Gamma-exponential model of Swerling-I SINR.

    Each target and channel has an exponential SINR with unknown rate ``1/S``; its
    conjugate prior is ``Gamma(prior_shape, prior_rate)``. Discounted statistics
    ``n = discount * n + played`` (the base's counts) and ``s = discount * s + played *
    gamma`` (``n`` times the base's discounted mean) give the posterior
    ``Gamma(prior_shape + n, prior_rate + s)``; each step a rate is drawn per target and
    channel, the sampled mean SINR is its inverse, fused over targets with eq34 and handed
    to the solver.

    Parameters
    ----------
    discount : float
        In (0, 1] (default 0.99).
    prior_shape, prior_rate : float
        Gamma prior of the rate (default 1, 1: prior mean SINR about 1).
    """

    name = "discounted-thompson"

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        discount: float = 0.99,
        prior_shape: float = 1.0,
        prior_rate: float = 1.0,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(scenario, seed, solver, solver_params)
        check_parameter("discount", discount, 0.0, 1.0, low_open=True)
        check_parameter("prior_shape", prior_shape, 0.0, low_open=True)
        check_parameter("prior_rate", prior_rate, 0.0, low_open=True)
        self.count_discount, self.prior_shape, self.prior_rate = discount, prior_shape, prior_rate

    def posterior(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Shape and rate (B, K, M, N) of the Gamma posterior of every rate ``1/S``."""
        counts = self.counts[:, None]
        return self.prior_shape + counts, self.prior_rate + counts * self.estimate

    def compute_index(self, predicted: NDArray[np.float64], obs: Observation) -> NDArray[np.float64]:
        """A posterior sample of the mean SINRs, fused (draws from the agent's generator)."""
        shape, rate = self.posterior()
        sampled_rate = self.rng.gamma(shape, 1.0 / rate)
        return self.fuse(1.0 / np.maximum(sampled_rate, 1e-300))
