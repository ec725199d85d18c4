"""The project's own actor-critic (plain torch): the network ``train-ppo --algo torch-ppo`` trains
(``benchmarks/torch_ppo.py``) and :class:`~agents.ppo.TorchPPOAgent` evaluates, with the running
observation statistics both apply.

The network is Stable-Baselines3's ``MlpPolicy`` for a ``Discrete`` action: separate policy and
value MLPs of ``net_arch`` tanh layers, orthogonal initialisation with gain sqrt(2), 0.01 on the
policy head and 1 on the value head. The statistics are SB3 ``VecNormalize``'s, with its update
(Chan et al.'s parallel mean and variance) and its ``clip((x - mean) / sqrt(var + eps))``, and are
saved in the same ``vecnormalize.npz`` layout as the SB3 learners'.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn


def _mlp(sizes: list[int], last_gain: float) -> nn.Sequential:
    layers: list[nn.Module] = []
    for i, (a, b) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
        linear = nn.Linear(a, b)
        last = i == len(sizes) - 2
        nn.init.orthogonal_(linear.weight, last_gain if last else math.sqrt(2))
        nn.init.zeros_(linear.bias)
        layers.append(linear)
        if not last:
            layers.append(nn.Tanh())
    return nn.Sequential(*layers)


class ActorCritic(nn.Module):
    """Policy logits and state value of a batch of features (float32)."""

    def __init__(self, observation_size: int, action_count: int, net_arch: tuple[int, ...] = (64, 64)):
        super().__init__()
        self.shape = {
            "observation_size": int(observation_size),
            "action_count": int(action_count),
            "net_arch": [int(units) for units in net_arch],
        }
        self.policy = _mlp([observation_size, *net_arch, action_count], 0.01)
        self.value = _mlp([observation_size, *net_arch, 1], 1.0)

    def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.policy(features), self.value(features).squeeze(-1)

    def save(self, path: Path) -> None:
        torch.save({"shape": self.shape, "weights": self.state_dict()}, path)

    @classmethod
    def load(cls, path: Path, device: Any = "cpu") -> ActorCritic:
        """The network saved in ``path``, read without unpickling code (``weights_only``)."""
        try:
            data = torch.load(path, map_location=device, weights_only=True)
            shape = data["shape"]
            sizes = int(shape["observation_size"]), int(shape["action_count"])
            network = cls(*sizes, tuple(shape["net_arch"]))
            network.load_state_dict(data["weights"])
        except (OSError, KeyError, TypeError, RuntimeError, ValueError) as exc:
            raise ValueError(f"{path} is not a torch-ppo model ({type(exc).__name__}: {exc})") from exc
        return network.to(device)


class RunningNormalization:
    """Running mean and variance of features, applied as SB3's ``VecNormalize`` applies them.

    Kept in float64 on the features' device; :meth:`update` folds in a batch (N, D).
    """

    def __init__(self, size: int, device: Any = "cpu", clip: float = 10.0, epsilon: float = 1e-8) -> None:
        self.mean = torch.zeros(size, dtype=torch.float64, device=device)
        self.var = torch.ones(size, dtype=torch.float64, device=device)
        self.count = 1e-4  # VecNormalize's RunningMeanStd starts here
        self.clip, self.epsilon = clip, epsilon

    def update(self, batch: torch.Tensor) -> None:
        batch = batch.to(torch.float64)
        mean, var, count = batch.mean(0), batch.var(0, unbiased=False), batch.shape[0]
        delta, total = mean - self.mean, self.count + count
        m2 = self.var * self.count + var * count + delta**2 * self.count * count / total
        self.mean = self.mean + delta * count / total
        self.var = m2 / total
        self.count = total

    def __call__(self, features: torch.Tensor) -> torch.Tensor:
        scaled = (features.to(torch.float64) - self.mean) / torch.sqrt(self.var + self.epsilon)
        return torch.clamp(scaled, -self.clip, self.clip).to(torch.float32)

    def to(self, device: Any) -> RunningNormalization:
        """The same statistics on ``device``."""
        moved = RunningNormalization(len(self.mean), device, self.clip, self.epsilon)
        moved.mean, moved.var, moved.count = self.mean.to(device), self.var.to(device), self.count
        return moved

    def save(self, path: Path) -> None:
        np.savez(
            path,
            mean=self.mean.cpu().numpy(),
            var=self.var.cpu().numpy(),
            count=np.array(self.count),
            clip_obs=np.array(self.clip),
            epsilon=np.array(self.epsilon),
        )

    @classmethod
    def load(cls, path: Path, device: Any = "cpu") -> RunningNormalization:
        with np.load(path, allow_pickle=False) as stats:
            clip, epsilon = float(stats["clip_obs"]), float(stats["epsilon"])
            normalization = cls(len(stats["mean"]), device, clip, epsilon)
            normalization.mean = torch.as_tensor(stats["mean"], dtype=torch.float64, device=device)
            normalization.var = torch.as_tensor(stats["var"], dtype=torch.float64, device=device)
            normalization.count = float(stats["count"])
        return normalization
