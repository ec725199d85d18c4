"""The receding-horizon tracking oracle: plans the next H steps' super arms, plays the first."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario
from mimo_radar_env.core.geometry import path_gain
from mimo_radar_env.core.motion import positions, transition_matrix
from mimo_radar_env.tracking.fusion import DEFAULT_FUSION
from mimo_radar_env.tracking.information import channel_information
from mimo_radar_env.tracking.planning import PLAN_SEARCHES, Forecast, Planner

from .base import Agent, Observation, ucb_bonus
from .costs import BOOKKEEPING, PLAN, TRACKING_SEARCH, Needs
from .oracle import check_attached, oracle_env
from .parameters import check_integer
from .tracking import TrackingUCB

#: The longest plan the oracle looks at.
MAX_HORIZON = 50


class PlanTrackingAgent(Agent):
    """The receding-horizon tracking oracle: the super arm that starts the plan of the next
    ``horizon`` steps with the smallest summed predicted posterior position error.

    Each step it reads the env's forecast (``tracking_forecast(horizon)``: the tracker's
    predicted covariance, and every channel's information along the predicted track with its
    true ``lambda`` along the truth), searches plans with
    :class:`~mimo_radar_env.tracking.planning.Planner` and plays the first super arm of the
    cheapest (docs/agents.md). ``horizon=1`` is best-tracking. It reads the truth and needs the
    env's tracker.

    Parameters
    ----------
    horizon : int
        H, the steps planned (default 5).
    search : str
        ``"beam"`` (default), ``"rollout"``, ``"mcts"`` or ``"exhaustive"``.
    width : int
        The beam's width (default 5).
    criterion : str
        ``"trace"`` (m^2) or ``"logdet"``.
    simulations, candidates : int
        MCTS's budget per step (default 64) and the children of each node (default 8).
    """

    name = "plan-tracking"
    # a plan's first step is scored by the tracking search
    needs = Needs(oracle=True, tracking=True, tracking_search=True)
    costs = (BOOKKEEPING, PLAN)

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        env: Any = None,
        horizon: int = 5,
        search: str = "beam",
        width: int = 5,
        criterion: str = "trace",
        simulations: int = 64,
        candidates: int = 8,
    ) -> None:
        super().__init__(scenario, seed)
        check_integer("horizon", horizon, 1, MAX_HORIZON)
        if search not in PLAN_SEARCHES:
            raise ValueError(f"search must be one of {list(PLAN_SEARCHES)}, got {search!r}")
        check_integer("width", width, 1, 10_000)
        self.horizon, self.search, self.width, self.criterion = horizon, search, width, criterion
        self.simulations, self.candidates = simulations, candidates
        # checks the layout, the search and its parameters now (the fusion is the env's, at attach)
        self._planner(DEFAULT_FUSION).check_horizon(horizon)
        self.planner: Planner | None = None
        self._forecast: Any = None
        self.oracle_trials = 0  # the trials of the env it reads, set by attach
        if env is not None:
            self.attach(env)

    def attach(self, env: Any) -> None:
        """Plan on ``env.tracking_forecast`` (single or vector env), with the env's fusion."""
        target = oracle_env(self, env, "tracking_forecast")
        self.planner = self._planner(target.options.fusion)
        self._forecast = target.tracking_forecast

    def _planner(self, fusion: str) -> Planner:
        sc = self.scenario
        return Planner(
            sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step, self.search, self.width, self.criterion,
            fusion, self.simulations, self.candidates,
        )  # fmt: skip

    def _reset(self, obs: Observation) -> None:
        check_attached(self, self.planner is not None, "planning")

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        assert self.planner is not None
        tx, rx = self.planner.first_arm(self._forecast(self.horizon))
        return self.actions_from_masks(tx, rx)


