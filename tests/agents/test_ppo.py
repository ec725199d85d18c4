"""PPO: wrappers with valid actions by construction, a short training run, the harness path."""

import json
import math
import subprocess
import sys
import warnings
from itertools import combinations

import gymnasium as gym
import numpy as np
import pytest

from mimo_radar_env.wrappers import (
    RadarFeatureObservation,
    StationScoreAction,
    SuperArmDiscreteAction,
    make_ppo_env,
)
from tests.helpers import large_scenario, vector_env


def test_discrete_super_arm_index_is_a_bijection():
    env = SuperArmDiscreteAction(gym.make("MimoRadarSelect-v0", scenario="paper-1"))
    assert env.action_space.n == math.comb(4, 2) * math.comb(6, 3) == 120
    actions = env.index.to_action(np.arange(120))
    assert (actions[:, :4].sum(axis=1) == 2).all() and (actions[:, 4:].sum(axis=1) == 3).all()
    every = {(t, r) for t in combinations(range(4), 2) for r in combinations(range(6), 3)}
    seen = {(tuple(np.flatnonzero(a[:4])), tuple(np.flatnonzero(a[4:]))) for a in actions}
    assert seen == every  # onto and, with 120 distinct images of 120 indices, one-to-one
    env.reset(seed=0)
    for i in (0, 57, 119):
        _, _, _, _, info = env.step(i)
        assert info["action_valid"]
    with pytest.raises(ValueError, match=r"super-arm index must be in \[0, 120\)"):
        env.index.to_action(120)


def test_station_scores_give_valid_selections_on_paper_and_16x16_layouts():
    rng = np.random.default_rng(0)
    for scenario in ("paper-3", large_scenario(16, 16, 5)):
        env = StationScoreAction(gym.make("MimoRadarSelect-v0", scenario=scenario))
        sc = env.unwrapped.scenario
        env.reset(seed=1)
        for _ in range(20):
            scores = rng.uniform(-1, 1, size=sc.num_tx + sc.num_rx).astype(np.float32)
            action = env.action(scores)
            assert action[: sc.num_tx].sum() == sc.tx_per_step and action[sc.num_tx :].sum() == sc.rx_per_step
            top_tx = np.argsort(-scores[: sc.num_tx])[: sc.tx_per_step]
            assert set(np.flatnonzero(action[: sc.num_tx])) == set(top_tx)
            assert env.step(scores)[4]["action_valid"]
        env.step(np.zeros(sc.num_tx + sc.num_rx, dtype=np.float32))  # ties resolve to a valid selection
    with pytest.raises(ValueError, match="use StationScoreAction"):
        SuperArmDiscreteAction(gym.make("MimoRadarSelect-v0", scenario=large_scenario(16, 16, 5)))
    assert isinstance(make_ppo_env(large_scenario(16, 16, 5)).env, StationScoreAction)
    assert isinstance(make_ppo_env("paper-1-v1").env, SuperArmDiscreteAction)


def test_features_track_age_and_latest_samples():
    env = make_ppo_env("paper-1-v1")
    assert isinstance(env, RadarFeatureObservation)
    obs, _ = env.reset(seed=0)
    assert obs.shape == env.observation_space.shape and obs.dtype == np.float32
    features = env.features
    assert (features.age == 0).all()
    env.step(0)  # super arm 0: TX1, TX2; RX1, RX2, RX3
    probed = np.zeros((4, 6), bool)
    probed[np.ix_([0, 1], [0, 1, 2])] = True
    assert (features.age[0][probed] == 0).all() and (features.age[0][~probed] == 1).all()


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


