"""The batch engine under the vector env: trial for trial the single env, the same seed the same
numbers, truncation and autoreset."""

import gymnasium as gym
import numpy as np
import pytest

from tests.helpers import random_valid_actions, vector_env


def _run_single(seed, actions, scenario="paper-3"):
    env = gym.make("MimoRadarSelect-v0", scenario=scenario)
    obs, info = env.reset(seed=seed)
    out = [(obs, 0.0, info)]
    for action in actions:
        obs, reward, _, _, info = env.step(action)
        out.append((obs, reward, info))
    return out


def test_vector_env_equals_single_envs_trial_for_trial():
    batch, steps = 3, 12
    rng = np.random.default_rng(0)
    actions = [random_valid_actions(rng, batch, 4, 6, 2, 3) for _ in range(steps)]
    actions[4][1, :] = 0  # an invalid action in trial 1
    venv = vector_env("MimoRadarSelect-v0", batch, scenario="paper-3")
    obs, info = venv.reset(seed=40)
    vector = [(obs, np.zeros(batch), info)]
    for action in actions:
        obs, reward, _, _, info = venv.step(action)
        vector.append((obs, reward, info))
    for i in range(batch):
        single = _run_single(40 + i, [a[i] for a in actions])
        for (vobs, vrew, vinfo), (sobs, srew, sinfo) in zip(vector, single, strict=True):
            for key in sobs:
                np.testing.assert_allclose(vobs[key][i], sobs[key], rtol=1e-12, atol=1e-12, err_msg=key)
            assert vrew[i] == pytest.approx(srew, rel=1e-12)
            for key in sinfo:
                np.testing.assert_allclose(vinfo[key][i], sinfo[key], rtol=1e-12, err_msg=key)


def test_same_seed_same_numbers_and_policies_share_the_truth():
    rng = np.random.default_rng(3)
    actions_a = [a[0] for a in (random_valid_actions(rng, 1, 4, 6, 2, 3) for _ in range(15))]
    actions_b = [a[0] for a in (random_valid_actions(rng, 1, 4, 6, 2, 3) for _ in range(15))]
    run1, run2 = _run_single(9, actions_a), _run_single(9, actions_a)
    for (o1, r1, i1), (o2, r2, i2) in zip(run1, run2, strict=True):
        assert r1 == r2
        np.testing.assert_array_equal(i1["true_state"], i2["true_state"])
        for key in o1:
            np.testing.assert_array_equal(o1[key], o2[key])
    other = _run_single(9, actions_b)
    for (_, _, i1), (_, _, i2) in zip(run1, other, strict=True):
        np.testing.assert_array_equal(i1["true_state"], i2["true_state"])
    different_seed = _run_single(10, actions_a)
    assert not np.array_equal(different_seed[-1][2]["true_state"], run1[-1][2]["true_state"])


def test_truncation_and_autoreset():
    venv = vector_env("MimoRadarSelect-v0", 2, horizon=3)
    obs, _ = venv.reset(seed=0)
    action = np.array([[1, 1, 0, 0, 1, 1, 1, 0, 0, 0]] * 2, dtype=np.int8)
    for t in range(3):
        _, _, terminated, truncated, _ = venv.step(action)
        assert not terminated.any()
        assert truncated.all() == (t == 2)
    obs, reward, terminated, truncated, _ = venv.step(action)  # NEXT_STEP autoreset
    assert obs["probed"].all() and not truncated.any() and (reward == 0).all()
    env = gym.make("MimoRadarSelect-v0", horizon=2)
    env.reset(seed=0)
    env.step(action[0])
    assert env.step(action[0])[3] is True