class PlanTrackingUCB(TrackingUCB):
    """The learning planner: tracking-ucb's estimates, planned ``horizon`` steps ahead; it reads
    no truth.

    Each step it carries MG-CRB-CL's eq16 along the tracker's prediction, extended by the
    constant-velocity model (``Y_bar(t + h) = alpha L(X_bar(t + h)) / L(X_hat) Y_hat +
    (1 - alpha) Y_hat``), adds eq18's optimism, maps it with eq32 to ``lambda_hat`` and plans the
    next ``horizon`` steps from the tracker's predicted covariance (observation
    ``track_pred_cov``) as :class:`PlanTrackingAgent` does with the truth; it plays the first
    super arm of the cheapest plan. ``horizon=1`` is tracking-ucb (``sinr_weight`` 0).

    Parameters
    ----------
    horizon, search, width, simulations, candidates
        As :class:`PlanTrackingAgent` (default 5, ``"beam"``, 5, 64, 8).
    alpha, alpha_bar, beta, criterion, fusion, lambda_scale, measurement_quality
        As :class:`~agents.tracking.TrackingUCB` (the harness passes the env's fusion, scale
        and quality).
    """

    name = "plan-tracking-ucb"
    needs = dataclasses.replace(TrackingUCB.needs, device=False)  # the planner is numpy's
    costs = (BOOKKEEPING, TRACKING_SEARCH, PLAN)

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        horizon: int = 5,
        search: str = "beam",
        width: int = 5,
        simulations: int = 64,
        candidates: int = 8,
        criterion: str = "trace",
        fusion: str = DEFAULT_FUSION,
        lambda_scale: str = "db",
        measurement_quality: float | None = None,
        **learning: float,
    ) -> None:
        super().__init__(
            scenario, seed, criterion, fusion, lambda_scale, 0.0, measurement_quality, **learning
        )
        check_integer("horizon", horizon, 1, MAX_HORIZON)
        sc = self.scenario
        self.horizon, self.search, self.width, self.simulations = horizon, search, width, simulations
        self.planner = Planner(
            sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step, search, width, criterion, fusion,
            simulations, candidates,
        )  # fmt: skip
        self.planner.check_horizon(horizon)
        self.transition = transition_matrix(0.0, sc.sample_time)

    def forecast(self, obs: Observation) -> Forecast:
        """The plan's inputs from the observation and the learnt estimates alone."""
        sc = self.scenario
        predicted = [np.asarray(obs["track_pred"], dtype=np.float64)]
        for _ in range(1, self.horizon):
            predicted.append(predicted[-1] @ self.transition.T)
        planned = positions(np.stack(predicted, axis=1))  # (B, H, K, 2)
        estimate = self.learning.estimate[:, None]  # Y_hat(t-1), (B, 1, K, M, N)
        now = path_gain(positions(np.asarray(obs["track"])), sc.tx_positions, sc.rx_positions)[:, None]
        ahead = path_gain(planned, sc.tx_positions, sc.rx_positions)
        alpha = self.learning.alpha
        sinr = alpha * ahead / now * estimate + (1.0 - alpha) * estimate  # eq16 along the plan
        optimistic = sinr + ucb_bonus(self.learning.beta, self.t, self.learning.counts)[:, None, None]  # eq18
        return Forecast(
            covariance=np.asarray(obs["track_pred_cov"], dtype=np.float64),
            information=channel_information(
                planned,
                sc.tx_positions,
                sc.rx_positions,
                self.selector.variance(optimistic),  # eq32
            ),
            transition=self.transition,
            process_cov=self.selector.model.process_cov,
            weights=np.asarray(sc.weights, dtype=np.float64),
        )

    def _reset(self, obs: Observation) -> None:
        if "track_pred_cov" not in obs:
            raise ValueError(
                f"{self.name} plans from the tracker's predicted covariance: make the env with "
                "prediction_covariance=True"
            )
        super()._reset(obs)

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        self.learning.predict(obs)  # eq16 for the coming step, kept for the update
        tx, rx = self.planner.first_arm(self.forecast(obs))
        return self.actions_from_masks(tx, rx)
