"""The SB3 envs: the training wrapper passes SB3's checks, and the native vector env equals it."""

import warnings

import gymnasium as gym
import numpy as np
import pytest

from mimo_radar_env.wrappers import (
    make_ppo_env,
)
from tests.helpers import large_scenario


def test_sb3_check_env_on_the_env_and_the_training_wrapper():
    sb3 = pytest.importorskip("stable_baselines3", reason="PPO needs the rl extra: pip install -e '.[rl]'")
    from stable_baselines3.common.env_checker import check_env

    # the raw env passes; SB3 only advises on its multi-dimensional Dict entries (it takes 3-D
    # arrays for images), which the training wrapper flattens
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(gym.make("MimoRadarSelect-v1", scenario="paper-3-v1").unwrapped)
    shape_advice = ("unconventional shape", "is an image", "minimal resolution for an image")
    for w in caught:
        assert any(text in str(w.message) for text in shape_advice), str(w.message)
    for env in (make_ppo_env("paper-3-v1"), make_ppo_env(large_scenario(16, 16, 5))):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            check_env(env)
    del sb3


def test_native_training_vec_env_matches_the_checked_gym_wrapper():
    """PPO trains on a VecEnv over the native batch env: same features and rewards as make_ppo_env."""
    pytest.importorskip("stable_baselines3", reason="PPO needs the rl extra: pip install -e '.[rl]'")
    from mimo_radar_env import load_scenario
    from mimo_radar_env.sb3 import NativeVecEnv

    scenario = load_scenario("paper-3")
    venv = NativeVecEnv(scenario, num_envs=2, seed=5)
    singles = [make_ppo_env(scenario) for _ in range(2)]
    batch = venv.reset()
    for i, env in enumerate(singles):
        obs, _ = env.reset(seed=5 + i)
        np.testing.assert_allclose(batch[i], obs, rtol=1e-6)
    assert venv.observation_space == singles[0].observation_space
    assert venv.action_space == singles[0].action_space
    rng = np.random.default_rng(0)
    for _ in range(5):
        actions = rng.integers(0, venv.action_space.n, size=2)
        batch, rewards, dones, _ = venv.step(actions)
        for i, env in enumerate(singles):
            obs, reward, _, _, _ = env.step(actions[i])
            np.testing.assert_allclose(batch[i], obs, rtol=1e-6)
            assert rewards[i] == pytest.approx(reward, rel=1e-6)
        assert not dones.any()


def test_native_vec_env_names_an_unknown_version():
    """An unknown ``version`` was a bare ``KeyError: 'v9'``."""
    pytest.importorskip("stable_baselines3", reason="PPO needs the rl extra: pip install -e '.[rl]'")
    from mimo_radar_env.sb3 import NativeVecEnv

    with pytest.raises(ValueError, match=r"env version must be one of \['v0', 'v1'\], got 'v9'"):
        NativeVecEnv("paper-1-v1", num_envs=2, version="v9")
    assert NativeVecEnv("paper-1", num_envs=2, version="v0").env.options.lambda_scale == "linear"
