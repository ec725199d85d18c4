"""A trained Stable-Baselines3 PPO policy as a batch-native agent (``ppo:PATH/model.zip``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario
from mimo_radar_env.extras import require
from mimo_radar_env.wrappers import RadarFeatures, SuperArmIndex, make_ppo_env, scores_to_action

from .base import Agent, Observation

#: Files written by ``mimo-radar-bench train-ppo`` into its output folder.
MODEL_FILE = "model.zip"
NORMALIZATION_FILE = "vecnormalize.pkl"


def require_sb3() -> Any:
    """The ``stable_baselines3`` module, or ``DependencyNotInstalled`` naming the ``rl`` extra."""
    return require("stable_baselines3", "rl", "PPO")


def model_file(path: str | Path) -> Path:
    """``PATH`` itself when it is a ``.zip`` file, else ``PATH/model.zip``."""
    path = Path(path)
    return path if path.suffix == ".zip" else path / MODEL_FILE


class PPOAgent(Agent):
    """A trained PPO policy (Stable-Baselines3), acting deterministically on B trials at once.

    Loads ``model.zip`` and, when present beside it, the ``vecnormalize.pkl`` observation
    statistics (through SB3's ``VecNormalize.load``); computes the same
    :class:`~mimo_radar_env.wrappers.RadarFeatures` as the training wrapper for all trials
    and runs one forward pass per step for the whole batch.

    Loading a model unpickles what SB3 stored in it: load only models you trust.

    Parameters
    ----------
    path : str or Path
        ``model.zip`` or the folder holding it.
    deterministic : bool
        Take the policy's most likely action (default) rather than sampling.
    """

    name = "ppo"
    needs_tracking = True

    def __init__(
        self, scenario: Scenario | str, path: str | Path, seed: int | None = None, deterministic: bool = True
    ) -> None:
        super().__init__(scenario, seed)
        sb3 = require_sb3()
        file = model_file(path)
        if not file.is_file():
            raise ValueError(f"PPO model {file} does not exist (expected ppo:PATH/TO/model.zip)")
        self.model = sb3.PPO.load(file, device="cpu")
        self.deterministic = deterministic
        self.features = RadarFeatures(self.scenario)
        if self.model.observation_space.shape != (self.features.size,):
            raise ValueError(
                f"the model at {file} was trained on {self.model.observation_space.shape[0]} features; "
                f"this scenario has {self.features.size}: train it on this layout"
            )
        self.discrete = self.model.action_space.__class__.__name__ == "Discrete"
        self.index = SuperArmIndex(self.scenario) if self.discrete else None
        self.normalization = None
        norm_file = file.parent / NORMALIZATION_FILE
        if norm_file.exists():
            from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

            action = "discrete" if self.discrete else "scores"
            probe = DummyVecEnv([lambda: make_ppo_env(self.scenario, action=action)])
            self.normalization = VecNormalize.load(str(norm_file), probe)
            self.normalization.training = False
        self._features: NDArray[np.float32] | None = None

    def _reset(self, obs: Observation) -> None:
        self._features = self.features.reset(obs)

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        features = self._features
        if self.normalization is not None:
            features = self.normalization.normalize_obs(features)
        actions, _ = self.model.predict(features, deterministic=self.deterministic)
        if self.discrete:
            return self.index.to_action(actions)
        return scores_to_action(actions, self.num_tx, self.tx_count, self.rx_count)

    def _update(self, obs: Observation, reward: NDArray[np.float64]) -> None:
        self._features = self.features.step(obs)
