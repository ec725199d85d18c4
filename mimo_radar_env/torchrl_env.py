"""A torchrl environment over the batch engine on a device: ``batch_size=[B]`` trials, every
tensor where the engine runs.

Needs torchrl, which runs in an environment of its own: torchrl 0.14 installs a top-level
``benchmarks`` package that shadows this project's (docs/clients.md)::

    from mimo_radar_env.torchrl_env import MimoRadarSelectTorchRLEnv
    from torchrl.envs.utils import check_env_specs

    env = MimoRadarSelectTorchRLEnv(num_envs=512, device="cuda")  # paper-1-v1, v1's options
    check_env_specs(env)
    rollout = env.rollout(100)  # a TensorDict of batch size [512, 100], on the device

It is the Flat env (:class:`~mimo_radar_env.wrappers.MimoRadarSelectFlatVectorEnv`): one
``Categorical`` action per super arm (every action valid) and the float32 features of
:class:`~mimo_radar_env.wrappers.RadarFeatures` as ``"observation"``, with the env made with
``device=``, so no step leaves the device. All trials end together after ``T`` steps
(``"truncated"``); a reset resets them all.
"""

from __future__ import annotations

from typing import Any

import torch
from tensordict import TensorDict
from torchrl.data import Categorical, Composite, Unbounded
from torchrl.envs import EnvBase

from .wrappers import MimoRadarSelectFlatVectorEnv


class MimoRadarSelectTorchRLEnv(EnvBase):
    """``MimoRadarSelectFlat`` as a torchrl ``EnvBase`` of ``num_envs`` trials on ``device``.

    Parameters
    ----------
    num_envs : int
        The batch size B.
    device : str or torch.device
        Where the engine, the features and every tensor live (default ``"cpu"``: CPU torch).
    seed : int
        Trial ``i`` of episode ``e`` is seeded ``seed + e * B + i`` (``set_seed`` changes it).
    **kwargs
        Env options and the scenario, as for ``gym.make("MimoRadarSelect-v1", ...)``.
    """

    def __init__(self, num_envs: int = 8, device: Any = "cpu", seed: int = 0, **kwargs: Any) -> None:
        if device is None:
            raise ValueError("device must be a torch device ('cpu', 'cuda', 'cuda:1'), got None")
        flat = MimoRadarSelectFlatVectorEnv(
            num_envs=num_envs, action="discrete", device=device, autoreset_mode="disabled", **kwargs
        )
        super().__init__(device=flat.device, batch_size=torch.Size([num_envs]))
        self.flat = flat
        self._seed, self._episode = seed, 0
        B = torch.Size([num_envs])
        size, arms = flat.single_observation_space.shape[0], int(flat.single_action_space.n)
        self.observation_spec = Composite(
            observation=Unbounded(shape=(*B, size), dtype=torch.float32, device=self.device), shape=B
        )
        self.action_spec = Categorical(arms, shape=B, dtype=torch.int64, device=self.device)
        self.reward_spec = Unbounded(shape=(*B, 1), dtype=torch.float32, device=self.device)
        self.done_spec = Composite(
            {
                key: Categorical(2, shape=(*B, 1), dtype=torch.bool, device=self.device)
                for key in ("done", "terminated", "truncated")
            },
            shape=B,
        )

    def _flags(self, terminated: torch.Tensor, truncated: torch.Tensor) -> dict[str, torch.Tensor]:
        return {
            "done": (terminated | truncated)[:, None],
            "terminated": terminated[:, None],
            "truncated": truncated[:, None],
        }

    def _reset(self, tensordict: TensorDict | None = None, **kwargs: Any) -> TensorDict:
        features, _ = self.flat.reset(seed=self._seed + self._episode * self.batch_size[0])
        self._episode += 1
        none = torch.zeros(self.batch_size, dtype=torch.bool, device=self.device)
        return TensorDict(
            {"observation": features, **self._flags(none, none)},
            batch_size=self.batch_size,
            device=self.device,
        )

    def _step(self, tensordict: TensorDict) -> TensorDict:
        features, reward, terminated, truncated, _ = self.flat.step(tensordict["action"])
        return TensorDict(
            {
                "observation": features,
                "reward": reward.to(torch.float32)[:, None],
                **self._flags(terminated, truncated),
            },
            batch_size=self.batch_size,
            device=self.device,
        )

    def _set_seed(self, seed: int | None) -> None:
        self._seed, self._episode = int(seed or 0), 0
