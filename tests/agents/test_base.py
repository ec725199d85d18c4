"""Every registered agent acts validly through an episode on the single and the vector env, and
refuses an env of another scenario and values that are not finite."""

import re

import gymnasium as gym
import numpy as np
import pytest

import agents
from tests.helpers import large_scenario, vector_env


def _episode(agent_name, scenario, vector, steps):
    cls = agents.agent_class(agent_name)
    kwargs = {"scenario": scenario, **cls.needs.observation_options}
    if vector:
        env = vector_env("MimoRadarSelect-v0", 3, **kwargs)
        sc = env.scenario
    else:
        env = gym.make("MimoRadarSelect-v0", **kwargs)
        sc = env.unwrapped.scenario
    params = {"seed": 0}
    if agent_name in ("fix1", "fix2") and sc.num_tx != 4 or agent_name in agents.learned_agents():
        # the learned agents need a trained model: tests/agents/test_ppo.py, test_learners.py
        return
    if agent_name == "fixed":
        params.update(tx=list(range(sc.tx_per_step)), rx=list(range(sc.rx_per_step)))
    if agent_name == "mg-crb-cl" and sc.num_tx > 8:
        params["solver"] = "alternating"
    if agent_name.startswith("plan-") and sc.num_tx > 8:
        # it scores every super arm at every planned step: layouts it refuses are tested there
        with pytest.raises(ValueError, match="planning scores every super arm"):
            agents.make_agent(agent_name, sc, **params)
        return
    options = env.unwrapped.options if not vector else env.options
    params.update({key: getattr(options, key) for key in cls.needs.env_option_params})
    agent = agents.make_agent(agent_name, sc, **params)
    for step in agents.Rollout(agent, env, seed=1).run(steps or sc.horizon):
        assert np.all(step.info["action_valid"])
    if steps is None:
        assert np.all(step.truncated)


SCENARIOS = ["paper-1", "paper-2", "paper-3", "large"]


def _scenario(name):
    return large_scenario(16, 16, 5) if name == "large" else name


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("vector", [False, True])
def test_every_agent_acts_validly(scenario, vector):
    for name in agents.available_agents():
        _episode(name, _scenario(scenario), vector, steps=30)


@pytest.mark.slow
@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("vector", [False, True])
def test_every_agent_runs_a_whole_episode(scenario, vector):
    for name in agents.available_agents():
        _episode(name, _scenario(scenario), vector, steps=None)


@pytest.mark.parametrize("policy", ["tracking-ucb", "best-tracking", "rbe", "cts", "ucb1", "mg-crb-cl"])
def test_an_agent_refuses_an_env_of_another_scenario_and_what_is_not_finite(policy):
    import math

    env = agents.make_env(agents.make_agent(policy, "paper-1-v1"), 2)  # K = 1
    obs, _ = env.reset(seed=0)
    stranger = agents.make_agent(policy, "paper-3-v1", seed=0)  # made for K = 2
    with pytest.raises(ValueError, match=r"was made for scenario 'paper-3-v1' \(K=2 targets, M=4, N=6\)"):
        stranger.reset(obs)
    agent = agents.make_agent(policy, "paper-1-v1", seed=0)
    if agent.needs.oracle:
        agent.attach(env)
    agent.reset(obs)
    obs, reward, *_ = env.step(agent.act(obs))
    with pytest.raises(ValueError, match="the 'reward' it was given is not finite"):
        agent.update(obs, np.full_like(reward, math.nan))
    bad = {**obs, "sinr": np.where(obs["sinr"] > 0, math.inf, obs["sinr"])}
    with pytest.raises(ValueError, match="the 'sinr' it was given is not finite"):
        agent.update(bad, reward)


@pytest.mark.parametrize("policy", ["ucb1", "mg-crb-cl", "fix1", "random"])
def test_an_agent_refuses_observations_and_rewards_of_another_batch_than_its_reset(policy):
    """Reset on 4 trials, it refuses 3, one unbatched trial, a reward of another length and a
    mapping without the env's keys, in one line each; before, a policy that reads no state of
    the trials acted on 4 and one that reads none of the reward learnt from 7 values."""
    agent = agents.make_agent(policy, "paper-1-v1", seed=0)
    four, three = agents.make_env(agent, 4), agents.make_env(agent, 3)
    obs, _ = four.reset(seed=0)
    other, _ = three.reset(seed=0)
    with pytest.raises(ValueError, match=r"key 'sinr'; got keys \['x'\]"):
        agent.reset({"x": obs["sinr"]})
    with pytest.raises(RuntimeError, match=r"update\(\) called before reset"):
        agent.update(obs, np.zeros(4))
    agent.reset(obs)
    with pytest.raises(ValueError, match=r"reset on 4 trial\(s\), and this observation holds 3 trial\(s\)"):
        agent.act(other)
    single = {key: value[0] for key, value in obs.items()}
    with pytest.raises(ValueError, match=r"reset on 4 trial\(s\), and this observation holds one trial"):
        agent.act(single)
    obs, reward, *_ = four.step(agent.act(obs))
    assert reward.shape == (4,)
    for wrong in (np.zeros(7), 1.0, np.zeros((2, 2, 2))):
        with pytest.raises(
            ValueError, match=rf"one value per trial \(4\), got shape {re.escape(str(np.shape(wrong)))}"
        ):
            agent.update(obs, wrong)
    with pytest.raises(ValueError, match=r"reset on 4 trial\(s\), and this observation holds 3 trial\(s\)"):
        agent.update(other, reward[:3])
    agent.update(obs, reward)  # the right ones still pass
    single_env = gym.make("MimoRadarSelect-v1")
    one, _ = single_env.reset(seed=0)
    agent.reset(one)  # the single env: the batch of one, a scalar reward
    one, scalar, *_ = single_env.step(agent.act(one))
    agent.update(one, scalar)


