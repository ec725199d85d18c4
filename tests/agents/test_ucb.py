"""UCB1 (and epsilon-greedy's estimate) follow eq29, computed by hand."""

import numpy as np

import agents
from mimo_radar_env import load_scenario
from tests.helpers import bandit_obs

PAPER = load_scenario("paper-3")  # K = 2, Omega = [0.6, 0.4]


def test_ucb1_and_epsilon_greedy_follow_eq29():
    rng = np.random.default_rng(1)
    y0 = rng.exponential(size=(2, 4, 6))
    probed = np.zeros((4, 6))
    probed[2, 3] = 1
    gamma = rng.exponential(size=(2, 4, 6)) * probed
    for name in ("ucb1", "epsilon-greedy"):
        agent = agents.make_agent(name, PAPER, alpha_star=0.998)
        agent.reset(bandit_obs(y0, np.ones((4, 6))))
        agent.act(bandit_obs(y0, np.ones((4, 6))))
        agent.update(bandit_obs(gamma, probed), 0.0)
        expected = y0.copy()
        expected[:, 2, 3] = 0.002 * y0[:, 2, 3] + 0.998 * gamma[:, 2, 3]
        np.testing.assert_allclose(agent.estimate[0], expected, rtol=1e-12)
        np.testing.assert_array_equal(agent.counts[0], 1 + probed)
    ucb = agents.make_agent("ucb1", PAPER)
    ucb.reset(bandit_obs(y0, np.ones((4, 6))))
    ucb.t = 5
    bonus = np.sqrt(2 * np.log(5) / 1.0)
    np.testing.assert_allclose(ucb.index(None)[0], 0.6 * (y0[0] + bonus) + 0.4 * (y0[1] + bonus))
