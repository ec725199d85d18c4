"""MG-CRB-CL: the paper's multi-group combinatorial-restless-bandit closed-loop policy."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario
from mimo_radar_env.core.arrays import namespace
from mimo_radar_env.core.geometry import path_gain
from mimo_radar_env.core.motion import positions

from .base import IndexPolicy, Observation, blend_samples, ucb_bonus
from .costs import Needs
from .parameters import check_parameter


@dataclass(frozen=True)
class LearningParameters:
    """MG-CRB-CL's estimator parameters, declared here once: MG-CRB-CL, tracking-ucb and the
    learning planner take them as keywords (``make_agent("tracking-ucb", sc, beta=1.0)``).

    Attributes
    ----------
    alpha : float
        Weight of the geometric prediction in eq16 (paper 0.998), in [0, 1].
    alpha_bar : float
        Weight of the new sample in eq14 (paper 0.2), in [0, 1].
    beta : float
        Exploration constant of eq18 (paper 2), >= 0.
    """

    alpha: float = 0.998
    alpha_bar: float = 0.2
    beta: float = 2.0

    def __post_init__(self) -> None:
        check_parameter("alpha", self.alpha, 0.0, 1.0)
        check_parameter("alpha_bar", self.alpha_bar, 0.0, 1.0)
        check_parameter("beta", self.beta, 0.0)


def geometric_prediction(
    estimate: NDArray[np.float64], obs: Observation, scenario: Scenario, alpha: float
) -> NDArray[np.float64]:
    """eq16: ``Y_bar = alpha L(X_bar) / L(X_hat) Y_hat + (1 - alpha) Y_hat`` from the tracker's
    estimate (``track``) and prediction (``track_pred``); the RCS ratio is 1."""
    xp = namespace(estimate)
    tx, rx = xp.asarray(scenario.tx_positions), xp.asarray(scenario.rx_positions)
    ratio = path_gain(positions(obs["track_pred"]), tx, rx) / path_gain(positions(obs["track"]), tx, rx)
    return alpha * ratio * estimate + (1.0 - alpha) * estimate


class MGCRBCLEstimator:
    """MG-CRB-CL's SINR learning as a component (for policies that select otherwise).

    The same estimates as :class:`MGCRBCL`: ``reset`` from the reset observation (every
    channel probed once), :meth:`predict` (eq16) before a step, :meth:`optimistic` (eq18,
    per target) for it, :meth:`update` (eq15's counts, eq14's blend) after it.
    """

    def __init__(self, scenario: Scenario, parameters: LearningParameters | None = None) -> None:
        self.scenario = scenario
        self.parameters = parameters or LearningParameters()
        self.alpha, self.alpha_bar, self.beta = dataclasses.astuple(self.parameters)

    def reset(self, obs: Observation) -> None:
        xp = namespace(obs["sinr"])
        self.estimate = xp.astype(xp.copy(obs["sinr"]), np.float64)  # Y_hat(0)
        self.counts = xp.astype(xp.copy(obs["probed"]), np.float64)  # d(0)
        self.predicted = self.estimate

    def predict(self, obs: Observation) -> NDArray[np.float64]:
        """``Y_bar(t)`` (eq16), kept for the update."""
        self.predicted = geometric_prediction(self.estimate, obs, self.scenario, self.alpha)
        return self.predicted

    def optimistic(self, t: int) -> NDArray[np.float64]:
        """``Y_up = Y_bar + sqrt(beta ln t / d)`` per target (eq18), (B, K, M, N)."""
        return self.predicted + ucb_bonus(self.beta, t, self.counts)[:, None]

    def update(self, obs: Observation) -> None:
        xp = namespace(obs["sinr"])
        played = xp.astype(obs["probed"], bool)
        self.counts = self.counts + played  # eq15
        sample = xp.astype(obs["sinr"], np.float64)
        self.estimate = blend_samples(self.predicted, played, sample, self.alpha_bar)


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
    alpha, alpha_bar, beta : float
        The estimator's parameters (:class:`LearningParameters`: eq16's weight 0.998, eq14's
        step 0.2, eq18's exploration constant 2).
    solver, solver_params, seed : see :class:`~agents.base.IndexPolicy`.
    """

    name = "mg-crb-cl"
    default_solver = "bpso"
    needs = Needs(tracking=True, device=True)
    keyword_parameters = LearningParameters
    parameters: LearningParameters

    def predict(self, obs: Observation) -> NDArray[np.float64]:
        """eq16 from the tracker's estimate and prediction."""
        return geometric_prediction(self.estimate, obs, self.scenario, self.parameters.alpha)

    def step_size(self, counts: NDArray[np.float64]) -> float:
        return self.parameters.alpha_bar  # eq14

    def compute_index(self, predicted: NDArray[np.float64], obs: Observation) -> NDArray[np.float64]:
        return self.fuse(predicted + self.bonus(self.parameters.beta)[:, None])  # eq18, eq34