def test_keyword_parameters_are_declared_once_and_other_keywords_are_refused():
    """MG-CRB-CL and tracking-ucb build their estimator parameters from the one dataclass; an
    agent that declares none refuses any keyword beyond its signature, as Gymnasium does."""
    from agents.base import IndexPolicy
    from agents.fixed import FixedAgent
    from agents.mg_crb_cl import MGCRBCL, LearningParameters
    from agents.tracking import TrackingUCB

    assert MGCRBCL("paper-1-v1", beta=1.5).parameters == LearningParameters(beta=1.5)
    assert TrackingUCB("paper-1-v1", alpha=0.9).learning.parameters == LearningParameters(alpha=0.9)
    with pytest.raises(TypeError, match="gamma"):
        MGCRBCL("paper-1-v1", gamma=1.0)

    class Plain(IndexPolicy):
        def compute_index(self, predicted, obs):
            return self.fuse(predicted)

    assert Plain("paper-1-v1").parameters is None
    with pytest.raises(TypeError, match=r"Plain\(\) got unexpected keyword argument\(s\) \['beta'\]"):
        Plain("paper-1-v1", beta=1.0)
    with pytest.raises(TypeError, match="unexpected keyword argument 'beta'"):  # its own signature
        FixedAgent("paper-1-v1", (0,), (0,), beta=1.0)


@pytest.mark.parametrize("seed", [-1, 2**63, 2**64, 1.5, "3", True, np.bool_(True)])
def test_an_agent_seed_outside_its_64_bit_keys_is_refused_by_name(seed):
    """Trial i draws from the key of seed + i in 64 bits: a seed at 2**63 or more could wrap onto
    small seeds' trials (2**64 - 1 + 1 is 0), and 2**64 once overflowed deep inside numpy."""
    with pytest.raises(ValueError, match=r"seed must be None or an integer from 0 to 2\*\*63 - 1, got "):
        agents.make_agent("epsilon-greedy", "paper-1-v1", seed=seed)


def test_the_largest_agent_seed_draws_keys_apart_from_small_seeds():
    largest = agents.make_agent("epsilon-greedy", "paper-1-v1", seed=2**63 - 1)
    small = agents.make_agent("epsilon-greedy", "paper-1-v1", seed=0)
    largest.random.reset(1000)
    small.random.reset(1000)
    assert len(np.unique(np.concatenate([largest.random.keys, small.random.keys]))) == 2000


def test_every_agent_pickles_in_mid_episode_and_its_copy_acts_as_it_does():
    """For a user's process pool or Ray: best-tracking's attached oracle was a lambda, which
    pickle refuses. An oracle's copy carries a copy of its env, at the same step."""
    import pickle

    learned = {"ppo", "maskable-ppo", "recurrent-ppo", "torch-ppo"}  # need a trained model
    for name in sorted(set(agents.available_agents()) - learned - {"fixed"}):
        agent = agents.make_agent(name, "paper-1-v1", seed=1)
        episode = agents.Rollout(agent, agents.make_env(agent, 3), seed=0)
        for _ in episode.run(3):
            pass
        copy = pickle.loads(pickle.dumps(agent))
        np.testing.assert_array_equal(copy.act(episode.obs), agent.act(episode.obs), err_msg=name)


def test_an_agents_repr_names_it_its_scenario_seed_and_episode():
    """``repr(agent)`` says what a notebook needs to tell agents apart: its class and name, the
    scenario it was made for, its seed, and how many trials it was reset on and its step."""
    agent = agents.make_agent("fix1", "paper-1-v1", seed=3)
    assert repr(agent) == "<FixedAgent 'fix1' on 'paper-1-v1', seed 3, not reset>"
    episode = agents.Rollout(agent, agents.make_env(agent, 4), seed=0)
    episode.step()
    assert repr(agent) == "<FixedAgent 'fix1' on 'paper-1-v1', seed 3, reset on 4 trial(s), step 1>"
