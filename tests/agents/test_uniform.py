"""random: every valid super arm equally likely, independently per trial, reproducible."""

import math
from collections import Counter

import numpy as np
from scipy import stats

import agents
from tests.helpers import vector_env


def test_random_plays_every_valid_super_arm_uniformly_and_reproducibly():
    trials, steps = 64, 60
    env = vector_env("MimoRadarSelect-v0", trials, scenario="paper-1")
    sc = env.scenario
    runs = []
    for _ in range(2):
        agent = agents.make_agent("random", sc, seed=3)
        obs, _ = env.reset(seed=0)
        agent.reset(obs)
        runs.append(np.stack([agent.act(obs) for _ in range(steps)]))  # (steps, B, M + N)
    np.testing.assert_array_equal(runs[0], runs[1])
    actions = runs[0].reshape(-1, sc.num_tx + sc.num_rx)
    assert (actions[:, : sc.num_tx].sum(1) == sc.tx_per_step).all()
    assert (actions[:, sc.num_tx :].sum(1) == sc.rx_per_step).all()
    # the trials draw independently: no two trials play the same sequence
    assert len({runs[0][:, b].tobytes() for b in range(trials)}) == trials
    arms = math.comb(sc.num_tx, sc.tx_per_step) * math.comb(sc.num_rx, sc.rx_per_step)
    counts = Counter(a.tobytes() for a in actions)
    assert len(counts) == arms
    # seeded: a chi-square test of uniformity over every super arm
    assert stats.chisquare(list(counts.values())).pvalue > 1e-3
