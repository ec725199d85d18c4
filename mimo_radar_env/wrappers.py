"""Wrappers for learning agents (PPO and other deep RL): valid actions and flat features.

* :class:`SuperArmDiscreteAction`: ``Discrete(C(M, Ms) * C(N, Ns))``, one action per super
  arm, for layouts where that number is small.
* :class:`StationScoreAction`: ``Box(-1, 1, (M + N,))`` scores; the top-``Ms``
  transmitters and top-``Ns`` receivers are selected, for large arrays.
* :class:`RadarFeatureObservation`: a flat ``Box`` feature vector an MLP can learn from
  (docs/ppo.md), computed by :class:`RadarFeatures`, which is batch-first so that the
  harness computes the same features for B trials at once.

All three keep every action valid by construction: a policy never has to learn the
``Ms``/``Ns`` constraint. :func:`make_flat_env` is the entry point of the registered
``MimoRadarSelectFlat-v0``/``-v1``: the env with a valid action and the feature observation,
for tools that take an env id (``make_vec_env``, rl-zoo3, torchrl's ``GymEnv``);
:class:`MimoRadarSelectFlatVectorEnv` is their vector entry point, B trials in one batch.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from .core.geometry import squared_range_products
from .core.superarm import all_super_arms, super_arm_count, top_mask
from .scenarios import Scenario

#: Largest number of super arms :class:`SuperArmDiscreteAction` enumerates.
MAX_DISCRETE_SUPER_ARMS = 100_000


def _scenario_of(env: gym.Env) -> Scenario:
    return env.unwrapped.scenario


class SuperArmIndex:
    """The bijection between ``0..C(M,Ms)*C(N,Ns)-1`` and valid super arms.

    Index ``i`` selects the ``i // C(N, Ns)``-th transmitter subset and the
    ``i % C(N, Ns)``-th receiver subset, subsets in lexicographic order.
    """

    def __init__(self, scenario: Scenario) -> None:
        sc = scenario
        self.num_tx, self.num_rx = sc.num_tx, sc.num_rx
        count = super_arm_count(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        if count > MAX_DISCRETE_SUPER_ARMS:
            raise ValueError(
                f"{count} super arms are too many for a Discrete action (limit {MAX_DISCRETE_SUPER_ARMS}); "
                "use StationScoreAction for this layout"
            )
        tx, rx = all_super_arms(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        self.actions = np.concatenate([tx, rx], axis=1).astype(np.int8)

    @property
    def size(self) -> int:
        return len(self.actions)

    def to_action(self, index: Any) -> NDArray[np.int8]:
        """Env action(s) ``(..., M + N)`` for super-arm index(es)."""
        index = np.asarray(index, dtype=np.int64)
        if np.any((index < 0) | (index >= self.size)):
            raise ValueError(f"super-arm index must be in [0, {self.size}), got {index}")
        return self.actions[index]


class SuperArmDiscreteAction(gym.ActionWrapper, gym.utils.RecordConstructorArgs):
    """``Discrete(C(M, Ms) * C(N, Ns))``: every action is one valid super arm (a bijection)."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ActionWrapper.__init__(self, env)
        self.index = SuperArmIndex(_scenario_of(env))
        self.action_space = spaces.Discrete(self.index.size)

    def action(self, action: Any) -> NDArray[np.int8]:
        return self.index.to_action(action)

    def action_masks(self) -> NDArray[np.bool_]:
        """Which Discrete actions are allowed: all of them, since each is a valid super arm.

        Mask-aware learners call it (sb3-contrib's ``MaskablePPO`` through
        ``get_wrapper_attr("action_masks")``); a subclass may narrow it, e.g. to exclude
        failed stations.
        """
        return np.ones(self.index.size, dtype=bool)


def scores_to_action(
    scores: NDArray[np.float64], num_tx: int, tx_count: int, rx_count: int
) -> NDArray[np.int8]:
    """Top-``Ms`` transmitter and top-``Ns`` receiver scores (ties: lowest index), (..., M + N)."""
    scores = np.asarray(scores, dtype=np.float64)
    if not np.all(np.isfinite(scores)):
        raise ValueError("station scores must be finite")
    tx = top_mask(scores[..., :num_tx], tx_count)
    rx = top_mask(scores[..., num_tx:], rx_count)
    return np.concatenate([tx, rx], axis=-1).astype(np.int8)


