"""torch-ppo, the project's own PPO: GAE and the loss against their definitions, a training's files,
reproducible weights, the agent it makes, refusals before anything is written, and both learners
against random."""

import dataclasses
import json

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="torch-ppo needs the rl extra")

import agents  # noqa: E402
from agents.networks import ActorCritic  # noqa: E402
from benchmarks import torch_ppo  # noqa: E402
from benchmarks.training import normalize_kwargs, train_ppo  # noqa: E402
from mimo_radar_env import load_scenario  # noqa: E402

SHORT = dataclasses.replace(load_scenario("paper-1-v1"), horizon=20)


def test_gae_matches_its_definition_episode_by_episode():
    """A_t = sum_l (gamma lambda)^l delta_{t+l} over the rest of the episode, delta_t = r_t +
    gamma V_{t+1} (0 past an episode's end) - V_t; the rollout's last value closes the tail."""
    rng = np.random.default_rng(0)
    S, B, gamma, lam = 13, 4, 0.9, 0.8
    rewards, values, last = rng.normal(size=(S, B)), rng.normal(size=(S, B)), rng.normal(size=B)
    dones = (rng.random((S, B)) < 0.2).astype(float)
    adv, ret = torch_ppo.compute_gae(*map(torch.as_tensor, (rewards, values, dones, last)), gamma, lam)
    expected = np.zeros((S, B))
    for b in range(B):
        for t in range(S):
            total, factor = 0.0, 1.0
            for u in range(t, S):
                following = last[b] if u == S - 1 else values[u + 1, b]
                delta = rewards[u, b] + gamma * following * (1 - dones[u, b]) - values[u, b]
                total += factor * delta
                if dones[u, b]:
                    break
                factor *= gamma * lam
            expected[t, b] = total
    np.testing.assert_allclose(adv.numpy(), expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ret.numpy(), expected + values, rtol=1e-12, atol=1e-12)


def test_the_loss_is_the_clipped_surrogate_value_and_entropy_terms():
    torch.manual_seed(0)
    network = ActorCritic(6, 5, (8,))
    config = torch_ppo.PPOConfig(ent_coef=0.01, vf_coef=0.5, clip_range=0.2)
    obs = torch.randn(10, 6)
    actions = torch.randint(0, 5, (10,))
    old = torch.randn(10) - 1.6
    adv, ret = torch.randn(10, dtype=torch.float64).float(), torch.randn(10)
    loss, stats = torch_ppo.ppo_loss(network, config, obs, actions, old, adv, ret)
    with torch.no_grad():
        logits, values = network(obs)
    logits, values = logits.double().numpy(), values.double().numpy()
    log_p = logits - np.log(np.exp(logits).sum(1, keepdims=True))
    new = log_p[np.arange(10), actions.numpy()]
    a = adv.double().numpy()
    a = (a - a.mean()) / (a.std(ddof=1) + 1e-8)
    ratio = np.exp(new - old.double().numpy())
    surrogate = -np.minimum(a * ratio, a * np.clip(ratio, 0.8, 1.2)).mean()
    value = ((ret.double().numpy() - values) ** 2).mean()
    entropy = -(np.exp(log_p) * log_p).sum(1).mean()
    assert float(loss.detach()) == pytest.approx(surrogate - 0.01 * entropy + 0.5 * value, rel=1e-5)
    assert float(stats["value_loss"].detach()) == pytest.approx(value, rel=1e-5)


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    folder = tmp_path_factory.mktemp("torch-ppo")
    meta = train_ppo(SHORT, 600, folder, seed=2, algo="torch-ppo", n_envs=6, progress=False)
    return folder, meta


