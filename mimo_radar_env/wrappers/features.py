"""Flat features for learning agents (docs/ppo.md): :class:`RadarFeatures`, batch-first so
that the harness computes the same features for B trials at once, and
:class:`RadarFeatureObservation`, the single env's flat ``Box`` of them for MLP policies."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from ..core import motion
from ..core.arrays import namespace
from ..core.geometry import squared_range_products
from ..scenarios import Scenario
from .actions import scenario_of


class RadarFeatures:
    """Batch-first feature vectors from env observations (docs/ppo.md).

    An MLP has no memory, so the features carry what a bandit agent keeps as state:

    * ``latest_sinr`` (K*M*N): the last SINR sample of every target and channel,
      ``log10(1 + sample)``; with
    * ``age`` (M*N): steps since the channel was last probed, ``min(age, 100) / 100``;
    * ``path_gain`` (K*M*N): ``log10`` of the geometric gain ``(R_tx R_rx)^-2`` at the
      tracker's one-step prediction, relative to its maximum over channels (so in
      ``[-inf, 0]``, clipped at -6): which channels the geometry favours next;
    * ``track`` (K*4): predicted position in units of the layout's extent and
      velocity in units of 100 m/s; ``mode_prob`` (K*3);
    * ``time`` (1): ``t / T``.

    With ``tracking=False`` envs the track-based parts are zeros. Observations of an env on a
    device (torch tensors) give the features there, as float32 tensors: the same computation.
    """

    MAX_AGE = 100.0

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        sc = scenario
        self.shape = (sc.num_targets, sc.num_tx, sc.num_rx)
        stations = np.concatenate([sc.tx_positions, sc.rx_positions])
        self.centre = stations.mean(axis=0)
        self.extent = max(float(np.ptp(stations, axis=0).max()), 1.0)
        K, M, N = self.shape
        self.size = 2 * K * M * N + M * N + K * 4 + K * 3 + 1

    def reset(self, obs: dict[str, NDArray]) -> NDArray[np.float32]:
        xp = self.xp = namespace(obs["sinr"])
        sinr = xp.astype(xp.asarray(obs["sinr"]), np.float64)
        self.latest = xp.log10(1.0 + sinr)
        probed = xp.asarray(obs["probed"]) > 0
        self.age = xp.where(probed, 0.0, xp.full(probed.shape, self.MAX_AGE))
        self.t = 0
        return self._features(obs)

    def step(self, obs: dict[str, NDArray]) -> NDArray[np.float32]:
        xp = self.xp
        probed = xp.asarray(obs["probed"]) > 0
        self.latest = xp.where(probed[:, None], xp.log10(1.0 + xp.asarray(obs["sinr"])), self.latest)
        self.age = xp.where(probed, 0.0, xp.minimum(self.age + 1.0, self.MAX_AGE))
        self.t += 1
        return self._features(obs)

    def _features(self, obs: dict[str, NDArray]) -> NDArray[np.float32]:
        xp = self.xp
        batch = self.latest.shape[0]
        K, M, N = self.shape
        sc = self.scenario
        if "track_pred" in obs:
            pred = xp.astype(xp.asarray(obs["track_pred"]), np.float64)
            positions = motion.positions(pred)
            log_gain = -xp.log10(
                squared_range_products(positions, xp.asarray(sc.tx_positions), xp.asarray(sc.rx_positions))
            )
            log_gain = xp.maximum(log_gain - xp.max(log_gain, axis=(-1, -2), keepdims=True), -6.0)
            track = xp.concatenate(
                [
                    (positions - xp.asarray(self.centre)) / self.extent,
                    pred[..., motion.VELOCITY] / 100.0,
                ],
                axis=-1,
            )
            modes = xp.astype(xp.asarray(obs["mode_prob"]), np.float64)
        else:
            log_gain = xp.zeros((batch, K, M, N))
            track = xp.zeros((batch, K, 4))
            modes = xp.zeros((batch, K, 3))
        parts = [
            self.latest.reshape(batch, -1),
            (self.age / self.MAX_AGE).reshape(batch, -1),
            log_gain.reshape(batch, -1),
            track.reshape(batch, -1),
            modes.reshape(batch, -1),
            xp.full((batch, 1), self.t / sc.horizon),
        ]
        return xp.astype(xp.concatenate(parts, axis=1), np.float32)


class RadarFeatureObservation(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """A flat ``Box`` of :class:`RadarFeatures` (float32) for MLP policies."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ObservationWrapper.__init__(self, env)
        self.features = RadarFeatures(scenario_of(env))
        self.observation_space = spaces.Box(-np.inf, np.inf, (self.features.size,), np.float32)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        return self.features.reset(_batch(obs))[0], info

    def observation(self, observation: dict[str, NDArray]) -> NDArray[np.float32]:
        return self.features.step(_batch(observation))[0]


def _batch(obs: dict[str, NDArray]) -> dict[str, NDArray]:
    return {key: np.asarray(value)[None] for key, value in obs.items()}