class StationScoreAction(gym.ActionWrapper, gym.utils.RecordConstructorArgs):
    """``Box(-1, 1, (M + N,))``: a score per station; the top-``Ms`` TX and top-``Ns`` RX are used."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ActionWrapper.__init__(self, env)
        sc = _scenario_of(env)
        self._sizes = (sc.num_tx, sc.tx_per_step, sc.rx_per_step)
        self.action_space = spaces.Box(-1.0, 1.0, (sc.num_tx + sc.num_rx,), np.float32)

    def action(self, action: Any) -> NDArray[np.int8]:
        return scores_to_action(action, *self._sizes)


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

    With ``tracking=False`` envs the track-based parts are zeros.
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
        sinr = np.asarray(obs["sinr"], dtype=np.float64)
        self.latest = np.log10(1.0 + sinr)
        self.age = np.where(np.asarray(obs["probed"]) > 0, 0.0, self.MAX_AGE)
        self.t = 0
        return self._features(obs)

    def step(self, obs: dict[str, NDArray]) -> NDArray[np.float32]:
        probed = np.asarray(obs["probed"]) > 0
        self.latest = np.where(probed[:, None], np.log10(1.0 + np.asarray(obs["sinr"])), self.latest)
        self.age = np.where(probed, 0.0, np.minimum(self.age + 1.0, self.MAX_AGE))
        self.t += 1
        return self._features(obs)

    def _features(self, obs: dict[str, NDArray]) -> NDArray[np.float32]:
        batch = self.latest.shape[0]
        K, M, N = self.shape
        if "track_pred" in obs:
            pred = np.asarray(obs["track_pred"], dtype=np.float64)
            positions = pred[..., [0, 2]]
            log_gain = -np.log10(
                squared_range_products(positions, self.scenario.tx_positions, self.scenario.rx_positions)
            )
            log_gain = np.maximum(log_gain - log_gain.max(axis=(-1, -2), keepdims=True), -6.0)
            track = np.concatenate(
                [
                    (positions - self.centre) / self.extent,
                    pred[..., [1, 3]] / 100.0,
                ],
                axis=-1,
            )
            modes = np.asarray(obs["mode_prob"], dtype=np.float64)
        else:
            log_gain = np.zeros((batch, K, M, N))
            track = np.zeros((batch, K, 4))
            modes = np.zeros((batch, K, 3))
        parts = [
            self.latest.reshape(batch, -1),
            (self.age / self.MAX_AGE).reshape(batch, -1),
            log_gain.reshape(batch, -1),
            track.reshape(batch, -1),
            modes.reshape(batch, -1),
            np.full((batch, 1), self.t / self.scenario.horizon),
        ]
        return np.concatenate(parts, axis=1).astype(np.float32)


class RadarFeatureObservation(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """A flat ``Box`` of :class:`RadarFeatures` (float32) for MLP policies."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ObservationWrapper.__init__(self, env)
        self.features = RadarFeatures(_scenario_of(env))
        self.observation_space = spaces.Box(-np.inf, np.inf, (self.features.size,), np.float32)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        return self.features.reset(_batch(obs))[0], info

    def observation(self, observation: dict[str, NDArray]) -> NDArray[np.float32]:
        return self.features.step(_batch(observation))[0]


def _batch(obs: dict[str, NDArray]) -> dict[str, NDArray]:
    return {key: np.asarray(value)[None] for key, value in obs.items()}


def make_ppo_env(
    scenario: Any = None, action: str = "auto", env_id: str = "MimoRadarSelect-v1", **kwargs: Any
) -> gym.Env:
    """``MimoRadarSelect`` (``env_id``, default v1) wrapped for PPO: flat features and valid actions.

    ``scenario``: a name, file or :class:`~mimo_radar_env.Scenario` (default: the env id's
    paper scenario 1, ``paper-1-v1`` for v1).
    ``action``: ``"discrete"`` (one action per super arm), ``"scores"`` (station
    scores) or ``"auto"`` (discrete when there are at most 1,000 super arms).
    """
    env = gym.make(env_id, **kwargs) if scenario is None else gym.make(env_id, scenario=scenario, **kwargs)
    return wrap_for_learning(env, action)


def make_flat_env(action: str = "auto", render_mode: str | None = None, **kwargs: Any) -> gym.Env:
    """Entry point of ``MimoRadarSelectFlat-v0``/``-v1``: the env (``kwargs`` as for
    ``MimoRadarSelect``) with a valid action (``action`` as in :func:`make_ppo_env`) and the
    float32 feature observation of :class:`RadarFeatures`."""
    from .envs import MimoRadarSelectEnv

    return wrap_for_learning(MimoRadarSelectEnv(render_mode=render_mode, **kwargs), action)


#: The action forms of the learning envs; ``"auto"`` is discrete up to this many super arms.
ACTION_FORMS = ("auto", "discrete", "scores")
AUTO_DISCRETE_SUPER_ARMS = 1000


