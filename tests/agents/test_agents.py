"""Agents: update rules against hand computations, oracle/fixed/epsilon behaviour, episodes."""

import gymnasium as gym
import numpy as np
import pytest
from scipy import stats

import agents
from mimo_radar_env import load_scenario
from tests.helpers import large_scenario, vector_env

PAPER = load_scenario("paper-3")  # K = 2, Omega = [0.6, 0.4]


def _obs(sinr, probed, track=None, track_pred=None):
    obs = {"sinr": np.asarray(sinr, dtype=float), "probed": np.asarray(probed, dtype=np.int8)}
    if track is not None:
        obs["track"] = np.asarray(track, dtype=float)
        obs["track_pred"] = np.asarray(track_pred, dtype=float)
    return obs


def _ranges_sq(state, scenario):
    pos = np.array([state[0], state[2]])
    rt = np.sum((scenario.tx_positions - pos) ** 2, axis=1)
    rr = np.sum((scenario.rx_positions - pos) ** 2, axis=1)
    return rt, rr


def test_mg_crb_cl_update_rules_by_hand():
    sc = PAPER
    rng = np.random.default_rng(0)
    y0 = rng.exponential(size=(2, 4, 6))
    track = np.array([[20e3, 100, 30e3, 50], [40e3, -20, 60e3, 10]])
    track_pred = track + np.array([[100, 0, 50, 0], [-20, 0, 10, 0]])
    agent = agents.make_agent("mg-crb-cl", sc, solver="exact", alpha=0.9, alpha_bar=0.3, beta=2.0)
    agent.reset(_obs(y0, np.ones((4, 6)), track, track_pred))
    np.testing.assert_array_equal(agent.counts, np.ones((1, 4, 6)))
    agent.act(_obs(y0, np.ones((4, 6)), track, track_pred))  # t = 1
    # eq16 by hand: ratio of path gains (R_tx R_rx)^-2 at the prediction and the estimate
    y_bar = np.empty_like(y0)
    for k in range(2):
        rt1, rr1 = _ranges_sq(track[k], sc)
        rt2, rr2 = _ranges_sq(track_pred[k], sc)
        for m in range(4):
            for n in range(6):
                ratio = (rt1[m] * rr1[n]) / (rt2[m] * rr2[n])
                y_bar[k, m, n] = 0.9 * ratio * y0[k, m, n] + 0.1 * y0[k, m, n]
    np.testing.assert_allclose(agent.predicted[0], y_bar, rtol=1e-12)
    # step t = 1: channels TX1-RX1 and TX2-RX3 played
    probed = np.zeros((4, 6))
    probed[0, 0] = probed[1, 2] = 1
    gamma = rng.exponential(size=(2, 4, 6)) * probed
    agent.update(_obs(gamma, probed, track, track_pred), 0.0)
    expected = y_bar.copy()  # eq14: unplayed channels keep Y_bar
    for m, n in ((0, 0), (1, 2)):
        expected[:, m, n] = 0.7 * y_bar[:, m, n] + 0.3 * gamma[:, m, n]
    np.testing.assert_allclose(agent.estimate[0], expected, rtol=1e-12)
    np.testing.assert_array_equal(agent.counts[0], 1 + probed)  # eq15
    # eq18 + eq34 at t = 2 with K = 2 weights
    agent.t = 2
    obs2 = _obs(gamma, probed, track, track_pred)
    before = (agent.estimate.copy(), agent.counts.copy(), agent.predicted.copy())
    index = agent.index(obs2)
    for was, now in zip(before, (agent.estimate, agent.counts, agent.predicted), strict=True):
        np.testing.assert_array_equal(was, now)  # index() is a pure query
    y_bar2 = agent.predict(obs2)[0]
    bonus = np.sqrt(2.0 * np.log(2) / (1 + probed))
    np.testing.assert_allclose(index[0], 0.6 * (y_bar2[0] + bonus) + 0.4 * (y_bar2[1] + bonus), rtol=1e-12)


def test_ucb1_and_epsilon_greedy_follow_eq29():
    rng = np.random.default_rng(1)
    y0 = rng.exponential(size=(2, 4, 6))
    probed = np.zeros((4, 6))
    probed[2, 3] = 1
    gamma = rng.exponential(size=(2, 4, 6)) * probed
    for name in ("ucb1", "epsilon-greedy"):
        agent = agents.make_agent(name, PAPER, alpha_star=0.998)
        agent.reset(_obs(y0, np.ones((4, 6))))
        agent.act(_obs(y0, np.ones((4, 6))))
        agent.update(_obs(gamma, probed), 0.0)
        expected = y0.copy()
        expected[:, 2, 3] = 0.002 * y0[:, 2, 3] + 0.998 * gamma[:, 2, 3]
        np.testing.assert_allclose(agent.estimate[0], expected, rtol=1e-12)
        np.testing.assert_array_equal(agent.counts[0], 1 + probed)
    ucb = agents.make_agent("ucb1", PAPER)
    ucb.reset(_obs(y0, np.ones((4, 6))))
    ucb.t = 5
    bonus = np.sqrt(2 * np.log(5) / 1.0)
    np.testing.assert_allclose(ucb.index(None)[0], 0.6 * (y0[0] + bonus) + 0.4 * (y0[1] + bonus))


