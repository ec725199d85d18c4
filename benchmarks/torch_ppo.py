"""The project's own PPO, in plain torch and in CleanRL's shape: one file a reader can follow.

``train-ppo --algo torch-ppo --device cuda`` (or ``--device cpu``) trains it on the Flat vector
env made with ``device=`` (:class:`~mimo_radar_env.wrappers.MimoRadarSelectFlatVectorEnv`): the
env's step, the features, the network, the rollout buffer and the updates all stay on that
device. Its hyperparameters are SB3 PPO's (the same ``hyperparams/ppo.yml`` entry), with SB3's
choices where the papers leave one open, so that the two learners can be compared:

* the ``MlpPolicy`` network and initialisation (:class:`~agents.networks.ActorCritic`), Adam
  with ``eps=1e-5``, gradients clipped at ``max_grad_norm``;
* observations normalised as ``VecNormalize`` does (:class:`~agents.networks.RunningNormalization`);
* a time limit bootstraps: the last reward of an episode gets ``gamma V(s_T)`` added;
* advantages by GAE, normalised per minibatch; the clipped surrogate, an unclipped value loss
  ``(R - V)^2`` and the entropy bonus; ``n_epochs`` passes in minibatches of ``batch_size``,
  stopped early when the approximate KL passes ``1.5 target_kl``.

Only the ``Discrete`` (super-arm) action is supported. Random draws (actions, minibatch order)
come from the project's counter-based streams, so they are the same on every device; the
network starts from ``torch.manual_seed(seed)`` on the CPU.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from agents.ppo import NORMALIZATION_FILE, TORCH_PPO, WEIGHTS_FILE
from mimo_radar_env import EnvOptions, Scenario
from mimo_radar_env.core.counter_hash import Stream
from mimo_radar_env.core.streams import TrialRandom

#: The SB3 PPO hyperparameters torch-ppo reads (the rest of an entry's keys are refused by name).
CARRIED = (
    "n_steps", "batch_size", "n_epochs", "learning_rate", "gamma", "gae_lambda", "ent_coef",
    "vf_coef", "clip_range", "max_grad_norm", "target_kl", "normalize_advantage",
)  # fmt: skip


@dataclass(frozen=True)
class PPOConfig:
    """torch-ppo's hyperparameters, with SB3 PPO's defaults."""

    n_envs: int = 8
    n_steps: int = 2048
    batch_size: int = 64
    n_epochs: int = 10
    learning_rate: float = 3e-4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    ent_coef: float = 0.0
    vf_coef: float = 0.5
    clip_range: float = 0.2
    max_grad_norm: float = 0.5
    target_kl: float | None = None
    normalize_advantage: bool = True
    net_arch: tuple[int, ...] = (64, 64)
    normalize_obs: bool = False
    clip_obs: float = 10.0

    @classmethod
    def from_hyperparams(
        cls, params: dict[str, Any], n_envs: int | None = None, normalize: dict[str, Any] | None = None
    ) -> PPOConfig:
        """The configuration of a checked ``train-ppo`` entry (SB3's keys), ``n_envs`` overriding
        the entry's, ``normalize`` its ``VecNormalize`` keywords (``training.normalize_kwargs``;
        None: none); a key torch-ppo does not implement is refused by name."""
        ignored = {"n_envs", "n_timesteps", "normalize", "policy", "policy_kwargs", *CARRIED}
        unknown = sorted(set(params) - ignored)
        if unknown:
            raise ValueError(f"torch-ppo does not implement {unknown}; it reads {sorted(ignored)}")
        normalize = normalize or {}
        if normalize.get("norm_reward", False):
            raise ValueError("torch-ppo normalises observations only: set normalize: dict(norm_reward=False)")
        values = {key: params[key] for key in CARRIED if key in params}
        arch = params.get("policy_kwargs", {}).get("net_arch", list(cls.net_arch))
        return cls(
            n_envs=int(n_envs if n_envs is not None else params.get("n_envs", cls.n_envs)),
            net_arch=tuple(arch),
            normalize_obs=bool(normalize.get("norm_obs", bool(normalize))),
            clip_obs=float(normalize.get("clip_obs", cls.clip_obs)),
            **values,
        )


def compute_gae(
    rewards: Any, values: Any, dones: Any, last_value: Any, gamma: float, gae_lambda: float
) -> tuple[Any, Any]:
    """Advantages and returns (S, B) by GAE (Schulman et al. 2016, eq11-eq16): ``dones[t]``
    marks the last step of an episode (its successor's value is not carried back)."""
    import torch

    advantages = torch.zeros_like(rewards)
    carry = torch.zeros_like(last_value)
    for t in reversed(range(rewards.shape[0])):
        next_value = last_value if t == rewards.shape[0] - 1 else values[t + 1]
        alive = 1.0 - dones[t]
        delta = rewards[t] + gamma * next_value * alive - values[t]
        carry = delta + gamma * gae_lambda * alive * carry
        advantages[t] = carry
    return advantages, advantages + values


def ppo_loss(
    network: Any, config: PPOConfig, obs: Any, actions: Any, old_log_probs: Any, advantages: Any, returns: Any
) -> tuple[Any, dict[str, Any]]:
    """PPO's loss on one minibatch (Schulman et al. 2017, eq7 and eq9) and its diagnostics."""
    import torch

    logits, values = network(obs)
    log_probs = torch.log_softmax(logits, dim=-1)
    new_log_probs = log_probs.gather(1, actions[:, None]).squeeze(1)
    entropy = -(log_probs.exp() * log_probs).sum(-1)
    if config.normalize_advantage and len(advantages) > 1:
        advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
    log_ratio = new_log_probs - old_log_probs
    ratio = log_ratio.exp()
    clipped = torch.clamp(ratio, 1 - config.clip_range, 1 + config.clip_range)
    policy_loss = -torch.min(advantages * ratio, advantages * clipped).mean()
    value_loss = torch.nn.functional.mse_loss(returns, values)
    loss = policy_loss - config.ent_coef * entropy.mean() + config.vf_coef * value_loss
    with torch.no_grad():
        approx_kl = ((ratio - 1) - log_ratio).mean()
    return loss, {"policy_loss": policy_loss, "value_loss": value_loss, "approx_kl": approx_kl}


def train(
    scenario: Scenario,
    timesteps: int,
    out: Path,
    seed: int,
    config: PPOConfig,
    options: EnvOptions,
    device: str = "cpu",
    log: Any = None,
) -> dict[str, Any]:
    """Train torch-ppo for at least ``timesteps`` env steps (whole rollouts of ``n_steps x
    n_envs``) and save ``model.pt``, ``vecnormalize.npz``, ``curve.csv`` and ``ppo.json`` in
    ``out``. ``log`` (a :class:`~benchmarks.training.LearningCurve`) hears of every rollout."""
    import torch

    from agents.networks import ActorCritic, RunningNormalization
    from mimo_radar_env.wrappers import MimoRadarSelectFlatVectorEnv

    from .training_log import CURVE_FILE, META_FILE, LearningCurve

    env = MimoRadarSelectFlatVectorEnv(
        num_envs=config.n_envs, action="discrete", scenario=scenario, device=device,
        autoreset_mode="disabled", **options.to_dict(),
    )  # fmt: skip
    xp, B, S, horizon = env.env.engine.xp, config.n_envs, config.n_steps, scenario.horizon
    size, arms = env.single_observation_space.shape[0], env.single_action_space.n
    torch.manual_seed(seed)
    network = ActorCritic(size, arms, config.net_arch).to(xp.device)
    optimizer = torch.optim.Adam(network.parameters(), lr=config.learning_rate, eps=1e-5)
    normalization = RunningNormalization(size, xp.device, config.clip_obs) if config.normalize_obs else None
    sampling, shuffling = TrialRandom.for_batch(seed, B, xp), TrialRandom.for_batch(seed, 1, xp)
    log = log or LearningCurve(timesteps)

    def observe(features: Any, update: bool = True) -> Any:
        if normalization is None:
            return features
        if update:
            normalization.update(features)
        return normalization(features)

    episode = 0

    def new_episode() -> Any:
        nonlocal episode
        features, _ = env.reset(seed=seed + episode * B)  # NativeVecEnv's seeds, episode by episode
        episode += 1
        return observe(features)

    def zeros(dtype: Any = torch.float32, *shape: int) -> Any:
        return torch.zeros((S, B, *shape), dtype=dtype, device=xp.device)

    obs_buf, action_buf, log_prob_buf = zeros(torch.float32, size), zeros(torch.int64), zeros()
    reward_buf, done_buf, value_buf = zeros(), zeros(), zeros()
    obs, length = new_episode(), 0
    returns, squared_errors = (torch.zeros(B, dtype=torch.float64, device=xp.device) for _ in range(2))
    updates, trained, start = math.ceil(timesteps / (S * B)), 0, time.perf_counter()
    log.start(updates * S * B)
    for _ in range(updates):
        for t in range(S):  # the rollout: act, step, record, all on the device
            with torch.no_grad():
                logits, value = network(obs)
            cumulative = torch.softmax(logits.double(), dim=-1).cumsum(-1)
            u = sampling.uniform(Stream.PPO_ACTION)
            action = torch.clamp((cumulative < u[:, None]).sum(-1), max=arms - 1)
            features, reward, _, _, info = env.step(action)
            reward_buf[t] = reward
            returns += reward
            squared_errors += (info["position_error"] ** 2).mean(-1) if "position_error" in info else 0.0
            obs_buf[t], action_buf[t], value_buf[t] = obs, action, value
            log_prob_buf[t] = torch.log_softmax(logits, dim=-1).gather(1, action[:, None]).squeeze(1)
            length += 1
            if length == horizon:  # every trial's time limit: bootstrap, then a new episode
                with torch.no_grad():
                    reward_buf[t] += config.gamma * network(observe(features, update=False))[1]
                done_buf[t] = 1.0
                armse = (
                    torch.sqrt(squared_errors / length) if "position_error" in info else returns * math.nan
                )
                log.add_episodes(returns.tolist(), armse.tolist())
                returns.zero_(), squared_errors.zero_()
                obs, length = new_episode(), 0
            else:
                done_buf[t] = 0.0
                obs = observe(features)
        with torch.no_grad():
            last_value = network(obs)[1]
        advantages, value_targets = compute_gae(
            reward_buf, value_buf, done_buf, last_value, config.gamma, config.gae_lambda
        )
        flat = (obs_buf.reshape(S * B, size), action_buf.reshape(-1), log_prob_buf.reshape(-1),
                advantages.reshape(-1), value_targets.reshape(-1))  # fmt: skip
        stop = False
        for _ in range(config.n_epochs):
            order = torch.argsort(shuffling.uniform(Stream.PPO_MINIBATCH, (S * B,))[0])
            for begin in range(0, S * B, config.batch_size):
                batch = order[begin : begin + config.batch_size]
                loss, stats = ppo_loss(network, config, *(part[batch] for part in flat))
                if config.target_kl is not None and stats["approx_kl"] > 1.5 * config.target_kl:
                    stop = True  # SB3's early stop, before this minibatch's step
                    break
                optimizer.zero_grad()
                loss.backward()
                torch.nn.utils.clip_grad_norm_(network.parameters(), config.max_grad_norm)
                optimizer.step()
            if stop:
                break
        trained += S * B
        log.close_rollout(trained)
    wall = time.perf_counter() - start
    out.mkdir(parents=True, exist_ok=True)
    network.save(out / WEIGHTS_FILE)
    if normalization is not None:
        normalization.save(out / NORMALIZATION_FILE)
    log.write(out / CURVE_FILE, f"{TORCH_PPO} on {scenario.name}")
    meta = {
        "algo": TORCH_PPO,
        "scenario": scenario.to_dict(),
        "env_options": options.to_dict(),
        "timesteps": timesteps,
        "trained_timesteps": trained,
        "seed": seed,
        "n_envs": B,
        "action": "discrete",
        "device": str(xp.device),
        "config": {f.name: getattr(config, f.name) for f in fields(config)},
        "train_wall_s": wall,
        "steps_per_second": trained / wall,
    }
    (out / META_FILE).write_text(json.dumps(meta, indent=2, default=str))
    return meta
