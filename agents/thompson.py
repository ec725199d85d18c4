"""Discounted Thompson sampling with a Gamma posterior, conjugate to exponential SINR samples."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario

from .base import IndexPolicy, Observation
from .costs import BOOKKEEPING, GAMMA_SAMPLER, SOLVER
from .parameters import check_parameter
from .solvers import SuperArmSolver


class CombinatorialThompson(IndexPolicy):
    """CTS, combinatorial Thompson sampling (Wang & Chen, "Thompson sampling for
    combinatorial semi-bandits", ICML 2018), with the Gamma-exponential model of Swerling-I
    SINR.

    Each target and channel has an exponential SINR with unknown rate ``1/S``; its
    conjugate prior is ``Gamma(prior_shape, prior_rate)``. Statistics ``n = discount * n +
    played`` (the base's counts) and ``s = discount * s + played * gamma`` (``n`` times the
    base's mean) give the posterior ``Gamma(prior_shape + n, prior_rate + s)``. Each step one
    rate is drawn per target and channel from its posterior (from the agent's generator); the
    sampled mean SINRs ``1/rate``, fused over targets with eq34, are the index the super-arm
    solver maximises (the exact solver at paper size, ``alternating`` on large arrays), as CTS
    hands one sample per base arm to its oracle. ``discount = 1`` is Wang & Chen's stationary
    CTS; ``discount < 1`` forgets old samples for non-stationary channels.

    Parameters
    ----------
    discount : float, optional
        In (0, 1]; default ``default_discount``: 1 (no forgetting) for ``cts``, 0.99 for
        ``discounted-thompson``.
    prior_shape, prior_rate : float
        Gamma prior of the rate (default 1, 1: prior mean SINR about 1).
    """

    name = "cts"
    costs = (BOOKKEEPING, SOLVER, GAMMA_SAMPLER)
    default_discount = 1.0

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        discount: float | None = None,
        prior_shape: float = 1.0,
        prior_rate: float = 1.0,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(scenario, seed, solver, solver_params)
        discount = self.default_discount if discount is None else discount
        check_parameter("discount", discount, 0.0, 1.0, low_open=True)
        check_parameter("prior_shape", prior_shape, 0.0, low_open=True)
        check_parameter("prior_rate", prior_rate, 0.0, low_open=True)
        self.count_discount, self.prior_shape, self.prior_rate = discount, prior_shape, prior_rate

    def posterior(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Shape and rate (B, K, M, N) of the Gamma posterior of every rate ``1/S``."""
        counts = self.counts[:, None]
        rate = self.prior_rate + counts * self.estimate
        return np.broadcast_to(self.prior_shape + counts, rate.shape), rate

    def posterior_mean_sinr(self) -> NDArray[np.float64]:
        """``E[S] = rate / (shape - 1)`` of the posterior (``inf`` while ``shape <= 1``)."""
        shape, rate = self.posterior()
        with np.errstate(divide="ignore"):
            return np.where(shape > 1, rate / np.maximum(shape - 1, 0.0), np.inf)

    def compute_index(self, predicted: NDArray[np.float64], obs: Observation) -> NDArray[np.float64]:
        """A posterior sample of the mean SINRs, fused (draws from the agent's generator)."""
        shape, rate = self.posterior()
        sampled_rate = self.random.gamma(shape) / rate
        return self.fuse(1.0 / np.maximum(sampled_rate, 1e-300))


class DiscountedThompson(CombinatorialThompson):
    """Discounted Thompson sampling (Raj & Kalyani, "Taming non-stationary bandits: a
    Bayesian approach", 2017): :class:`CombinatorialThompson` with discounted statistics
    by default (``discount`` 0.99, an effective memory of about 100 steps).
    """

    name = "discounted-thompson"
    default_discount = 0.99
