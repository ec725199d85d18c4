"""The one loop that runs an agent on an env.

Every place that runs a policy (the benchmark harness, the speed suite, the demo, the docs'
figures and the tests) goes through it, so they all build the env with what the agent
needs, attach the oracle and run act, step and update the same way, batched over trials::

    agent = agents.make_agent("best-tracking", "paper-1-v1", seed=0)
    env = agents.make_env(agent, num_envs=500, options={"fusion": "centralized"})  # over v1's
    episode = agents.Rollout(agent, env, seed=0)  # resets the env and the agent
    for step in episode.run(100):
        step.info["position_error"]  # (500, K)

A :class:`Rollout` runs on a vector env (actions (B, M + N)) or a single env (the batch of
one: actions (M + N,)) alike.
"""

from __future__ import annotations

import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from numpy.typing import NDArray

from mimo_radar_env import DEFAULT_VERSION, EnvOptions, MimoRadarSelectVectorEnv, Scenario, env_version
from mimo_radar_env.envs.versions import check_scenario_version
from mimo_radar_env.scenarios.scenario import field_differences

from . import base
from .base import Agent, Observation


def env_options_for(agent: Agent, options: EnvOptions | Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The env options ``options`` with those ``agent`` needs for its observation
    (``Agent.needs.observation_options``; they add observation keys and change no number of the env)."""
    given = options.to_dict() if isinstance(options, EnvOptions) else dict(options or {})
    return {**given, **agent.needs.observation_options}


def make_env(
    agent: Agent,
    num_envs: int,
    options: EnvOptions | Mapping[str, Any] | None = None,
    scenario: Scenario | str | Path | None = None,
    version: str = DEFAULT_VERSION,
    device: Any = None,
    device_mode: str = "eager",
) -> MimoRadarSelectVectorEnv:
    """The native vector env of ``num_envs`` trials of ``scenario`` (default: the agent's) with
    the options the agent needs: ``options`` an :class:`~mimo_radar_env.EnvOptions` (as it is) or
    a mapping of options over env version ``version``'s defaults (default: v1's, as
    ``gym.make_vec("MimoRadarSelect-v1", ...)`` has them). ``device`` (``"cuda"``, ``"cpu"``)
    runs it on torch there, the agent acting on its tensors, the step in form ``device_mode``
    (``"eager"``, ``"graph"``, ``"compiled"``: :mod:`mimo_radar_env.envs.device_forms`);
    ``None`` on numpy. Another version's paper scenario by name is refused, as ``gym.make``
    refuses it (its Scenario object is the explicit way to run it under ``version``)."""
    check_scenario_version(scenario, version)
    if options is not None and not isinstance(options, EnvOptions | Mapping):
        given = type(options).__name__
        raise TypeError(f"options must be an EnvOptions or a mapping of env options, got {given}")
    if not isinstance(options, EnvOptions):
        options = env_version(version).options(**(options or {}))
    return MimoRadarSelectVectorEnv(
        num_envs=num_envs,
        scenario=agent.scenario if scenario is None else scenario,
        device=device,
        device_mode=device_mode,
        **env_options_for(agent, options),
    )


def check_same_scenario(made_for: Scenario, runs: Scenario) -> int:
    """Refuses an env whose scenario is not the one the agent was made for (its horizon aside:
    no agent reads it); the env's horizon."""
    differ = [name for name in field_differences(made_for, runs) if name != "horizon"]
    if differ:
        raise ValueError(
            f"the agent was made for scenario {made_for.name!r} and the env runs {runs.name!r}, "
            f"which differ in {', '.join(differ)}; make the agent for the env's scenario "
            "(agents.make_agent(name, env.unwrapped.scenario))"
        )
    return runs.horizon


def check_env_options(agent: Agent, options: EnvOptions) -> None:
    """Refuses an env whose options differ from the agent's parameters named after them."""
    for key, value in agent.env_option_values().items():
        if value != getattr(options, key):
            raise ValueError(
                f"{agent.name} was made with {key}={value!r} and the env runs {key}="
                f"{getattr(options, key)!r}: they must match (make the agent with the env's, "
                f"{key}=env.unwrapped.options.{key})"
            )


@dataclass
class Step:
    """One step of a rollout: the step's number ``t`` (from 1), the action played, what the env
    returned for it, and the agent's ``act`` time (s)."""

    t: int
    action: NDArray[Any]
    obs: Observation
    reward: NDArray[Any]
    terminated: Any
    truncated: Any
    info: dict[str, Any]
    act_seconds: float


class Rollout:
    """An episode of ``agent`` on ``env`` from ``env.reset(seed=seed)``: attaches the env to an
    oracle agent, gives the agent the env's form on torch (``device_mode``), resets both, then
    each :meth:`step` acts, steps the env and updates the agent.

    ``obs`` and ``info`` are the latest the env returned (the reset's until the first step).
    The agent must have been made for the env's scenario (a horizon overridden aside), and the
    rollout ends with the episode: steps past the horizon are refused, not run into the vector
    env's reset."""

    def __init__(self, agent: base.Agent, env: Any, seed: int | None = None) -> None:
        if not isinstance(getattr(getattr(env, "unwrapped", None), "scenario", None), Scenario):
            raise TypeError(
                "env must be a MimoRadarSelect env, single or vector (gym.make, agents.make_env, or "
                f'gym.make_vec with vectorization_mode="vector_entry_point"), got {type(env).__name__}'
            )
        if not isinstance(agent, base.Agent):
            raise TypeError(f"agent must be an agents.Agent (agents.make_agent), got {type(agent).__name__}")
        self.horizon = check_same_scenario(agent.scenario, env.unwrapped.scenario)
        check_env_options(agent, env.unwrapped.options)
        self.agent, self.env = agent, env
        if agent.needs.oracle:
            agent.attach(env)  # type: ignore[attr-defined]
        agent.use_device_mode(getattr(env, "device_mode", "eager"))
        self.obs, self.info = env.reset(seed=seed)
        agent.reset(self.obs)
        self.t = 0

    def step(self) -> Step:
        """Act, step the env, and update the agent with what it returned."""
        if self.t == self.horizon:
            raise RuntimeError(f"the episode ended after its {self.horizon} steps; start a new Rollout")
        start = time.perf_counter()
        action = self.agent.act(self.obs)
        act_seconds = time.perf_counter() - start
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.agent.update(obs, reward)
        self.obs, self.info = obs, info
        self.t += 1
        return Step(self.t, action, obs, reward, terminated, truncated, info, act_seconds)

    def run(self, steps: int) -> Iterator[Step]:
        """The next ``steps`` steps, one at a time, within the episode."""
        if isinstance(steps, bool) or not isinstance(steps, int) or steps < 0:
            raise ValueError(f"steps must be an integer >= 0, got {steps!r}")
        if self.t + steps > self.horizon:
            raise ValueError(
                f"steps must be at most the {self.horizon - self.t} left of the episode "
                f"(horizon {self.horizon}, {self.t} run), got {steps}"
            )
        for _ in range(steps):
            yield self.step()
