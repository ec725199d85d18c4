"""RBE: recency-based exploration for restless arms (Oksanen & Koivunen 2012)."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario

from .base import IndexPolicy, Observation
from .parameters import check_parameter
from .solvers import SuperArmSolver

#: Index of a channel never probed: finite (the solvers take finite indices) and larger than any
#: sum of SINR indices, so a super arm with more unprobed channels is preferred.
UNPROBED_INDEX = 1e6

Estimate = Literal["eq29", "last", "mean"]
ESTIMATES: tuple[str, ...] = ("eq29", "last", "mean")


class RecencyBasedExploration(IndexPolicy):
    """RBE, recency-based exploration (Oksanen & Koivunen, "An order optimal policy for
    exploiting idle spectrum in cognitive radio networks", IEEE TSP 2015 / CISS 2012; as used
    for restless arms in Pulkkinen et al.'s combinatorial bandits for distributed MIMO radar).

    Per target and channel, ``I[k, m, n] = Y_hat[k, m, n] + sqrt(log(c / c_last[m, n]))``,
    fused over targets with eq34's weights and maximised by the super-arm solver. ``c`` counts
    time from the reset probe (``c = 1``; the agent's decision ``t`` is at ``c = t + 1``) and
    ``c_last`` is when the channel was last probed: the bonus is 0 for a channel probed at the
    last step and grows, without bound, while a channel is not probed. A channel never probed
    has the index ``UNPROBED_INDEX`` (1e6; the reset probe normally probes every channel).

    Parameters
    ----------
    estimate : {"eq29", "last", "mean"}
        The SINR estimate ``Y_hat``: eq29's exponential smoothing with ``alpha_star``
        (default), the last sample, or the sample mean.
    alpha_star : float
        ``alpha_bar*`` of eq29 (default 0.998, the paper's UCB1 value).
    """

    name = "rbe"

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        estimate: Estimate = "eq29",
        alpha_star: float = 0.998,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(scenario, seed, solver, solver_params)
        if estimate not in ESTIMATES:
            raise ValueError(f"estimate must be one of {list(ESTIMATES)}, got {estimate!r}")
        check_parameter("alpha_star", alpha_star, 0.0, 1.0)
        self.estimate_rule, self.alpha_star = estimate, alpha_star

    def _reset(self, obs: Observation) -> None:
        super()._reset(obs)
        # the reset probe is at c = 1; 0 marks a channel never probed
        self.last_probed = np.where(np.asarray(obs["probed"]) > 0, 1.0, 0.0)

    def step_size(self, counts: NDArray[np.float64]) -> float | NDArray[np.float64]:
        if self.estimate_rule == "eq29":
            return self.alpha_star
        if self.estimate_rule == "last":
            return 1.0
        return super().step_size(counts)  # the sample mean

    def recency_bonus(self) -> NDArray[np.float64]:
        """``sqrt(log(c / c_last))`` (B, M, N) for the coming decision; ``inf`` where never probed."""
        now = self.t + 1.0
        with np.errstate(divide="ignore"):
            return np.sqrt(np.log(now / self.last_probed))

    def compute_index(self, predicted: NDArray[np.float64], obs: Observation) -> NDArray[np.float64]:
        bonus = self.recency_bonus()
        fused = self.fuse(predicted + np.where(np.isfinite(bonus), bonus, 0.0)[:, None])
        return np.where(np.isfinite(bonus), fused, UNPROBED_INDEX)

    def _update(self, obs: Observation, reward: NDArray[np.float64]) -> None:
        super()._update(obs, reward)
        self.last_probed = np.where(np.asarray(obs["probed"]) > 0, self.t + 1.0, self.last_probed)
