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


class Collector:
    """The rollout side of a training: the Flat vector env on the device, the observation
    statistics, the rollout buffers and the episodes in progress. :meth:`collect` fills the
    buffers with ``n_steps`` steps of every trial, acting with the network."""

    def __init__(
        self, scenario: Scenario, seed: int, config: PPOConfig, options: EnvOptions, device: str,
        device_mode: str = "eager",
    ):  # fmt: skip
        import torch

        from agents.networks import RunningNormalization
        from mimo_radar_env.wrappers import MimoRadarSelectFlatVectorEnv

        self.env = MimoRadarSelectFlatVectorEnv(
            num_envs=config.n_envs, action="discrete", scenario=scenario, device=device,
            device_mode=device_mode, autoreset_mode="disabled", **options.to_dict(),
        )  # fmt: skip
        self.xp, self.config, self.seed, self.horizon = self.env.env.engine.xp, config, seed, scenario.horizon
        B, S, where = config.n_envs, config.n_steps, self.xp.device
        self.size, self.arms = self.env.single_observation_space.shape[0], int(self.env.single_action_space.n)
        self.normalization = (
            RunningNormalization(self.size, where, config.clip_obs) if config.normalize_obs else None
        )
        self.sampling = TrialRandom.for_batch(seed, B, self.xp)
        self.obs = torch.zeros((S, B, self.size), dtype=torch.float32, device=where)
        self.actions = torch.zeros((S, B), dtype=torch.int64, device=where)
        self.log_probs, self.rewards, self.dones, self.values = (
            torch.zeros((S, B), device=where) for _ in range(4)
        )
        self.returns, self.squared_errors = (
            torch.zeros(B, dtype=torch.float64, device=where) for _ in range(2)
        )
        self.episode, self.length = 0, 0
        self.current = self._new_episode()

    def observe(self, features: Any, update: bool = True) -> Any:
        """The features as the network sees them: normalised, the statistics updated first (as
        ``VecNormalize`` does in training) unless ``update`` is false."""
        if self.normalization is None:
            return features
        if update:
            self.normalization.update(features)
        return self.normalization(features)

    def _new_episode(self) -> Any:
        B = self.config.n_envs
        features, _ = self.env.reset(seed=self.seed + self.episode * B)  # NativeVecEnv's seeds
        self.episode += 1
        return self.observe(features)

    def collect(self, network: Any, log: Any) -> Any:
        """One rollout; returns the value of the state after it (GAE's last value)."""
        import torch

        for t in range(self.config.n_steps):  # act, step, record, all on the device
            with torch.no_grad():
                logits, value = network(self.current)
            cumulative = torch.softmax(logits.double(), dim=-1).cumsum(-1)
            u = self.sampling.uniform(Stream.PPO_ACTION)
            action = torch.clamp((cumulative < u[:, None]).sum(-1), max=self.arms - 1)
            features, reward, _, _, info = self.env.step(action)
            self.obs[t], self.actions[t], self.values[t], self.rewards[t] = (
                self.current,
                action,
                value,
                reward,
            )
            self.log_probs[t] = torch.log_softmax(logits, dim=-1).gather(1, action[:, None]).squeeze(1)
            self.returns += reward
            tracked = "position_error" in info
            if tracked:
                self.squared_errors += (info["position_error"] ** 2).mean(-1)
            self.length += 1
            self.dones[t] = float(self.length == self.horizon)
            if self.length < self.horizon:
                self.current = self.observe(features)
                continue
            # every trial's time limit: bootstrap with the value of the last state, then a new episode
            with torch.no_grad():
                self.rewards[t] += self.config.gamma * network(self.observe(features, update=False))[1]
            armse = torch.sqrt(self.squared_errors / self.length) if tracked else self.returns * math.nan
            log.add_episodes(self.returns.tolist(), armse.tolist())
            self.returns.zero_(), self.squared_errors.zero_()
            self.current, self.length = self._new_episode(), 0
        with torch.no_grad():
            return network(self.current)[1]


