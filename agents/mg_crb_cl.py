"""MG-CRB-CL: the paper's multi-group combinatorial-restless-bandit closed-loop policy."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario
from mimo_radar_env.core.geometry import path_gain

from .base import IndexPolicy, Observation, check_parameter
from .solvers import SuperArmSolver


class MGCRBCL(IndexPolicy):
    """MG-CRB-CL (Algorithm 1; eq14, eq15, eq16, eq18, eq34).

    State: the SINR estimates ``Y_hat[k, m, n]`` of every target on every channel
    and the play counts ``d[m, n]``, both initialised by the reset observation, in
    which every channel is probed once. Before each step ``t``:

    * eq16: ``Y_bar(t) = alpha * L(X_bar_t) / L(X_hat_{t-1}) * Y_hat(t-1) + (1 - alpha) * Y_hat(t-1)``
      with ``L = (R_tx R_rx)^-2`` evaluated at the tracker's fused estimate
      ``X_hat_{t-1}`` (observation ``"track"``) and one-step prediction ``X_bar_t``
      (``"track_pred"``, eq24); the RCS ratio is 1 (constant ``psi``);
    * eq18: ``I[k, m, n] = Y_bar(t) + sqrt(beta ln t / d[m, n])``;
    * eq34: ``I[m, n] = sum_k Omega_k I[k, m, n]``; the solver (BPSO by default, as
      in the paper) picks the super arm.

    After the step, eq14: played channels ``Y_hat(t) = (1 - alpha_bar) Y_bar(t) +
    alpha_bar gamma(t)``, the others ``Y_hat(t) = Y_bar(t)``; eq15: ``d += 1`` for
    played channels.

    Parameters
    ----------
    alpha : float
        Weight of the geometric prediction in eq16 (paper 0.998).
    alpha_bar : float
        Weight of the new sample in eq14 (paper 0.2).
    beta : float
        Exploration constant of eq18 (paper 2).
    solver, solver_params, seed : see :class:`~agents.base.IndexPolicy`.
    """

    name = "mg-crb-cl"
    default_solver = "bpso"

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        alpha: float = 0.998,
        alpha_bar: float = 0.2,
        beta: float = 2.0,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
    ) -> None:
        super().__init__(scenario, seed, solver, solver_params)
        check_parameter("alpha", alpha, 0.0, 1.0)
        check_parameter("alpha_bar", alpha_bar, 0.0, 1.0)
        check_parameter("beta", beta, 0.0)
        self.alpha, self.alpha_bar, self.beta = alpha, alpha_bar, beta
        self.tx = self.scenario.tx_positions
        self.rx = self.scenario.rx_positions

    def _reset(self, obs: Observation) -> None:
        if "track" not in obs or "track_pred" not in obs:
            raise ValueError(
                "mg-crb-cl predicts the SINR from the tracker's estimates (eq16): "
                "make the env with tracking=True"
            )
        self.estimate = np.array(obs["sinr"], dtype=np.float64)  # Y_hat(0)
        self.counts = np.array(obs["probed"], dtype=np.float64)  # d(0)
        self.predicted = self.estimate

    def path_gain(self, states: NDArray[np.float64]) -> NDArray[np.float64]:
        """``L = (R_tx R_rx)^-2`` for states (B, K, 4): (B, K, M, N)."""
        return path_gain(states[..., [0, 2]], self.tx, self.rx)

    def index(self, obs: Observation) -> NDArray[np.float64]:
        ratio = self.path_gain(obs["track_pred"]) / self.path_gain(obs["track"])
        self.predicted = self.alpha * ratio * self.estimate + (1.0 - self.alpha) * self.estimate  # eq16
        bonus = np.sqrt(self.beta * np.log(self.t) / self.counts)  # eq18
        return self.fuse(self.predicted + bonus[:, None])  # eq34

    def _update(self, obs: Observation, reward: NDArray[np.float64]) -> None:
        played = np.asarray(obs["probed"], dtype=bool)
        sample = np.asarray(obs["sinr"], dtype=np.float64)
        blended = (1.0 - self.alpha_bar) * self.predicted + self.alpha_bar * sample
        self.estimate = np.where(played[:, None], blended, self.predicted)  # eq14
        self.counts = self.counts + played  # eq15
