"""The Best oracle: the optimal super arm for the true mean SINR of each step."""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario

from .base import Agent, Observation
from .costs import BOOKKEEPING, ORACLE_SEARCH, TRACKING_SEARCH, Needs
from .rollout import check_same_scenario


def oracle_env(agent: Agent, env: Any, method: str) -> Any:
    """The MimoRadarSelect env (single or vector) behind ``env`` that has the truth-reading
    ``method`` (``oracle_action``, ``tracking_oracle_action``, ``tracking_forecast``), for
    ``agent`` to read; ``ValueError`` naming it otherwise, or an env of another scenario than the
    agent's. Records its number of trials, which the agent's reset must have
    (:func:`check_attached`)."""
    target = env if hasattr(env, method) else getattr(env, "unwrapped", env)
    if not hasattr(target, method):
        raise ValueError(f"env must be a MimoRadarSelect env (it has {method}()), got {type(env).__name__}")
    check_same_scenario(agent.scenario, target.scenario)
    agent.oracle_trials = getattr(target, "num_envs", 1)
    return target


def check_attached(agent: Agent, attached: bool, kind: str) -> None:
    """At ``reset``: the oracle agent has an env to read, of as many trials as the observation."""
    if not attached:
        raise RuntimeError(f"the {kind} oracle needs the env: call agent.attach(env) first")
    if agent.batch_size != agent.oracle_trials:
        raise ValueError(
            f"{agent.name} reads the truth of an env of {agent.oracle_trials} trial(s) and was reset on "
            f"{agent.batch_size}: reset it on the observations of the env it is attached to"
        )


class BestAgent(Agent):
    """The Best oracle: the optimal super arm for the true mean SINR of each step.

    It reads the truth, through the ``oracle_action()`` of the env it is attached to
    (:meth:`attach`); it has zero regret by construction.
    """

    name = "best"
    needs = Needs(oracle=True, device=True)
    costs = (BOOKKEEPING, ORACLE_SEARCH)

    def __init__(self, scenario: Scenario | str, seed: int | None = None, env: Any = None) -> None:
        super().__init__(scenario, seed)
        self._oracle: Callable[[], NDArray[np.int8]] | None = None
        self.oracle_trials = 0  # the trials of the env it reads, set by attach
        if env is not None:
            self.attach(env)

    def attach(self, env: Any) -> None:
        """Read the optimal super arm from ``env.oracle_action()`` (single or vector env)."""
        self._oracle = oracle_env(self, env, "oracle_action").oracle_action

    def _reset(self, obs: Observation) -> None:
        check_attached(self, self._oracle is not None, "best")

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        assert self._oracle is not None
        return self.xp.reshape(self.xp.asarray(self._oracle(), dtype=np.int8), (self.batch_size, -1))


class BestTrackingAgent(BestAgent):
    """The tracking oracle: the super arm with the smallest predicted posterior position error.

    Each step it minimises ``sum_k Omega_k trace`` (``criterion="trace"``, m^2) or ``log det``
    (``"logdet"``) of the position block of ``(P_bar^-1 + sum H' R^-1 H)^-1`` over all super arms
    (docs/model.md, section 14): the tracker's one-step prediction, each channel's Jacobian at
    it and the channels' true ``lambda`` (it reads the truth, through the env's
    ``tracking_oracle_action()``). It needs the env's tracker.
    """

    name = "best-tracking"
    needs = Needs(oracle=True, tracking_search=True, device=True)
    costs = (BOOKKEEPING, TRACKING_SEARCH)

    def __init__(
        self, scenario: Scenario | str, seed: int | None = None, env: Any = None, criterion: str = "trace"
    ) -> None:
        from mimo_radar_env.tracking.selection import CRITERIA

        if criterion not in CRITERIA:
            raise ValueError(f"criterion must be one of {list(CRITERIA)}, got {criterion!r}")
        self.criterion = criterion
        super().__init__(scenario, seed, env)

    def attach(self, env: Any) -> None:
        """Read the super arm from ``env.tracking_oracle_action()`` (single or vector env)."""
        target = oracle_env(self, env, "tracking_oracle_action")
        if getattr(target, "options", None) is not None and not target.options.tracking:
            raise ValueError("best-tracking needs the tracker: the env was made with tracking=False")
        self._oracle = functools.partial(target.tracking_oracle_action, self.criterion)  # pickles
