"""Epsilon-greedy explores at its rate epsilon (a seeded binomial test)."""

import numpy as np
import pytest
from scipy import stats

import agents
from mimo_radar_env import load_scenario
from tests.helpers import bandit_obs

PAPER = load_scenario("paper-3")  # K = 2, Omega = [0.6, 0.4]


def test_epsilon_greedy_explores_at_rate_epsilon():
    agent = agents.make_agent("epsilon-greedy", PAPER, epsilon=0.1, seed=3)
    y0 = np.random.default_rng(2).exponential(size=(400, 2, 4, 6))
    agent.reset(bandit_obs(y0, np.ones((400, 4, 6))))
    explored = []
    for _ in range(25):
        agent.act(bandit_obs(y0, np.ones((400, 4, 6))))
        explored.append(agent.explored)
    explored = np.concatenate(explored)
    n, k = explored.size, explored.sum()
    assert stats.binomtest(int(k), n, 0.1).pvalue > 0.01
    agent0 = agents.make_agent("epsilon-greedy", PAPER, epsilon=0.0)
    agent0.reset(bandit_obs(y0, np.ones((400, 4, 6))))
    greedy = agent0.act(bandit_obs(y0, np.ones((400, 4, 6))))
    fused = np.einsum("k,bkmn->bmn", [0.6, 0.4], y0)
    for b in range(0, 400, 37):  # greedy choice = exact optimum of the fused estimate
        tx, rx = np.flatnonzero(greedy[b, :4]), np.flatnonzero(greedy[b, 4:])
        from itertools import combinations

        best = max(
            fused[b][np.ix_(t, r)].sum() for t in combinations(range(4), 2) for r in combinations(range(6), 3)
        )
        assert fused[b][np.ix_(tx, rx)].sum() == pytest.approx(best)
