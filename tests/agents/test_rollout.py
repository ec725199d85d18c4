"""The one rollout loop: the same steps as act/step/update written out, on vector and single
envs, with the agent's observation options and its oracle attached."""

import gymnasium as gym
import numpy as np
import pytest

import agents
from mimo_radar_env import VERSIONS, MimoRadarSelectVectorEnv


def _centralized(policy):
    """The agent's parameters named after env options, set to the env's centralised fusion."""
    return {"fusion": "centralized"} if "fusion" in agents.agent_class(policy).needs.env_option_params else {}


def _by_hand(policy, env, seed, steps):
    """The loop as every caller used to write it."""
    agent = agents.make_agent(policy, "paper-1-v1", seed=5, **_centralized(policy))
    if agent.needs.oracle:
        agent.attach(env)
    obs, _ = env.reset(seed=seed)
    agent.reset(obs)
    actions, rewards = [], []
    for _ in range(steps):
        action = agent.act(obs)
        obs, reward, _, _, _ = env.step(action)
        agent.update(obs, reward)
        actions.append(action)
        rewards.append(reward)
    return np.array(actions), np.array(rewards)


@pytest.mark.parametrize("policy", ["mg-crb-cl", "best", "tracking-ucb"])
def test_a_rollout_is_the_loop_written_out(policy):
    agent = agents.make_agent(policy, "paper-1-v1", seed=5, **_centralized(policy))
    env = agents.make_env(agent, 4, {"fusion": "centralized"})
    assert env.options.fusion == "centralized"
    steps = list(agents.Rollout(agent, env, seed=9).run(6))
    assert [step.t for step in steps] == list(range(1, 7))
    assert all(step.act_seconds >= 0 for step in steps)
    assert env.options == VERSIONS["v1"].options(fusion="centralized", **agent.needs.observation_options)
    reference_env = MimoRadarSelectVectorEnv(
        num_envs=4, scenario="paper-1-v1", **agents.env_options_for(agent, env.options)
    )
    actions, rewards = _by_hand(policy, reference_env, 9, 6)
    np.testing.assert_array_equal(np.array([step.action for step in steps]), actions)
    np.testing.assert_array_equal(np.array([step.reward for step in steps]), rewards)


def test_make_env_adds_what_the_agent_observes():
    agent = agents.make_agent("tracking-ucb", "paper-1-v1")
    assert agents.env_options_for(agent, {"fusion": "average"}) == {
        "fusion": "average",
        "prediction_covariance": True,
    }
    assert "track_pred_pos_cov" in agents.make_env(agent, 2).reset(seed=0)[0]
    plain = agents.make_agent("ucb1", "paper-1-v1")
    assert agents.env_options_for(plain) == {}


def test_a_rollout_runs_on_the_single_env_as_the_batch_of_one():
    env = gym.make("MimoRadarSelect-v1")
    agent = agents.make_agent("best", "paper-1-v1")
    episode = agents.Rollout(agent, env, seed=3)
    assert episode.info["true_state"].shape == (1, 4)  # the reset's info until the first step
    step = episode.step()
    assert step.action.shape == (10,)
    np.testing.assert_array_equal(step.action, step.info["optimal_action"])
    vector = agents.make_env(agents.make_agent("best", "paper-1-v1"), 1)  # v1's options, as gym.make's
    batch = agents.Rollout(agents.make_agent("best", "paper-1-v1"), vector, seed=3).step()
    np.testing.assert_array_equal(batch.action[0], step.action)
    assert batch.reward[0] == pytest.approx(step.reward, rel=1e-12)


def test_make_env_refuses_another_versions_paper_scenario_by_name_as_gym_make_does():
    """v0's paper-1 under v1's options is a hybrid of the two readings: by name it is refused, as
    ``gym.make("MimoRadarSelect-v1", scenario="paper-1")`` refuses it; its Scenario object runs."""
    from mimo_radar_env import load_scenario

    agent = agents.make_agent("ucb1", "paper-1")
    message = (
        "scenario 'paper-1' is MimoRadarSelect-v0's paper Scenario 1; MimoRadarSelect-v1's is 'paper-1-v1'"
    )
    with pytest.raises(ValueError, match=message):
        agents.make_env(agent, 2, scenario="paper-1")
    with pytest.raises(ValueError, match=message):
        gym.make("MimoRadarSelect-v1", scenario="paper-1")
    assert agents.make_env(agent, 2, scenario="paper-1", version="v0").options == VERSIONS["v0"].options()
    assert agents.make_env(agent, 2, scenario=load_scenario("paper-1")).options == VERSIONS["v1"].options()


