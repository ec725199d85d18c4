"""A new policy is one file: an index policy written and registered in this file alone is made
by name, runs through the rollout loop and the benchmark harness, with no other edit. Like
SMPyBandits' IndexPolicy, it only writes its index."""

import numpy as np
import pytest

import agents
from agents.registry import _REGISTRY
from benchmarks.harness import make_config, run
from mimo_radar_env.core.superarm import all_super_arms


class GreedyMean(agents.IndexPolicy):
    """Greedy on the sample means: no exploration at all."""

    name = "greedy-mean"

    def compute_index(self, predicted, obs):
        return self.fuse(predicted)  # eq34 over the estimates, nothing added


@pytest.fixture
def policy():
    agents.register_agent("greedy-mean", GreedyMean, "greedy on the sample means")
    yield "greedy-mean"
    _REGISTRY.pop("greedy-mean")


def test_it_plays_the_super_arm_of_the_largest_index(policy):
    agent = agents.make_agent(policy, "paper-1-v1", seed=0)
    assert policy in agents.available_agents() and isinstance(agent, GreedyMean)
    episode = agents.Rollout(agent, agents.make_env(agent, 3), seed=2)
    tx_masks, rx_masks = all_super_arms(4, 6, 2, 3)
    for _ in range(5):
        index = np.einsum("k,bkmn->bmn", agent.weights, agent.estimate)  # what it knows before acting
        step = episode.step()
        value = np.einsum("am,bmn,an->ba", tx_masks.astype(float), index, rx_masks.astype(float))
        best = np.argmax(value, axis=1)
        np.testing.assert_array_equal(step.action, np.concatenate([tx_masks[best], rx_masks[best]], 1))


def test_the_harness_runs_it_beside_the_built_in_policies(policy, tmp_path):
    config = make_config("paper-1-v1", [policy, "ucb1"], trials=4, steps=10, say=lambda message: None)
    per_trial = run(config, tmp_path, progress=False)
    assert set(per_trial) == {policy, "ucb1"}
    assert np.isfinite(per_trial[policy]["trial_expected"]).all()