def test_best_has_zero_regret_and_fixed_always_plays_its_arm():
    venv = vector_env("MimoRadarSelect-v0", 8, scenario="paper-3")
    best = agents.make_agent("best", venv.scenario, env=venv)
    fix2 = agents.make_agent("fix2", venv.scenario)
    obs, _ = venv.reset(seed=0)
    best.reset(obs)
    fix2.reset(obs)
    expected_fix2 = np.array([0, 0, 1, 1, 0, 0, 0, 1, 1, 1])
    for _ in range(50):
        np.testing.assert_array_equal(fix2.act(obs), np.tile(expected_fix2, (8, 1)))
        obs, reward, _, _, info = venv.step(best.act(obs))
        np.testing.assert_allclose(info["expected_reward"], info["optimal_reward"], rtol=1e-12)
    with pytest.raises(ValueError, match="tx must be 2 distinct transmitter indices"):
        agents.make_agent("fixed", venv.scenario, tx=[0], rx=[0, 1, 2])


def test_epsilon_greedy_explores_at_rate_epsilon():
    agent = agents.make_agent("epsilon-greedy", PAPER, epsilon=0.1, seed=3)
    y0 = np.random.default_rng(2).exponential(size=(400, 2, 4, 6))
    agent.reset(_obs(y0, np.ones((400, 4, 6))))
    explored = []
    for _ in range(25):
        agent.act(_obs(y0, np.ones((400, 4, 6))))
        explored.append(agent.explored)
    explored = np.concatenate(explored)
    n, k = explored.size, explored.sum()
    assert stats.binomtest(int(k), n, 0.1).pvalue > 0.01
    agent0 = agents.make_agent("epsilon-greedy", PAPER, epsilon=0.0)
    agent0.reset(_obs(y0, np.ones((400, 4, 6))))
    greedy = agent0.act(_obs(y0, np.ones((400, 4, 6))))
    fused = np.einsum("k,bkmn->bmn", [0.6, 0.4], y0)
    for b in range(0, 400, 37):  # greedy choice = exact optimum of the fused estimate
        tx, rx = np.flatnonzero(greedy[b, :4]), np.flatnonzero(greedy[b, 4:])
        from itertools import combinations

        best = max(
            fused[b][np.ix_(t, r)].sum() for t in combinations(range(4), 2) for r in combinations(range(6), 3)
        )
        assert fused[b][np.ix_(tx, rx)].sum() == pytest.approx(best)


def test_registry_errors_list_what_exists():
    with pytest.raises(ValueError, match="unknown agent 'ucb2'; available agents are .*mg-crb-cl"):
        agents.make_agent("ucb2", PAPER)
    with pytest.raises(
        ValueError, match=r"unknown parameter\(s\) \['gamma'\] for agent 'ucb1'; allowed: .*beta"
    ):
        agents.make_agent("ucb1", PAPER, gamma=3)
    assert {
        "mg-crb-cl",
        "ucb1",
        "epsilon-greedy",
        "fix1",
        "fix2",
        "best",
        "discounted-ucb",
        "sliding-window-ucb",
        "discounted-thompson",
        "cucb",
        "random",
    } <= set(agents.available_agents())


def test_mg_crb_cl_needs_the_tracker():
    venv = vector_env("MimoRadarSelect-v0", 2, tracking=False)
    obs, _ = venv.reset(seed=0)
    with pytest.raises(ValueError, match="tracking=True"):
        agents.make_agent("mg-crb-cl", venv.scenario).reset(obs)


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


def test_paper1_mg_crb_cl_beats_ucb1_and_best_has_the_highest_sinr():
    results = {}
    for name in ("best", "mg-crb-cl", "ucb1", "epsilon-greedy", "fix1", "fix2"):
        venv = vector_env("MimoRadarSelect-v0", 50)
        agent = agents.make_agent(name, venv.scenario, seed=0)
        regret = sinr = 0.0
        for step in agents.Rollout(agent, venv, seed=0).run(1000):
            regret += np.mean(step.info["optimal_reward"] - step.info["expected_reward"])
            sinr += np.mean(step.info["expected_reward"])
        results[name] = (regret, sinr)
    assert results["mg-crb-cl"][0] < results["ucb1"][0]
    assert max(results, key=lambda n: results[n][1]) == "best"


@pytest.mark.parametrize(
    ("name", "params", "message"),
    [
        ("mg-crb-cl", {"alpha": 1.5}, r"alpha must be in \[0, 1\], got 1.5"),
        ("mg-crb-cl", {"beta": -1}, r"beta must be in \[0, inf\), got -1"),
        ("discounted-ucb", {"discount": 0.0}, r"discount must be in \(0, 1\], got 0.0"),
        ("discounted-thompson", {"prior_rate": 0}, r"prior_rate must be in \(0, inf\), got 0"),
        ("sliding-window-ucb", {"window": 0}, r"window must be in \[1, inf\), got 0"),
        ("epsilon-greedy", {"epsilon": 2}, r"epsilon must be in \[0, 1\], got 2"),
    ],
)
def test_bad_agent_parameters_are_named(name, params, message):
    with pytest.raises(ValueError, match=message):
        agents.make_agent(name, PAPER, **params)


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