def action_form(action: str, scenario: Scenario) -> str:
    """``"discrete"`` or ``"scores"``: ``action`` with ``"auto"`` resolved for ``scenario``."""
    if action not in ACTION_FORMS:
        raise ValueError(f"action must be one of {list(ACTION_FORMS)}, got {action!r}")
    if action != "auto":
        return action
    sc = scenario
    count = super_arm_count(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
    return "discrete" if count <= AUTO_DISCRETE_SUPER_ARMS else "scores"


def wrap_for_learning(env: gym.Env, action: str = "auto") -> gym.Env:
    """``env`` with a valid action wrapper and the feature observation."""
    if action_form(action, env.unwrapped.scenario) == "discrete":
        env = SuperArmDiscreteAction(env)
    else:
        env = StationScoreAction(env)
    return RadarFeatureObservation(env)


class MimoRadarSelectFlatVectorEnv(VectorEnv):
    """B trials of ``MimoRadarSelectFlat`` as one numpy computation: the vector entry point of
    the Flat ids (``gym.make_vec("MimoRadarSelectFlat-v1", num_envs=B,
    vectorization_mode="vector_entry_point")``).

    The batch engine of :class:`~mimo_radar_env.MimoRadarSelectVectorEnv` with the Flat env's
    valid action (one ``Discrete`` action per super arm, or station scores, as ``action``) and
    its float32 features (:class:`RadarFeatures`, computed for the batch at once). Trial ``i``
    of ``reset(seed=s)`` is the single Flat env reset with ``seed=s + i``, step for step. All
    trials end together after ``T`` steps; with ``autoreset_mode`` ``"next-step"`` (default,
    Gymnasium's) the next step resets them all; with ``"disabled"`` (what torchrl's
    ``GymWrapper`` takes) a step after the end raises and the caller resets, also through
    ``reset(options={"reset_mask": mask})`` with every trial in the mask (they run in
    lockstep). :meth:`action_masks` gives the allowed Discrete actions, (B, A).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(
        self,
        num_envs: int = 1,
        action: str = "auto",
        render_mode: str | None = None,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        **kwargs: Any,
    ):
        modes = {"next-step": AutoresetMode.NEXT_STEP, "disabled": AutoresetMode.DISABLED}
        mode = (
            modes.get(autoreset_mode, autoreset_mode) if isinstance(autoreset_mode, str) else autoreset_mode
        )
        if mode not in modes.values():
            raise ValueError(
                f"autoreset_mode must be one of {list(modes)} (or those AutoresetMode members), "
                f"got {autoreset_mode!r}"
            )
        #: As Gymnasium's own vector envs have it (torchrl's ``GymWrapper`` reads it).
        self.autoreset_mode = mode
        self.metadata = {**self.metadata, "autoreset_mode": self.autoreset_mode}
        from .envs import MimoRadarSelectVectorEnv

        self.env = MimoRadarSelectVectorEnv(num_envs=num_envs, render_mode=render_mode, **kwargs)
        self.num_envs = self.env.num_envs
        self.scenario = sc = self.env.scenario
        self.options = self.env.options
        self.action_form = action_form(action, sc)
        if self.action_form == "discrete":
            self.index: SuperArmIndex | None = SuperArmIndex(sc)
            self.single_action_space: spaces.Space = spaces.Discrete(self.index.size)
        else:
            self.index = None
            self.single_action_space = spaces.Box(-1.0, 1.0, (sc.num_tx + sc.num_rx,), np.float32)
        self.features = RadarFeatures(sc)
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (self.features.size,), np.float32)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.render_mode = None
        self._needs_reset = False

    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        if mask is not None and not np.all(mask):
            raise ValueError(
                "reset_mask must select every trial: the trials run in lockstep and end together"
            )
        obs, info = self.env.reset(seed=seed, options=options or None)
        self._needs_reset = False
        self._np_random, self._np_random_seed = self.env.np_random, self.env.np_random_seed
        return self.features.reset(obs), info

    def to_env_actions(self, actions: Any) -> NDArray[np.int8]:
        """The env's actions (B, M + N) for the batch's Flat actions."""
        if self.index is not None:
            return self.index.to_action(np.asarray(actions).reshape(self.num_envs))
        sc = self.scenario
        scores = np.asarray(actions, dtype=np.float64).reshape(self.num_envs, -1)
        return scores_to_action(scores, sc.num_tx, sc.tx_per_step, sc.rx_per_step)

    def step(
        self, actions: Any
    ) -> tuple[
        NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]
    ]:
        if self._needs_reset and self.autoreset_mode == AutoresetMode.DISABLED:
            raise RuntimeError(
                "the episode ended after the horizon; call reset() (autoreset_mode='disabled')"
            )
        if self._needs_reset:  # the inner env resets on this step; its action is not used
            obs, reward, terminated, truncated, info = self.env.step(None)
            self._needs_reset = False
            return self.features.reset(obs), reward, terminated, truncated, info
        obs, reward, terminated, truncated, info = self.env.step(self.to_env_actions(actions))
        self._needs_reset = bool((terminated | truncated).all())
        return self.features.step(obs), reward, terminated, truncated, info

    def action_masks(self) -> NDArray[np.bool_]:
        """The allowed Discrete actions of every trial, (B, A): all of them, since each is a
        valid super arm (``ValueError`` for station scores, which have no mask)."""
        if self.index is None:
            raise ValueError("station-score actions have no mask; make the env with action='discrete'")
        return np.ones((self.num_envs, self.index.size), dtype=bool)

    def oracle_action(self) -> NDArray[np.int8]:
        """The env's optimal super arms of the coming step, (B, M + N) (reads the truth)."""
        return self.env.oracle_action()
