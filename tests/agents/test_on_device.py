"""Agents on the torch engine (checked on CPU torch): the same selections as on numpy, every
step, for the policies of the paper and the tracking-aware ones, with their draws computed on
the device."""

import os

import numpy as np
import pytest

torch = pytest.importorskip("torch")

#: The device the torch side runs on: CPU torch in CI; .ci/device-check sets "cuda" on a GPU.
DEVICE = os.environ.get("MIMO_RADAR_TEST_DEVICE", "cpu")

import agents  # noqa: E402
from mimo_radar_env.core.arrays import device_namespace  # noqa: E402
from mimo_radar_env.core.counter_hash import Stream  # noqa: E402
from mimo_radar_env.core.streams import TrialRandom  # noqa: E402

#: policy, its parameters, steps: the paper's policies (MG-CRB-CL with BPSO, as in the paper, and
#: with the exact solver), the baselines, the oracles and tracking-ucb.
POLICIES = [
    ("mg-crb-cl", {}, 12),
    ("mg-crb-cl", {"solver": "bpso", "solver_params": {"rule": "set"}}, 12),
    ("mg-crb-cl", {"solver": "exact"}, 40),
    ("ucb1", {}, 40),
    ("epsilon-greedy", {}, 40),
    ("fix1", {}, 10),
    ("best", {}, 20),
    ("best-tracking", {}, 20),
    ("tracking-ucb", {}, 20),
    ("random", {}, 20),
    ("sliding-window-ucb", {"window": 5}, 20),
]


def _actions(policy, params, steps, device, fusion="average"):
    agent = agents.make_agent(policy, "paper-1-v1", seed=3, **params)
    env = agents.make_env(agent, 5, {"fusion": fusion}, device=device)
    actions = []
    for step in agents.Rollout(agent, env, seed=11).run(steps):
        action = step.action
        assert isinstance(action, torch.Tensor) == (device is not None)
        actions.append(action.cpu().numpy() if device is not None else action)
        assert isinstance(step.reward, torch.Tensor) == (device is not None)
    return np.array(actions)


@pytest.mark.parametrize(
    ("policy", "params", "steps"), POLICIES, ids=[f"{p}-{i}" for i, (p, _, _) in enumerate(POLICIES)]
)
def test_an_agent_selects_the_same_super_arms_on_torch(policy, params, steps):
    np.testing.assert_array_equal(
        _actions(policy, params, steps, DEVICE), _actions(policy, params, steps, None)
    )


def test_the_tracking_oracle_on_torch_under_centralized_fusion():
    np.testing.assert_array_equal(
        _actions("best-tracking", {}, 10, DEVICE, "centralized"),
        _actions("best-tracking", {}, 10, None, "centralized"),
    )


def test_an_agents_draws_on_torch_are_numpys_bit_for_bit():
    ours, theirs = TrialRandom.for_batch(7, 6), TrialRandom.for_batch(7, 6, device_namespace(DEVICE))
    for _ in range(2):  # a stream's second call draws anew, on both
        np.testing.assert_array_equal(
            theirs.uniform(Stream.AGENT_EXPLORE, (3,)).cpu().numpy(), ours.uniform(Stream.AGENT_EXPLORE, (3,))
        )
        np.testing.assert_allclose(
            theirs.normal(Stream.GAMMA_NORMAL, (4,)).cpu().numpy(),
            ours.normal(Stream.GAMMA_NORMAL, (4,)),
            rtol=1e-15,
        )
    np.testing.assert_array_equal(
        theirs.keys_for(Stream.BPSO_KEYS).cpu().numpy().view(np.uint64), ours.keys_for(Stream.BPSO_KEYS)
    )


def test_an_agent_that_acts_on_numpy_only_refuses_a_device_env_by_name():
    agent = agents.make_agent("cts", "paper-1-v1", seed=0)
    assert not agent.needs.device and agents.make_agent("ucb1", "paper-1-v1").needs.device
    env = agents.make_env(agent, 2, device="cpu")
    with pytest.raises(ValueError, match=r"cts acts on numpy arrays only, .* make its env with device=None"):
        agents.Rollout(agent, env, seed=0)


def test_an_agent_on_a_device_names_what_is_not_finite_after_one_read_of_all():
    agent = agents.make_agent("ucb1", "paper-1-v1", seed=0)
    episode = agents.Rollout(agent, agents.make_env(agent, 4, device=DEVICE), seed=0)
    obs = episode.obs
    reward = torch.zeros(4, dtype=torch.float64, device=DEVICE)
    agent.update(obs, reward)  # all finite: accepted
    with pytest.raises(ValueError, match="ucb1: the 'reward' it was given is not finite"):
        agent.update(obs, torch.full_like(reward, float("nan")))
    bad = {**obs, "track": obs["track"].clone()}
    bad["track"][1, 0, 2] = float("inf")
    with pytest.raises(ValueError, match="ucb1: the 'track' it was given is not finite"):
        agent.update(bad, reward)
