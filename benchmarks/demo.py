"""A short demo: one episode of a scenario with a random policy and the oracle."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import agents
from mimo_radar_env import DEFAULT_VERSION, VERSIONS

#: The demo's policies and their labels: uniformly random valid super arms, and the oracle of
#: the true mean SINR.
POLICIES = {"random": "random", "best": "best (oracle)"}


def run_demo(
    scenario: str = VERSIONS[DEFAULT_VERSION].default_scenario, seed: int = 0, steps: int | None = None
) -> dict[str, dict[str, float]]:
    """Run one episode per policy (same seed, so the same target trajectory) and summarise it."""
    results: dict[str, dict[str, float]] = {}
    for policy in POLICIES:
        env = gym.make(VERSIONS[DEFAULT_VERSION].env_id, scenario=scenario)
        sc = env.unwrapped.scenario
        horizon = sc.horizon if steps is None else min(steps, sc.horizon)
        episode = agents.Rollout(agents.make_agent(policy, sc, seed=seed), env, seed=seed)
        regret, errors, reward_sum = 0.0, [], 0.0
        for step in episode.run(horizon):
            reward_sum += float(step.reward)
            regret += step.info["optimal_reward"] - step.info["expected_reward"]
            errors.append(step.info["position_error"])
        results[policy] = {
            "steps": horizon,
            "total_reward": reward_sum,
            "final_regret": float(f"{regret:.1f}") + 0.0,  # the oracle's rounding is no "-0.0"
            "mean_position_error_m": float(np.mean(errors)),
        }
    return results


def print_demo(results: dict[str, dict[str, float]], scenario: str) -> None:
    env_id = VERSIONS[DEFAULT_VERSION].env_id
    print(f"{env_id}, scenario {scenario}: one episode per policy, same target trajectory")
    print(f"{'policy':<14}{'steps':>7}{'total reward':>15}{'regret':>12}{'mean pos. error (m)':>22}")
    for name, row in results.items():
        label = POLICIES.get(name, name)
        print(
            f"{label:<14}{row['steps']:>7d}{row['total_reward']:>15.1f}{row['final_regret']:>12.1f}"
            f"{row['mean_position_error_m']:>22.2f}"
        )