def test_a_training_writes_the_model_its_statistics_curve_and_record(trained):
    folder, meta = trained
    assert {p.name for p in folder.iterdir()} >= {"model.pt", "vecnormalize.npz", "curve.csv", "ppo.json"}
    n_steps = 256  # the shipped entry's: whole rollouts of n_steps x n_envs
    assert meta["trained_timesteps"] == 1 * n_steps * 6 and meta["device"] == "cpu"
    assert json.loads((folder / "ppo.json").read_text())["algo"] == "torch-ppo"
    # when it trained, on the wall clock: ended before the record was written, after it began
    written = (folder / "ppo.json").stat().st_mtime
    assert meta["trained_from_unix_s"] + meta["train_wall_s"] <= written + 1e-3
    assert meta["trained_from_unix_s"] > written - 3600
    rows = (folder / "curve.csv").read_text().splitlines()
    assert rows[0] == "timesteps,episodes,return,armse"
    # 256 steps of 20-step episodes end 12 episodes in each of the 6 trials
    assert rows[1].startswith("1536,72,")


def test_the_same_seed_trains_the_same_weights(trained, tmp_path):
    folder, _ = trained
    train_ppo(SHORT, 600, tmp_path, seed=2, algo="torch-ppo", n_envs=6, progress=False)
    first = torch.load(folder / "model.pt", weights_only=True)["weights"]
    again = torch.load(tmp_path / "model.pt", weights_only=True)["weights"]
    assert all(torch.equal(first[k], again[k]) for k in first)


def test_the_step_replayed_as_a_graph_trains_the_same_weights(trained, tmp_path):
    """``device_mode="graph"`` (the traced step; on the CPU the traced function runs) is an
    execution setting: the same curve and weights as the eager step, recorded in ppo.json."""
    folder, _ = trained
    meta = train_ppo(
        SHORT, 600, tmp_path, seed=2, algo="torch-ppo", n_envs=6, progress=False, device_mode="graph"
    )
    assert meta["device_mode"] == "graph"
    first = torch.load(folder / "model.pt", weights_only=True)["weights"]
    again = torch.load(tmp_path / "model.pt", weights_only=True)["weights"]
    assert all(torch.equal(first[k], again[k]) for k in first)
    assert (tmp_path / "curve.csv").read_text() == (folder / "curve.csv").read_text()


def test_seeds_trained_in_processes_sharing_a_device_train_the_same_weights(tmp_path):
    """With a device and several workers, each seed trains in a worker process of its own on
    that device (here CPU torch, one thread a worker): seed 2 gives the weights and curve it
    gives alone in this process on one thread (another thread count sums in another order)."""
    folder, threads = tmp_path / "alone", torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        train_ppo(SHORT, 600, folder, seed=2, algo="torch-ppo", device="cpu", n_envs=6, progress=False)
    finally:
        torch.set_num_threads(threads)
    result = train_ppo(
        SHORT, 600, tmp_path / "shared", seed=2, seeds=2, workers=2, algo="torch-ppo", device="cpu",
        n_envs=6, progress=False,
    )  # fmt: skip
    assert sorted(result["seeds"]) == [2, 3]
    first = torch.load(folder / "model.pt", weights_only=True)["weights"]
    again = torch.load(tmp_path / "shared/seed-2/model.pt", weights_only=True)["weights"]
    assert all(torch.equal(first[k], again[k]) for k in first)
    assert (tmp_path / "shared/seed-2/curve.csv").read_text() == (folder / "curve.csv").read_text()
    other = torch.load(tmp_path / "shared/seed-3/model.pt", weights_only=True)["weights"]
    assert not all(torch.equal(first[k], other[k]) for k in first)


def _play(agent, device=None, trials=3, steps=6):
    episode = agents.Rollout(agent, agents.make_env(agent, trials, device=device), seed=5)
    played = [np.asarray(step.action.cpu() if device else step.action) for step in episode.run(steps)]
    return np.stack(played, axis=1)