def test_a_rollout_refuses_a_step_count_that_is_not_a_whole_number():
    agent = agents.make_agent("ucb1", "paper-1-v1")
    episode = agents.Rollout(agent, agents.make_env(agent, 2), seed=0)
    for bad in (-1, 2.5, True, "3"):
        with pytest.raises(ValueError, match=r"steps must be an integer >= 0, got"):
            next(episode.run(bad))
    assert episode.t == 0 and list(episode.run(0)) == []


def test_a_rollout_refuses_an_agent_made_for_another_scenario():
    """An agent made for one scenario on an env of another ran silently (a tracking agent's
    predictions would be another layout's); the horizon alone may differ (no agent reads it)."""
    from mimo_radar_env import load_scenario

    agent = agents.make_agent("tracking-ucb", "paper-2-v1")
    with pytest.raises(ValueError, match=r"made for scenario 'paper-2-v1' and the env runs 'paper-1-v1', "):
        agents.Rollout(agent, agents.make_env(agent, 2, scenario="paper-1-v1"), seed=0)
    with pytest.raises(ValueError, match=r"which differ in peak_sinr; make the agent for the env's scenario"):
        agents.Rollout(agent, gym.make("MimoRadarSelect-v1", scenario="paper-2-v1", peak_sinr=20.0), seed=0)
    short = agents.make_env(agent, 2, scenario=load_scenario("paper-2-v1", horizon=700))
    assert agents.Rollout(agent, short, seed=0).horizon == 700


def test_a_rollout_refuses_what_is_not_an_env_of_this_project_or_an_agent_and_make_env_bad_options():
    """An object without the env's scenario was an AttributeError on ``env.unwrapped``."""
    agent = agents.make_agent("ucb1", "paper-1-v1", seed=0)
    sync = gym.make_vec("MimoRadarSelect-v1", num_envs=2, vectorization_mode="sync")
    for env, kind in ((object(), "object"), (gym.make("CartPole-v1"), "TimeLimit"), (sync, "SyncVectorEnv")):
        with pytest.raises(TypeError, match=rf'vectorization_mode="vector_entry_point"\), got {kind}$'):
            agents.Rollout(agent, env, seed=0)
    with pytest.raises(TypeError, match=r"agent must be an agents.Agent \(agents.make_agent\), got str$"):
        agents.Rollout("ucb1", gym.make("MimoRadarSelect-v1"), seed=0)
    with pytest.raises(TypeError, match=r"must be an EnvOptions or a mapping of env options, got list$"):
        agents.make_env(agent, 2, [("fusion", "average")])  # was a TypeError of Python's ** operator


def test_a_rollout_ends_with_its_episode():
    """Past the horizon the vector env resets, and the agent would learn from the reset: the
    rollout refuses those steps before running any, and a step after the last raises."""
    from mimo_radar_env import load_scenario

    agent = agents.make_agent("ucb1", "paper-1-v1")
    episode = agents.Rollout(
        agent, agents.make_env(agent, 2, scenario=load_scenario("paper-1-v1", horizon=3))
    )
    with pytest.raises(
        ValueError, match=r"steps must be at most the 3 left of the episode \(horizon 3, 0 run\)"
    ):
        next(episode.run(4))
    assert episode.t == 0
    assert [step.truncated.all() for step in episode.run(3)] == [False, False, True]
    with pytest.raises(RuntimeError, match="the episode ended after its 3 steps"):
        episode.step()


def test_a_rollout_refuses_an_env_whose_options_differ_from_the_agents_parameters_named_after_them():
    """tracking-ucb predicts the posterior with its own ``fusion``, ``lambda_scale`` and
    ``measurement_quality``: on an env of other options it selected for another tracker, silently
    (this file's first test ran it so, with average fusion on a centralised env)."""
    agent = agents.make_agent("tracking-ucb", "paper-1-v1", fusion="average")
    assert agent.env_option_values() == {
        "fusion": "average",
        "lambda_scale": "db",
        "measurement_quality": None,
    }
    with pytest.raises(
        ValueError,
        match=r"tracking-ucb was made with fusion='average' and the env runs fusion='centralized': they must",
    ):
        agents.Rollout(agent, agents.make_env(agent, 2, {"fusion": "centralized"}))
    quality = agents.make_agent("plan-tracking-ucb", "paper-1-v1", measurement_quality=2)
    with pytest.raises(ValueError, match=r"measurement_quality=2 and the env runs measurement_quality=None"):
        agents.Rollout(quality, agents.make_env(quality, 2))
    assert agents.Rollout(quality, agents.make_env(quality, 2, {"measurement_quality": 2.0})).t == 0
    assert agents.make_agent("ucb1", "paper-1-v1").env_option_values() == {}
