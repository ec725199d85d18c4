"""CTS and discounted Thompson sampling: the posterior by hand, its samples and its convergence."""

import numpy as np
import pytest

import agents
from mimo_radar_env import load_scenario
from mimo_radar_env.core.streams import TrialRandom
from tests.helpers import bandit_obs

PAPER = load_scenario("paper-3")  # K = 2, Omega = [0.6, 0.4], 4 TX x 6 RX


WEIGHTS = np.array([0.6, 0.4])


@pytest.mark.parametrize(("name", "discount"), [("cts", 1.0), ("cts", 0.9), ("discounted-thompson", 0.99)])
def test_cts_posterior_by_hand(name, discount):
    params = (
        {} if (name, discount) in (("cts", 1.0), ("discounted-thompson", 0.99)) else {"discount": discount}
    )
    agent = agents.make_agent(name, PAPER, prior_shape=2.0, prior_rate=3.0, seed=0, **params)
    rng = np.random.default_rng(2)
    y0 = rng.exponential(size=(2, 4, 6))
    agent.reset(bandit_obs(y0, np.ones((4, 6))))
    n, s = np.ones((4, 6)), y0.copy()
    for _ in range(5):
        agent.act(bandit_obs(y0, np.ones((4, 6))))
        probed = (rng.random((4, 6)) < 0.4).astype(float)
        gamma = rng.exponential(size=(2, 4, 6)) * probed
        agent.update(bandit_obs(gamma, probed), 0.0)
        n, s = discount * n + probed, discount * s + gamma
    shape, rate = agent.posterior()
    np.testing.assert_allclose(shape[0], 2.0 + np.broadcast_to(n, (2, 4, 6)), rtol=1e-12)
    np.testing.assert_allclose(rate[0], 3.0 + s, rtol=1e-10)


def test_cts_samples_the_posterior_and_hands_the_fused_sample_to_the_solver():
    agent = agents.make_agent("cts", PAPER, seed=5)
    y0 = np.random.default_rng(3).exponential(size=(1, 2, 4, 6))
    agent.reset(bandit_obs(y0, np.ones((1, 4, 6))))
    twin = TrialRandom.for_batch(5, 1)  # the agent's streams, replayed
    shape, rate = agent.posterior()
    expected = np.einsum("k,bkmn->bmn", WEIGHTS, 1.0 / (twin.gamma(shape) / rate))
    np.testing.assert_allclose(agent.index(None), expected, rtol=1e-12)


def test_cts_posterior_mean_converges_to_the_true_mean_sinr_of_stationary_channels():
    agent = agents.make_agent("cts", PAPER, seed=0)
    rng = np.random.default_rng(4)
    truth = rng.uniform(0.05, 10.0, size=(2, 4, 6))  # mean SINRs spanning the paper's range
    agent.reset(bandit_obs(rng.exponential(truth), np.ones((4, 6))))
    steps = 3000
    for _ in range(steps):
        agent.act(bandit_obs(truth, np.ones((4, 6))))
        agent.update(bandit_obs(rng.exponential(truth), np.ones((4, 6))), 0.0)
    mean = agent.posterior_mean_sinr()[0]
    n = steps + 1
    z = (mean - truth) / (truth / np.sqrt(n))  # the sample mean's standard error is S / sqrt(n)
    assert np.all(np.abs(z) < 4.0), np.abs(z).max()
    assert abs(z.mean()) < 4.0 / np.sqrt(z.size)  # no bias across the 48 channels
