"""train-ppo's learners: a short training saves, reloads and acts everywhere, with the statistics
SB3 reads."""

import json

import gymnasium as gym
import numpy as np
import pytest

from tests.helpers import vector_env


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
    argv = "run --scenario paper-1-v1 --trials 3 --steps 30 --workers 1 --no-figures --quiet".split()
    assert main([*argv, "--policies", f"ppo:{model},ucb1", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["policies"]) == {f"ppo:{model}", "ucb1"}


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


def test_trainings_in_worker_processes_are_submitted_longest_first(tmp_path, monkeypatch):
    """With several workers the longest trainings start first (the last to finish are short);
    each training is its own seeded run, so the order moves no number."""
    import concurrent.futures
    import contextlib

    from benchmarks import backends, training

    submitted = []

    class InOrder(concurrent.futures.Executor):
        def close(self):
            pass

        def submit(self, fn, *args):
            submitted.append((args[0]["timesteps"], args[2]))
            future = concurrent.futures.Future()
            future.set_result({"timesteps": args[0]["timesteps"]})
            return future

    monkeypatch.setattr(backends, "worker_pool", lambda workers: contextlib.nullcontext(InOrder()))
    tasks = [
        ({"timesteps": t}, tmp_path / f"t{t}", seed) for t, seed in ((600, 0), (5000, 1), (600, 2), (2000, 3))
    ]
    done = training.train_jobs(tasks, workers=2, progress=False, device="cpu")
    assert submitted == [(5000, 1), (2000, 3), (600, 0), (600, 2)]
    assert {key: meta["timesteps"] for key, meta in done.items()} == {
        (tmp_path / f"t{t}", seed): t for t, seed in ((600, 0), (5000, 1), (600, 2), (2000, 3))
    }
