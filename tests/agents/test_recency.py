"""RBE: its index and eq29 update by hand, and its recency bonus."""

import numpy as np
import pytest

import agents
from mimo_radar_env import load_scenario
from tests.helpers import bandit_obs

PAPER = load_scenario("paper-3")  # K = 2, Omega = [0.6, 0.4], 4 TX x 6 RX


WEIGHTS = np.array([0.6, 0.4])


def test_rbe_index_and_eq29_update_by_hand():
    rng = np.random.default_rng(0)
    y0 = rng.exponential(size=(2, 4, 6))
    agent = agents.make_agent("rbe", PAPER)
    agent.reset(bandit_obs(y0, np.ones((4, 6))))
    agent.act(bandit_obs(y0, np.ones((4, 6))))  # t = 1: every channel last probed at c = 1, now c = 2
    probed = np.zeros((4, 6))
    probed[1, 2] = probed[3, 5] = 1
    gamma = rng.exponential(size=(2, 4, 6)) * probed
    agent.update(bandit_obs(gamma, probed), 0.0)
    estimate = y0.copy()
    for m, n in ((1, 2), (3, 5)):
        estimate[:, m, n] = 0.002 * y0[:, m, n] + 0.998 * gamma[:, m, n]  # eq29
    np.testing.assert_allclose(agent.estimate[0], estimate, rtol=1e-12)
    agent.t = 2  # the coming decision: c = 3; probed channels were last probed at c = 2, the others at 1
    bonus = np.where(probed > 0, np.sqrt(np.log(3 / 2)), np.sqrt(np.log(3 / 1)))
    expected = sum(WEIGHTS[k] * (estimate[k] + bonus) for k in range(2))
    np.testing.assert_allclose(agent.index(None)[0], expected, rtol=1e-12)


def test_rbe_bonus_grows_while_unprobed_and_resets_when_probed():
    agent = agents.make_agent("rbe", PAPER, estimate="last")
    rng = np.random.default_rng(1)
    agent.reset(bandit_obs(rng.exponential(size=(2, 4, 6)), np.ones((4, 6))))
    history = []
    for t in range(1, 40):
        agent.act(bandit_obs(np.zeros((2, 4, 6)), np.zeros((4, 6))))
        history.append(agent.recency_bonus()[0].copy())
        probed = np.zeros((4, 6))
        if t % 10 == 0:
            probed[2, 1] = 1
        sample = rng.exponential(size=(2, 4, 6)) * probed
        agent.update(bandit_obs(sample, probed), 0.0)
        if probed.any():
            np.testing.assert_array_equal(agent.estimate[0][:, 2, 1], sample[:, 2, 1])  # "last" sample
    history = np.array(history)  # (steps, M, N)
    never = history[:, 0, 0]
    assert np.all(np.diff(never) > 0)  # grows while not probed
    np.testing.assert_allclose(never, np.sqrt(np.log((np.arange(1, 40) + 1) / 1.0)), rtol=1e-12)
    probed_channel = history[:, 2, 1]
    for t in (10, 20, 30):  # probed at decision t (c = t + 1): at decision t + 1 the bonus restarts
        assert probed_channel[t] < probed_channel[t - 1]
        assert probed_channel[t] == pytest.approx(np.sqrt(np.log((t + 2) / (t + 1))), rel=1e-12)


def test_rbe_sample_mean_variant_and_unprobed_channels():
    agent = agents.make_agent("rbe", PAPER, estimate="mean")
    probed0 = np.ones((4, 6))
    probed0[0, 0] = 0  # a channel the reset did not probe
    y0 = np.full((2, 4, 6), 2.0)
    agent.reset(bandit_obs(y0 * probed0, probed0))
    agent.act(bandit_obs(y0, probed0))
    index = agent.index(None)[0]
    assert index[0, 0] == agents.recency.UNPROBED_INDEX and np.all(index[probed0 > 0] < 100)
    samples = [4.0, 6.0, 1.0]
    for x in samples:
        probed = np.zeros((4, 6))
        probed[1, 1] = 1
        agent.update(bandit_obs(np.full((2, 4, 6), x) * probed, probed), 0.0)
        agent.act(bandit_obs(y0, probed))
    assert agent.estimate[0, 0, 1, 1] == pytest.approx(np.mean([2.0, *samples]), rel=1e-12)
    with pytest.raises(ValueError, match=r"estimate must be one of \['eq29', 'last', 'mean'\]"):
        agents.make_agent("rbe", PAPER, estimate="median")
