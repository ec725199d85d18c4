"""The planning agents: one step ahead they are best-tracking and tracking-ucb, and their parameters
are checked with their ranges."""

import numpy as np
import pytest

import agents
from mimo_radar_env import MimoRadarSelectVectorEnv
from mimo_radar_env.tracking.planning import Planner


@pytest.mark.parametrize("fusion", ["centralized", "average"])
def test_planning_one_step_ahead_is_best_tracking(fusion):
    env = MimoRadarSelectVectorEnv(num_envs=6, scenario="paper-1-v1", fusion=fusion)
    obs, _ = env.reset(seed=2)
    planners = [
        agents.make_agent(name, "paper-1-v1", horizon=1)
        for name in ("plan-tracking", "plan-tracking-rollout", "plan-tracking-mcts")
    ]
    for planner in planners:
        planner.attach(env)
        planner.reset(obs)
    for _ in range(25):
        expected = env.tracking_oracle_action()
        for planner in planners:
            np.testing.assert_array_equal(planner.act(obs), expected)
        obs, *_ = env.step(expected)


def test_bad_planning_parameters_are_refused_naming_the_range():
    with pytest.raises(
        ValueError, match=r"search must be one of \['beam', 'rollout', 'mcts', 'exhaustive'\]"
    ):
        agents.make_agent("plan-tracking", "paper-1-v1", search="dp")
    with pytest.raises(ValueError, match=r"simulations must be an integer in \[1, 100000\]"):
        agents.make_agent("plan-tracking-mcts", "paper-1-v1", simulations=0)
    with pytest.raises(ValueError, match="horizon must be"):
        agents.make_agent("plan-tracking", "paper-1-v1", horizon=0)
    with pytest.raises(ValueError, match="exhaustive search scores 120\\^4 sequences"):
        agents.make_agent("plan-tracking", "paper-1-v1", horizon=4, search="exhaustive")
    with pytest.raises(ValueError, match="planning scores every super arm"):
        Planner(16, 16, 4, 4)
    with pytest.raises(ValueError, match="width must be an integer"):
        Planner(4, 6, 2, 3, width=0)


@pytest.mark.parametrize("fusion", ["centralized", "average"])
def test_the_learning_planner_one_step_ahead_is_tracking_ucb(fusion):
    """plan-tracking-ucb reads no truth: its H = 1 plays tracking-ucb's super arms exactly, and
    a longer horizon plays valid ones from the same estimates."""
    env = MimoRadarSelectVectorEnv(
        num_envs=5, scenario="paper-2-v1", fusion=fusion, prediction_covariance=True
    )
    obs, _ = env.reset(seed=4)
    learner = agents.make_agent("tracking-ucb", "paper-2-v1", fusion=fusion)
    planner = agents.make_agent("plan-tracking-ucb", "paper-2-v1", horizon=1, fusion=fusion)
    ahead = agents.make_agent("plan-tracking-ucb", "paper-2-v1", horizon=4, fusion=fusion)
    for agent in (learner, planner, ahead):
        agent.reset(obs)
    for _ in range(20):
        action = learner.act(obs)
        np.testing.assert_array_equal(planner.act(obs), action)
        longer = ahead.act(obs)
        assert (longer[:, :4].sum(1) == 2).all() and (longer[:, 4:].sum(1) == 3).all()
        obs, reward, *_ = env.step(action)
        for agent in (learner, planner, ahead):
            agent.update(obs, reward)
    assert not hasattr(ahead, "_forecast")  # no truth: it was never attached to an env
