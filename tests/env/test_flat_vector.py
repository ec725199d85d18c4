"""The Flat ids' vector entry point: the batch engine with the Flat env's action and features,
equal to N single Flat envs trial for trial, across the next-step autoreset."""

import gymnasium as gym
import numpy as np
import pytest

import mimo_radar_env  # noqa: F401  (registers the ids)
from mimo_radar_env.wrappers import MimoRadarSelectFlatVectorEnv


@pytest.mark.parametrize("action", ["discrete", "scores"])
def test_the_flat_vector_env_equals_single_flat_envs_trial_for_trial(action):
    trials, horizon, seed = 3, 4, 11
    venv = gym.make_vec(
        "MimoRadarSelectFlat-v1",
        num_envs=trials,
        vectorization_mode="vector_entry_point",
        horizon=horizon,
        action=action,
    )
    assert isinstance(venv.unwrapped, MimoRadarSelectFlatVectorEnv)
    singles = [gym.make("MimoRadarSelectFlat-v1", horizon=horizon, action=action) for _ in range(trials)]
    assert venv.single_action_space == singles[0].action_space
    assert venv.single_observation_space == singles[0].observation_space
    rng = np.random.default_rng(0)
    obs, _ = venv.reset(seed=seed)
    single_obs = [env.reset(seed=seed + i)[0] for i, env in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(single_obs))
    for step in range(2 * horizon + 1):  # two episodes: the step after the first resets all trials
        if action == "scores":
            actions = rng.uniform(-1, 1, venv.action_space.shape).astype(np.float32)
        else:
            actions = rng.integers(0, venv.single_action_space.n, trials)
        obs, reward, terminated, truncated, _ = venv.step(actions)
        if step == horizon:  # the autoreset step: single envs are reset without a seed
            expected = [env.reset()[0] for env in singles]
            np.testing.assert_array_equal(obs, np.stack(expected))
            assert not truncated.any() and (reward == 0).all()
            continue
        for i, env in enumerate(singles):
            o, r, te, tr, _ = env.step(actions[i])
            np.testing.assert_array_equal(obs[i], o)
            assert reward[i] == r and terminated[i] == te and truncated[i] == tr
    assert truncated.all()


def test_the_flat_vector_env_gives_masks_and_refuses_a_bad_action_form():
    venv = MimoRadarSelectFlatVectorEnv(num_envs=2, scenario="paper-1-v1")
    assert venv.action_form == "discrete" and venv.action_masks().shape == (2, 6 * 20)  # C(4, 2) C(6, 3)
    assert venv.action_masks().all()
    with pytest.raises(ValueError, match=r"action must be one of \['auto', 'discrete', 'scores'\], got 'x'"):
        MimoRadarSelectFlatVectorEnv(num_envs=2, action="x")
    scores = MimoRadarSelectFlatVectorEnv(num_envs=2, action="scores")
    with pytest.raises(ValueError, match="station-score actions have no mask"):
        scores.action_masks()
    venv.reset(seed=0)
    with pytest.raises(ValueError, match=r"super-arm index must be in \[0, 120\)"):
        venv.step(np.array([0, 120]))
