"""Stable-Baselines3 view of the native vector env: one numpy step for all training envs.

Needs the ``rl`` extra (``pip install torch==2.13.0 && pip install 'mimo-radar-env[rl]'``)::

    from stable_baselines3 import PPO
    from mimo_radar_env.sb3 import NativeVecEnv

    venv = NativeVecEnv("paper-1-v1", num_envs=8, seed=0)
    PPO("MlpPolicy", venv).learn(10_000)
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .envs.versions import env_version
from .extras import require
from .scenarios import Scenario
from .wrappers import MimoRadarSelectFlatVectorEnv, make_ppo_env

VecEnv = require("stable_baselines3.common.vec_env.base_vec_env", "rl", "mimo_radar_env.sb3").VecEnv


class NativeVecEnv(VecEnv):
    """An SB3 ``VecEnv`` over the Flat ids' vector env
    (:class:`~mimo_radar_env.wrappers.MimoRadarSelectFlatVectorEnv`: the batch engine with the
    PPO features and valid-by-construction actions, one ``Discrete`` action per super arm or
    station scores).

    All envs end together after ``T`` steps; they are then reset at once and the last
    features are returned as ``terminal_observation`` (SB3's convention). Episode ``e``
    seeds trial ``i`` with ``seed + e * num_envs + i``.

    Parameters
    ----------
    scenario : str or Scenario
    num_envs : int
    seed : int
    action : {"auto", "discrete", "scores"}
        As :func:`~mimo_radar_env.wrappers.make_ppo_env`.
    version : {"v1", "v0"}
        The env version whose defaults the options start from (default v1).
    **options
        Env options (``fusion=...``) and scenario overrides, as for ``gym.make``.
    """

    render_mode = None

    def __init__(
        self,
        scenario: str | Scenario,
        num_envs: int,
        seed: int = 0,
        action: str = "auto",
        version: str = "v1",
        **options: Any,
    ) -> None:
        probe = make_ppo_env(scenario, action=action, env_id=env_version(version).env_id, **options)
        options = {**probe.unwrapped.options.to_dict(), **options}  # the version's defaults, resolved
        self.flat = MimoRadarSelectFlatVectorEnv(
            num_envs=num_envs, action=action, scenario=probe.unwrapped.scenario, **options
        )
        self.env = self.flat.env
        self.scenario = self.flat.scenario
        self.discrete = self.flat.action_form == "discrete"
        self.seed_value = seed
        self.episode = 0
        self._actions: NDArray | None = None
        super().__init__(num_envs, probe.observation_space, probe.action_space)

    def reset(self) -> NDArray[np.float32]:
        features, _ = self.flat.reset(seed=self.seed_value + self.episode * self.num_envs)
        self.episode += 1
        self.returns = np.zeros(self.num_envs)
        self.squared_errors = np.zeros(self.num_envs)  # summed over steps, mean over targets
        self.lengths = 0
        return features

    def step_async(self, actions: NDArray) -> None:
        self._actions = actions

    def step_wait(self) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.bool_], list[dict]]:
        assert self._actions is not None, "step_async() first"
        features, reward, terminated, truncated, info = self.flat.step(self._actions)
        self.returns += reward
        if "position_error" in info:
            self.squared_errors += np.mean(np.asarray(info["position_error"]) ** 2, axis=1)
        self.lengths += 1
        dones = terminated | truncated
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        if dones.all():  # SB3 resets at once (the Flat vector env would on the next step)
            for i in range(self.num_envs):
                infos[i] = {
                    "terminal_observation": features[i],
                    "TimeLimit.truncated": bool(truncated[i]),
                    "episode": {
                        "r": float(self.returns[i]),
                        "l": self.lengths,
                        "t": 0.0,
                        # the tracker's ARMSE over the episode (m; NaN without tracking)
                        "armse": float(np.sqrt(self.squared_errors[i] / self.lengths))
                        if "position_error" in info
                        else float("nan"),
                    },
                }
            features = self.reset()
        return features, reward.astype(np.float32), dones, infos

    def action_masks(self) -> NDArray[np.bool_]:
        """The allowed Discrete actions of every env, (num_envs, A) (sb3-contrib's MaskablePPO)."""
        return self.flat.action_masks()

    def close(self) -> None:
        return None

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        return [getattr(self, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        setattr(self, attr_name, value)

    def env_method(self, method_name: str, *args: Any, indices: Any = None, **kwargs: Any) -> list[Any]:
        """Only ``action_masks`` (what sb3-contrib's MaskablePPO calls): one mask per env."""
        if method_name != "action_masks":
            raise NotImplementedError(
                f"NativeVecEnv runs all envs as one batch: it has no per-env method {method_name!r}"
            )
        masks = self.flat.action_masks()
        return [masks[i] for i in self._indices(indices)]

    def env_is_wrapped(self, wrapper_class: Any, indices: Any = None) -> list[bool]:
        return [False] * len(self._indices(indices))

    def _indices(self, indices: Any) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        return [indices] if isinstance(indices, int) else list(indices)

    def seed(self, seed: int | None = None) -> list[int | None]:
        if seed is not None:
            self.seed_value = seed
        return [seed] * self.num_envs
