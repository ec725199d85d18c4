"""best: the optimal super arm of each step, so zero regret; the oracles read the truth of the
env they act on, and no other."""

import gymnasium as gym
import numpy as np
import pytest

import agents
from tests.helpers import vector_env


def test_best_has_zero_regret():
    venv = vector_env("MimoRadarSelect-v0", 8, scenario="paper-3")
    best = agents.make_agent("best", venv.scenario, env=venv)
    obs, _ = venv.reset(seed=0)
    best.reset(obs)
    for _ in range(50):
        obs, reward, _, _, info = venv.step(best.act(obs))
        np.testing.assert_allclose(info["expected_reward"], info["optimal_reward"], rtol=1e-12)


@pytest.mark.parametrize("policy", ["best", "best-tracking", "plan-tracking"])
def test_an_oracle_refuses_an_env_of_another_scenario_or_batch_than_it_acts_on(policy):
    """Attached to an env of another scenario, an oracle read that env's truth for the agent's;
    reset on 3 trials while attached to 2, it failed in a reshape (best) or acted on the 2."""
    other = vector_env("MimoRadarSelect-v1", 2, scenario="paper-2-v1")
    with pytest.raises(ValueError, match=r"made for scenario 'paper-1-v1' and the env runs 'paper-2-v1'"):
        agents.make_agent(policy, "paper-1-v1", env=other)
    oracle = agents.make_agent(policy, "paper-1-v1", env=vector_env("MimoRadarSelect-v1", 2))
    three, _ = vector_env("MimoRadarSelect-v1", 3).reset(seed=0)
    reads = rf"{policy} reads the truth of an env of 2 trial\(s\) and was reset on 3"
    with pytest.raises(ValueError, match=reads):
        oracle.reset(three)
    single = gym.make("MimoRadarSelect-v1")
    oracle.attach(single)  # the single env is one trial
    obs, _ = single.reset(seed=0)
    oracle.reset(obs)
    assert single.step(oracle.act(obs))[4]["action_valid"]
