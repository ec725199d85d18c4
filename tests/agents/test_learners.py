"""The learners beside PPO (sb3-contrib's MaskablePPO and RecurrentPPO): trained by the same
command, registered as agents, batched over trials; several seeds, resumably."""

import dataclasses
import json

import numpy as np
import pytest

pytest.importorskip("sb3_contrib", reason="MaskablePPO and RecurrentPPO need the rl extra")

import agents  # noqa: E402
from benchmarks.training import load_hyperparams, seed_folder, train_ppo  # noqa: E402
from mimo_radar_env import MimoRadarSelectVectorEnv, load_scenario  # noqa: E402

SHORT = dataclasses.replace(load_scenario("paper-1-v1"), horizon=20)


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    folder = tmp_path_factory.mktemp("learners")
    for algo in ("ppo", "maskable-ppo", "recurrent-ppo"):
        train_ppo(SHORT, 256, folder / algo, seed=3, progress=False, algo=algo)
    return folder


def _actions(agent, trials, steps=8, seed=0):
    env = MimoRadarSelectVectorEnv(num_envs=trials, scenario=SHORT)
    obs, _ = env.reset(seed=seed)
    agent.reset(obs)
    played = []
    for _ in range(steps):
        action = agent.act(obs)
        obs, reward, *_ = env.step(action)
        agent.update(obs, reward)
        played.append(action)
    return np.stack(played, axis=1)  # (B, steps, M + N)


def test_each_learner_is_a_registered_agent_that_plays_valid_super_arms(trained):
    for algo in ("ppo", "maskable-ppo", "recurrent-ppo"):
        agent = agents.make_agent(algo, SHORT, path=trained / algo, seed=0)
        assert type(agent).learner.name == algo
        actions = _actions(agent, trials=3)
        assert (actions[..., :4].sum(-1) == 2).all() and (actions[..., 4:].sum(-1) == 3).all()
        assert json.loads((trained / algo / "ppo.json").read_text())["algo"] == algo
        assert (trained / algo / "curve.csv").read_text().startswith("timesteps,episodes,return,armse")


def test_the_recurrent_agent_keeps_each_trials_lstm_state(trained):
    """Three trials in one batch act as three agents of one trial each: the LSTM state is
    carried per trial, and started afresh at reset."""
    path = trained / "recurrent-ppo"
    batched = _actions(agents.make_agent("recurrent-ppo", SHORT, path=path, seed=0), trials=3)
    for trial in range(3):
        alone = agents.make_agent("recurrent-ppo", SHORT, path=path, seed=0)
        single = MimoRadarSelectVectorEnv(num_envs=1, scenario=SHORT)
        obs, _ = single.reset(seed=[trial])
        alone.reset(obs)
        for step in range(8):
            action = alone.act(obs)
            np.testing.assert_array_equal(action[0], batched[trial, step])
            obs, reward, *_ = single.step(action)
            alone.update(obs, reward)
    again = _actions(agents.make_agent("recurrent-ppo", SHORT, path=path, seed=0), trials=3)
    np.testing.assert_array_equal(again, batched)  # a reset starts the state afresh


def test_maskable_ppo_with_every_action_valid_learns_what_ppo_learns(trained):
    """On these layouts every super arm is valid, so the mask allows all actions and MaskablePPO
    is PPO: same seed, same weights, same actions (what the RL study's tables show)."""
    ppo = _actions(agents.make_agent("ppo", SHORT, path=trained / "ppo", seed=0), trials=4)
    masked = _actions(
        agents.make_agent("maskable-ppo", SHORT, path=trained / "maskable-ppo", seed=0), trials=4
    )
    np.testing.assert_array_equal(ppo, masked)


def test_each_learner_reads_its_own_hyperparameter_file():
    assert load_hyperparams(algo="recurrent-ppo")["policy"] == "MlpLstmPolicy"
    assert load_hyperparams(algo="maskable-ppo")["policy"] == "MlpPolicy"
    with pytest.raises(ValueError, match="policy must be one of \\['MlpLstmPolicy'\\] for recurrent-ppo"):
        load_hyperparams("benchmarks/hyperparams/ppo.yml", algo="recurrent-ppo")
    with pytest.raises(ValueError, match="algo must be one of \\['ppo', 'maskable-ppo', 'recurrent-ppo'\\]"):
        load_hyperparams(algo="dqn")
    with pytest.raises(ValueError, match="maskable-ppo masks a Discrete action"):
        train_ppo(SHORT, 16, "unused", algo="maskable-ppo", action="scores")


def test_several_seeds_train_once_each_and_resume(tmp_path):
    out = tmp_path / "seeds"
    first = train_ppo(SHORT, 128, out, seed=0, seeds=2, workers=2, progress=False)
    assert set(first["seeds"]) == {0, 1}
    models = {s: seed_folder(out, s) / "model.zip" for s in (0, 1)}
    stamps = {s: m.stat().st_mtime_ns for s, m in models.items()}
    assert first["seeds"][0]["seed"] == 0 and first["seeds"][1]["seed"] == 1
    # a training killed before its end (no finished ppo.json) is trained again; the other is kept
    (seed_folder(out, 1) / "ppo.json").unlink()
    train_ppo(SHORT, 128, out, seed=0, seeds=2, workers=2, progress=False)
    assert models[0].stat().st_mtime_ns == stamps[0] and models[1].stat().st_mtime_ns != stamps[1]
    # the same seeds with the same job: nothing to do; another job into the same folder: refused
    train_ppo(SHORT, 128, out, seed=0, seeds=2, progress=False)
    assert models[0].stat().st_mtime_ns == stamps[0]
    with pytest.raises(ValueError, match="holds another training"):
        train_ppo(SHORT, 256, out, seed=0, seeds=2, progress=False)
    # two seeds learn different policies
    a, b = (np.load(seed_folder(out, s) / "vecnormalize.npz")["mean"] for s in (0, 1))
    assert not np.array_equal(a, b)
