"""Third-party clients on the env as they are used (each skipped with its reason when absent)."""

import numpy as np
import pytest

from mimo_radar_env.wrappers import SuperArmDiscreteAction, make_ppo_env


def test_maskable_ppo_trains_on_the_discrete_wrapper_and_every_action_is_valid():
    sb3_contrib = pytest.importorskip(
        "sb3_contrib", reason="MaskablePPO needs sb3-contrib (in the test extra: pip install -e '.[rl,test]')"
    )
    from sb3_contrib.common.maskable.utils import get_action_masks
    from stable_baselines3.common.env_util import make_vec_env

    venv = make_vec_env(lambda: make_ppo_env(horizon=40, action="discrete"), n_envs=2, seed=0)
    masks = get_action_masks(venv)
    assert masks.shape == (2, 120) and masks.all()
    model = sb3_contrib.MaskablePPO(
        "MlpPolicy", venv, n_steps=64, batch_size=32, n_epochs=1, seed=0, verbose=0
    )
    model.learn(total_timesteps=256)

    env = make_ppo_env(horizon=40, action="discrete")
    obs, _ = env.reset(seed=1)
    valid = []
    for _ in range(40):
        mask = env.get_wrapper_attr("action_masks")()
        action, _ = model.predict(obs, action_masks=mask, deterministic=False)
        assert mask[int(action)]
        obs, _, _, truncated, info = env.step(action)
        valid.append(bool(info["action_valid"]))
        if truncated:
            break
    assert len(valid) == 40 and all(valid)


def test_action_masks_allow_exactly_the_valid_super_arms():
    """Brute force: every station subset of the right sizes is one allowed action, each once, and
    each allowed action the env accepts as valid."""
    from itertools import combinations

    base = make_ppo_env(horizon=50).unwrapped
    env = SuperArmDiscreteAction(base)
    sc = base.scenario
    mask = env.action_masks()
    assert mask.dtype == np.bool_ and mask.shape == (env.action_space.n,)
    allowed = {tuple(env.action(i)) for i in np.flatnonzero(mask)}
    brute = set()
    for tx in combinations(range(sc.num_tx), sc.tx_per_step):
        for rx in combinations(range(sc.num_rx), sc.rx_per_step):
            bits = np.zeros(sc.num_tx + sc.num_rx, np.int8)
            bits[list(tx)] = 1
            bits[[sc.num_tx + r for r in rx]] = 1
            brute.add(tuple(bits))
    assert allowed == brute and int(mask.sum()) == len(brute)
    env.reset(seed=0)
    for i in np.flatnonzero(mask)[:: max(1, len(brute) // 10)]:
        assert env.step(int(i))[4]["action_valid"]


def test_stone_soup_recipe_tracks_from_the_info_measurements():
    pytest.importorskip(
        "stonesoup", reason="the recipe needs Stone Soup (in the test extra: pip install -e '.[test]')"
    )
    import importlib.util
    from pathlib import Path

    path = Path(__file__).parents[2] / "docs" / "examples" / "stone_soup_tracker.py"
    spec = importlib.util.spec_from_file_location("stone_soup_tracker", path)
    recipe = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(recipe)
    result = recipe.run(steps=150, seed=2)
    # a UKF with the true NCV model and the env's IMM-UKF, both centralised, on the same data
    assert 0.2 < result["stone_soup_ukf"] < 5.0
    assert 0.75 < result["stone_soup_ukf"] / result["env_imm_ukf"] < 1.25


def test_flat_variant_works_by_id_with_gymnasium_and_sb3():
    import gymnasium as gym

    sb3 = pytest.importorskip("stable_baselines3", reason="PPO needs the rl extra: pip install -e '.[rl]'")
    from stable_baselines3.common.env_checker import check_env
    from stable_baselines3.common.env_util import make_vec_env

    env = gym.make("MimoRadarSelectFlat-v1", horizon=30)
    assert env.action_space == gym.spaces.Discrete(120)
    assert env.observation_space.dtype == np.float32 and env.observation_space.shape == (80,)
    assert env.spec.max_episode_steps == 30
    check_env(env)
    obs, _ = env.reset(seed=0)
    assert np.abs(obs).max() < 10  # features on a normalised scale
    remade = gym.make(env.spec)  # the spec records the wrappers and recreates the same env
    np.testing.assert_array_equal(remade.reset(seed=4)[0], env.reset(seed=4)[0])
    venv = make_vec_env("MimoRadarSelectFlat-v1", n_envs=2, seed=0, env_kwargs={"horizon": 30})
    sb3.PPO("MlpPolicy", venv, n_steps=32, batch_size=32, n_epochs=1, seed=0).learn(64)
    v0 = gym.make("MimoRadarSelectFlat-v0", horizon=5)
    assert v0.unwrapped.scenario.name == "paper-1" and v0.unwrapped.options.lambda_scale == "linear"


def test_torchrl_runs_the_flat_variant_by_id():
    pytest.importorskip(
        "torchrl",
        reason="torchrl shadows this project's 'benchmarks' package; .ci/wheel-check runs it in its own venv",
    )
    from torchrl.envs import GymEnv
    from torchrl.envs.utils import check_env_specs

    env = GymEnv("MimoRadarSelectFlat-v1", horizon=20)
    check_env_specs(env)
    rollout = env.rollout(50)
    assert rollout.batch_size[0] == 20 and bool(rollout["next", "truncated"][-1])


@pytest.mark.slow
def test_rl_zoo3_trains_with_the_shipped_hyperparameter_file(tmp_path):
    pytest.importorskip("rl_zoo3", reason="needs rl-zoo3 (in the test extra: pip install -e '.[rl,test]')")
    import subprocess
    import sys
    from pathlib import Path

    conf = Path(__file__).parents[2] / "benchmarks" / "hyperparams" / "ppo.yml"
    command = [sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", "MimoRadarSelectFlat-v1"]
    command += ["--gym-packages", "mimo_radar_env", "-conf", str(conf), "-n", "256", "--seed", "0"]
    command += ["--env-kwargs", "horizon:40", "-f", str(tmp_path), "--eval-freq", "-1"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "'norm_obs': True, 'norm_reward': False" in done.stdout  # the file's normalisation, as meant
    assert list(tmp_path.glob("ppo/MimoRadarSelectFlat-v1_*/MimoRadarSelectFlat-v1.zip"))


def test_train_ppo_reads_the_rl_zoo3_entries():
    from benchmarks.training import load_hyperparams, normalize_kwargs

    for key in ("MimoRadarSelectFlat-v1", "MimoRadarSelectFlat-v0"):
        params = load_hyperparams(key=key)
        assert params["policy_kwargs"] == {"net_arch": [128, 128]}
        assert normalize_kwargs(params) == {"norm_obs": True, "norm_reward": False, "gamma": 0.9}
    assert normalize_kwargs({"normalize": True}) == {}  # rl-zoo3: observations and rewards
    assert normalize_kwargs({}) is None
    with pytest.raises(ValueError, match="has no entry 'MimoRadarSelect-v9'"):
        load_hyperparams(key="MimoRadarSelect-v9")