def test_the_agent_plays_valid_super_arms_the_same_on_numpy_and_on_a_device(trained):
    folder, _ = trained
    on_numpy = _play(agents.make_agent("torch-ppo", SHORT, path=folder))
    assert (on_numpy[..., :4].sum(-1) == 2).all() and (on_numpy[..., 4:].sum(-1) == 3).all()
    on_device = _play(agents.make_agent("torch-ppo", SHORT, path=folder / "model.pt"), device="cpu")
    np.testing.assert_array_equal(on_numpy, on_device)
    assert "torch-ppo" in agents.learned_agents()


def test_the_agent_refuses_a_model_of_another_layout(trained):
    folder, _ = trained
    with pytest.raises(ValueError, match="train it on this layout"):
        agents.make_agent("torch-ppo", "paper-3-v1", path=folder)  # two targets
    with pytest.raises(ValueError, match="does not exist"):
        agents.make_agent("torch-ppo", SHORT, path=folder / "missing")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"algo": "ppo", "device": "cpu"}, "takes no device"),
        ({"algo": "torch-ppo", "device": "tpu"}, r"'cuda:N', or no device, got 'tpu'"),
        ({"algo": "torch-ppo", "action": "scores"}, "Discrete"),
        ({"algo": "torch-ppo", "n_envs": 0}, "n_envs"),
        ({"algo": "torch-ppo", "device_mode": "fused"}, "device_mode must be one of eager, graph"),
        ({"algo": "ppo", "device_mode": "graph"}, r"takes no device_mode \('graph'\)"),
    ],
)
def test_bad_requests_are_refused_before_anything_is_written(tmp_path, kwargs, match):
    with pytest.raises(ValueError, match=match):
        train_ppo(SHORT, 16, tmp_path / "out", progress=False, **kwargs)
    assert not (tmp_path / "out").exists()


def test_an_sb3_key_torch_ppo_does_not_implement_is_refused_by_name():
    with pytest.raises(ValueError, match=r"does not implement \['use_sde'\]"):
        torch_ppo.PPOConfig.from_hyperparams({"use_sde": True})
    params = {"n_envs": 8, "gamma": 0.9, "normalize": {"norm_obs": True, "norm_reward": False},
              "policy_kwargs": {"net_arch": [32]}}  # fmt: skip
    config = torch_ppo.PPOConfig.from_hyperparams(params, n_envs=512, normalize=normalize_kwargs(params))
    assert (config.n_envs, config.gamma, config.net_arch, config.normalize_obs) == (512, 0.9, (32,), True)


def _returns(agent, trials=200, seed=10_000):
    episode = agents.Rollout(agent, agents.make_env(agent, trials), seed=seed)
    return sum(step.reward for step in episode.run(SHORT.horizon))


@pytest.mark.slow
def test_both_learners_beat_random_and_land_within_each_others_across_seed_interval(tmp_path):
    """SB3 PPO and torch-ppo with the same hyperparameters and budget (six rollouts), four
    seeds each, scored on the same 200 trials: every trained policy beats random there (paired,
    the difference's 95 % interval above 0), and the learners do not differ beyond the spread
    over seeds: Welch's 95 % interval of the difference of their means over seeds holds 0."""
    from scipy import stats

    random_returns = _returns(agents.make_agent("random", SHORT, seed=0))
    means = {}
    for algo in ("ppo", "torch-ppo"):
        scores = []
        for seed in range(4):
            train_ppo(SHORT, 12_000, tmp_path / algo / str(seed), seed=seed, algo=algo, progress=False)
            returns = _returns(agents.make_agent(algo, SHORT, path=tmp_path / algo / str(seed)))
            gain = returns - random_returns
            assert gain.mean() - 1.96 * gain.std(ddof=1) / np.sqrt(len(gain)) > 0, (algo, seed)
            scores.append(returns.mean())
        means[algo] = np.array(scores)
    welch = stats.ttest_ind(means["ppo"], means["torch-ppo"], equal_var=False)
    low, high = welch.confidence_interval(0.95)
    assert low <= 0 <= high, means