def test_short_training_saves_reloads_and_acts_everywhere(tmp_path):
    pytest.importorskip("stable_baselines3", reason="PPO needs the rl extra: pip install -e '.[rl]'")
    import agents
    from agents import PPOAgent
    from benchmarks.cli import main
    from benchmarks.training import train_ppo

    meta = train_ppo("paper-1-v1", 2048, tmp_path / "ppo", seed=3, progress=False, tensorboard=True)
    assert meta["trained_timesteps"] >= meta["timesteps"] == 2048  # whole rollouts, said as run
    assert list((tmp_path / "ppo" / "tensorboard").rglob("events.out.tfevents.*"))
    assert (tmp_path / "ppo" / "model.zip").exists() and (tmp_path / "ppo" / "vecnormalize.npz").exists()
    assert json.loads((tmp_path / "ppo" / "ppo.json").read_text())["timesteps"] == 2048 == meta["timesteps"]
    agent = PPOAgent("paper-1", tmp_path / "ppo" / "model.zip")
    assert isinstance(agent, agents.Agent)
    # single env
    env = gym.make("MimoRadarSelect-v0", scenario="paper-1")
    obs, _ = env.reset(seed=0)
    agent.reset(obs)
    for _ in range(20):
        obs, reward, _, _, info = env.step(agent.act(obs))
        agent.update(obs, reward)
        assert info["action_valid"]
    # vector env
    venv = vector_env("MimoRadarSelect-v0", 5)
    obs, _ = venv.reset(seed=0)
    agent.reset(obs)
    for _ in range(20):
        obs, reward, _, _, info = venv.step(agent.act(obs))
        agent.update(obs, reward)
        assert info["action_valid"].all()
    # the harness, next to the bandits on the same trials
    out = tmp_path / "bench"
    model = str(tmp_path / "ppo" / "model.zip")
    assert (
        main(
            [
                "run",
                "--scenario",
                "paper-1-v1",
                "--policies",
                f"ppo:{model},ucb1",
                "--trials",
                "3",
                "--steps",
                "30",
                "--workers",
                "1",
                "--no-figures",
                "--quiet",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["policies"]) == {f"ppo:{model}", "ucb1"}


def test_core_imports_and_runs_without_the_rl_extra():
    code = (
        "import sys; sys.modules['stable_baselines3'] = None; sys.modules['torch'] = None\n"
        "import gymnasium as gym, mimo_radar_env, agents, benchmarks.harness, mimo_radar_env.wrappers\n"
        "env = gym.make('MimoRadarSelect-v0'); env.reset(seed=0); env.step(env.action_space.sample())\n"
        "from agents import PPOAgent\n"
        "from gymnasium.error import DependencyNotInstalled\n"
        "try:\n    PPOAgent('paper-1', 'x.zip')\nexcept DependencyNotInstalled as e:\n    print('ERR', e)\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "ERR PPO needs stable_baselines3, in the rl extra" in result.stdout


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


# ---------------------------------------------------------------- normalisation, the ecosystem's way
@pytest.fixture(scope="module")
def small_model(tmp_path_factory):
    pytest.importorskip("stable_baselines3", reason="PPO needs the rl extra")
    from benchmarks.training import train_ppo

    folder = tmp_path_factory.mktemp("ppo") / "small"
    train_ppo("paper-1-v1", 128, folder, seed=0, progress=False)
    return folder


def test_sb3s_own_vecnormalize_load_reads_what_train_ppo_saves(small_model):
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    venv = VecNormalize.load(
        str(small_model / "vecnormalize.pkl"), DummyVecEnv([lambda: gym.make("MimoRadarSelectFlat-v1")])
    )
    with np.load(small_model / "vecnormalize.npz") as stats:
        np.testing.assert_array_equal(venv.obs_rms.mean, stats["mean"])
        np.testing.assert_array_equal(venv.obs_rms.var, stats["var"])
    model = PPO.load(small_model / "model.zip", device="cpu")
    actions, _ = model.predict(venv.reset(), deterministic=True)
    assert venv.action_space.contains(int(actions[0]))


def test_a_model_in_rl_zoo3s_layout_runs_with_its_statistics_or_is_refused(small_model, tmp_path):
    import shutil

    from agents import PPOAgent

    # rl-zoo3: logs/ppo/ENV_1/ENV.zip, the statistics in logs/ppo/ENV_1/ENV/vecnormalize.pkl
    run = tmp_path / "MimoRadarSelectFlat-v1_1"
    (run / "MimoRadarSelectFlat-v1").mkdir(parents=True)
    model = run / "MimoRadarSelectFlat-v1.zip"
    shutil.copy(small_model / "model.zip", model)
    stats = run / "MimoRadarSelectFlat-v1" / "vecnormalize.pkl"
    shutil.copy(small_model / "vecnormalize.pkl", stats)
    with pytest.raises(
        ValueError, match=rf"statistics in {stats} \(rl-zoo3's layout\), which are not beside it"
    ):
        PPOAgent("paper-1-v1", model)
    with pytest.raises(ValueError, match="is a pickle .* pass allow_pickle=true"):
        PPOAgent("paper-1-v1", model, normalization=stats)
    with pytest.warns(UserWarning, match="unpickling"):
        agent = PPOAgent("paper-1-v1", model, normalization=stats, allow_pickle=True)
    reference = PPOAgent("paper-1-v1", small_model)  # train-ppo's folder: the npz beside the model
    np.testing.assert_array_equal(agent.normalization.obs_rms.mean, reference.normalization.obs_rms.mean)
    assert reference.normalization_file == small_model / "vecnormalize.npz"
    named = PPOAgent("paper-1-v1", model, normalization=small_model / "vecnormalize.npz")
    assert named.normalization_file == small_model / "vecnormalize.npz"
    with pytest.raises(ValueError, match="normalization file .* does not exist"):
        PPOAgent("paper-1-v1", model, normalization=tmp_path / "none.npz")


def test_the_harness_records_the_statistics_the_agent_applies(small_model, tmp_path):
    from benchmarks.harness import make_config

    config = make_config("paper-1-v1", [f"ppo:{small_model}"], trials=2, steps=2)
    files = config.policy_files[f"ppo:{small_model}"]
    assert set(files) == {str(small_model / "model.zip"), str(small_model / "vecnormalize.npz")}
