"""The receding-horizon tracking oracle: plans the next H steps' super arms, plays the first."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario
from mimo_radar_env.tracking.planning import PLAN_SEARCHES, Planner

from .base import Agent, Observation
from .parameters import check_integer

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
        ``"beam"`` (default), ``"rollout"`` or ``"exhaustive"``.
    width : int
        The beam's width (default 5).
    criterion : str
        ``"trace"`` (m^2) or ``"logdet"``.
    """

    name = "plan-tracking"
    needs_oracle = True
    needs_tracking = True

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        env: Any = None,
        horizon: int = 5,
        search: str = "beam",
        width: int = 5,
        criterion: str = "trace",
    ) -> None:
        super().__init__(scenario, seed)
        check_integer("horizon", horizon, 1, MAX_HORIZON)
        if search not in PLAN_SEARCHES:
            raise ValueError(f"search must be one of {list(PLAN_SEARCHES)}, got {search!r}")
        check_integer("width", width, 1, 10_000)
        self.horizon, self.search, self.width, self.criterion = horizon, search, width, criterion
        sc = self.scenario
        # checks the layout, the search and the criterion now (the fusion is the env's, at attach)
        Planner(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step, search, width, criterion).check_horizon(
            horizon
        )
        self.planner: Planner | None = None
        self._forecast: Any = None
        if env is not None:
            self.attach(env)

    def attach(self, env: Any) -> None:
        """Plan on ``env.tracking_forecast`` (single or vector env), with the env's fusion."""
        target = env if hasattr(env, "tracking_forecast") else getattr(env, "unwrapped", env)
        if not hasattr(target, "tracking_forecast"):
            raise ValueError(
                f"env must be a MimoRadarSelect env (it has tracking_forecast()), got {type(env).__name__}"
            )
        sc = self.scenario
        self.planner = Planner(
            sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step, self.search, self.width, self.criterion,
            target.options.fusion,
        )  # fmt: skip
        self._forecast = target.tracking_forecast

    def memory_per_trial(self) -> int:
        """The plans kept (the beam, or one per super arm for the rollout), each scoring every
        super arm of a step (its 2 x 2 posteriors and their criterion: ``benchmarks.speed.
        policy_cost`` measured about 14 float64 per plan, super arm and target), with its prior and
        the channels' information."""
        sc = self.scenario
        from mimo_radar_env.core.superarm import super_arm_count

        arms = super_arm_count(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        states = arms if self.search == "rollout" else min(self.width, arms ** max(self.horizon - 1, 0))
        channels = sc.num_targets * sc.num_tx * sc.num_rx
        return super().memory_per_trial() + 8 * states * (arms * (8 + 16 * sc.num_targets) + channels * 4 * 4)

    def operations_per_trial_step(self) -> float:
        """Every kept plan extended by every super arm at every planned step."""
        sc = self.scenario
        from mimo_radar_env.core.superarm import super_arm_count

        arms = super_arm_count(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        states = arms if self.search == "rollout" else min(self.width, arms ** max(self.horizon - 1, 0))
        per_arm = sc.num_targets * (8.0 * sc.num_tx * sc.num_rx + 60)
        return super().operations_per_trial_step() + self.horizon * states * arms * per_arm

    def _reset(self, obs: Observation) -> None:
        if self.planner is None:
            raise RuntimeError("the planning oracle needs the env: call agent.attach(env) first")

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        assert self.planner is not None
        tx, rx = self.planner.first_arm(self._forecast(self.horizon))
        return self.actions_from_masks(tx, rx)