def update(
    network: Any, optimizer: Any, config: PPOConfig, batch: tuple[Any, ...], shuffling: TrialRandom
) -> None:
    """``n_epochs`` passes over a rollout's samples ``batch`` (observations, actions, log
    probabilities, advantages, returns) in minibatches of ``batch_size``, in a fresh order each
    epoch; SB3's early stop when the approximate KL passes ``1.5 target_kl``."""
    import torch

    samples = len(batch[0])
    for _ in range(config.n_epochs):
        order = torch.argsort(shuffling.uniform(Stream.PPO_MINIBATCH, (samples,))[0])
        for begin in range(0, samples, config.batch_size):
            chosen = order[begin : begin + config.batch_size]
            loss, stats = ppo_loss(network, config, *(part[chosen] for part in batch))
            if config.target_kl is not None and stats["approx_kl"] > 1.5 * config.target_kl:
                return  # before this minibatch's step, as SB3
            optimizer.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(network.parameters(), config.max_grad_norm)
            optimizer.step()


def train(
    scenario: Scenario, timesteps: int, out: Path, seed: int, config: PPOConfig, options: EnvOptions,
    *, device: str = "cpu", device_mode: str = "eager", log: Any = None,
) -> dict[str, Any]:  # fmt: skip
    """Train torch-ppo for at least ``timesteps`` env steps (whole rollouts of ``n_steps x
    n_envs``) and save ``model.pt``, ``vecnormalize.npz``, ``curve.csv`` and ``ppo.json`` in
    ``out``, the env's step in form ``device_mode`` (:mod:`mimo_radar_env.envs.device_forms`:
    the same numbers). ``log`` (a :class:`~benchmarks.training_log.LearningCurve`) hears of
    every rollout."""
    import torch

    from agents.networks import ActorCritic

    from .training_log import CURVE_FILE, LearningCurve

    collector = Collector(scenario, seed, config, options, device, device_mode)
    where, rollout = collector.xp.device, config.n_steps * config.n_envs
    torch.manual_seed(seed)
    network = ActorCritic(collector.size, collector.arms, config.net_arch).to(where)
    optimizer = torch.optim.Adam(network.parameters(), lr=config.learning_rate, eps=1e-5)
    shuffling = TrialRandom.for_batch(seed, 1, collector.xp)
    log = log or LearningCurve(timesteps)
    updates, start, began = math.ceil(timesteps / rollout), time.perf_counter(), time.time()
    log.start(updates * rollout)
    for done in range(1, updates + 1):
        last_value = collector.collect(network, log)
        c = collector
        advantages, value_targets = compute_gae(
            c.rewards, c.values, c.dones, last_value, config.gamma, config.gae_lambda
        )
        batch = (c.obs.reshape(rollout, -1), c.actions.reshape(-1), c.log_probs.reshape(-1),
                 advantages.reshape(-1), value_targets.reshape(-1))  # fmt: skip
        update(network, optimizer, config, batch, shuffling)
        log.close_rollout(done * rollout)
    wall = time.perf_counter() - start
    out.mkdir(parents=True, exist_ok=True)
    network.save(out / WEIGHTS_FILE)
    if collector.normalization is not None:
        collector.normalization.save(out / NORMALIZATION_FILE)
    log.write(out / CURVE_FILE, f"{TORCH_PPO} on {scenario.name}")
    return _record(
        out, scenario, options, timesteps, updates * rollout, seed, config, str(where), device_mode,
        (began, wall),
    )  # fmt: skip


def _record(
    out: Path, scenario: Scenario, options: EnvOptions, timesteps: int, trained: int, seed: int,
    config: PPOConfig, device: str, device_mode: str, timed: tuple[float, float],
) -> dict[str, Any]:  # fmt: skip
    """``ppo.json``: what was trained, where, and how fast (``timed``: the training's start on the
    wall clock, Unix seconds, and its wall time)."""
    from .training_log import META_FILE

    began, wall = timed
    meta = {
        "algo": TORCH_PPO,
        "scenario": scenario.to_dict(),
        "env_options": options.to_dict(),
        "timesteps": timesteps,
        "trained_timesteps": trained,
        "seed": seed,
        "n_envs": config.n_envs,
        "action": "discrete",
        "device": device,
        "device_mode": device_mode,
        "config": {f.name: getattr(config, f.name) for f in fields(config)},
        "train_wall_s": wall,
        # when, on the wall clock: what a study's trainings spanned together (rl.json)
        "trained_from_unix_s": began,
        "steps_per_second": trained / wall,
    }
    (out / META_FILE).write_text(json.dumps(meta, indent=2, default=str))
    return meta
