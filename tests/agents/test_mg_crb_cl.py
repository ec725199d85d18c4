"""MG-CRB-CL: its update rules against a hand computation, its need of the tracker, and its regret
against UCB1 on paper Scenario 1."""

import numpy as np
import pytest

import agents
from mimo_radar_env import load_scenario
from tests.helpers import bandit_obs, vector_env

PAPER = load_scenario("paper-3")  # K = 2, Omega = [0.6, 0.4]


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
    agent.reset(bandit_obs(y0, np.ones((4, 6)), track, track_pred))
    np.testing.assert_array_equal(agent.counts, np.ones((1, 4, 6)))
    agent.act(bandit_obs(y0, np.ones((4, 6)), track, track_pred))  # t = 1
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
    agent.update(bandit_obs(gamma, probed, track, track_pred), 0.0)
    expected = y_bar.copy()  # eq14: unplayed channels keep Y_bar
    for m, n in ((0, 0), (1, 2)):
        expected[:, m, n] = 0.7 * y_bar[:, m, n] + 0.3 * gamma[:, m, n]
    np.testing.assert_allclose(agent.estimate[0], expected, rtol=1e-12)
    np.testing.assert_array_equal(agent.counts[0], 1 + probed)  # eq15
    # eq18 + eq34 at t = 2 with K = 2 weights
    agent.t = 2
    obs2 = bandit_obs(gamma, probed, track, track_pred)
    before = (agent.estimate.copy(), agent.counts.copy(), agent.predicted.copy())
    index = agent.index(obs2)
    for was, now in zip(before, (agent.estimate, agent.counts, agent.predicted), strict=True):
        np.testing.assert_array_equal(was, now)  # index() is a pure query
    y_bar2 = agent.predict(obs2)[0]
    bonus = np.sqrt(2.0 * np.log(2) / (1 + probed))
    np.testing.assert_allclose(index[0], 0.6 * (y_bar2[0] + bonus) + 0.4 * (y_bar2[1] + bonus), rtol=1e-12)


def test_mg_crb_cl_needs_the_tracker():
    venv = vector_env("MimoRadarSelect-v0", 2, tracking=False)
    obs, _ = venv.reset(seed=0)
    with pytest.raises(ValueError, match="tracking=True"):
        agents.make_agent("mg-crb-cl", venv.scenario).reset(obs)


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
