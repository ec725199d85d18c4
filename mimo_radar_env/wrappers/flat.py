"""The learning envs: an env with a valid action and the feature observation.

:func:`make_flat_env` is the entry point of the registered ``MimoRadarSelectFlat-v0``/``-v1``,
for tools that take an env id (``make_vec_env``, rl-zoo3, torchrl's ``GymEnv``);
:class:`MimoRadarSelectFlatVectorEnv` is their vector entry point, B trials in one batch;
:func:`make_ppo_env` wraps the env of a ``MimoRadarSelect`` id of one's choice.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from ..core.superarm import super_arm_count
from ..envs.mimo_radar_select import HorizonSpec
from ..envs.versions import DEFAULT_VERSION, ENV_IDS
from ..scenarios import Scenario
from . import actions as action_spaces
from .features import RadarFeatureObservation, RadarFeatures


def make_ppo_env(
    scenario: Any = None, action: str = "auto", env_id: str = ENV_IDS[DEFAULT_VERSION], **kwargs: Any
) -> gym.Env:
    """``MimoRadarSelect`` (``env_id``, default v1) wrapped for PPO: flat features and valid actions.

    ``scenario``: a name, file or :class:`~mimo_radar_env.Scenario` (default: the env id's
    paper scenario 1, ``paper-1-v1`` for v1).
    ``action``: ``"discrete"`` (one action per super arm), ``"scores"`` (station
    scores) or ``"auto"`` (discrete when there are at most 1,000 super arms).
    """
    if env_id not in ENV_IDS.values():
        raise ValueError(f"env_id must be one of {sorted(ENV_IDS.values())}, got {env_id!r}")
    env = gym.make(env_id, **kwargs) if scenario is None else gym.make(env_id, scenario=scenario, **kwargs)
    return wrap_for_learning(env, action)


def make_flat_env(action: str = "auto", render_mode: str | None = None, **kwargs: Any) -> gym.Env:
    """Entry point of ``MimoRadarSelectFlat-v0``/``-v1``: the env (``kwargs`` as for
    ``MimoRadarSelect``) with a valid action (``action`` as in :func:`make_ppo_env`) and the
    float32 feature observation of :class:`RadarFeatures`."""
    from ..envs import MimoRadarSelectEnv

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
        env = action_spaces.SuperArmDiscreteAction(env)
    else:
        env = action_spaces.StationScoreAction(env)
    return RadarFeatureObservation(env)


class MimoRadarSelectFlatVectorEnv(HorizonSpec, VectorEnv):
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
        from ..envs.mimo_radar_select import autoreset_mode_of

        #: As Gymnasium's own vector envs have it (torchrl's ``GymWrapper`` reads it).
        self.autoreset_mode = autoreset_mode_of(autoreset_mode)
        self.metadata = {**self.metadata, "autoreset_mode": self.autoreset_mode}
        from ..envs import MimoRadarSelectVectorEnv

        self.env = MimoRadarSelectVectorEnv(num_envs=num_envs, render_mode=render_mode, **kwargs)
        self.num_envs = self.env.num_envs
        #: where the trials run (``device=`` as for ``MimoRadarSelectVectorEnv``): ``None`` for
        #: numpy, else the ``torch.device`` of every tensor returned
        self.device = self.env.device
        self.scenario = sc = self.env.scenario
        self.options = self.env.options
        self.action_form = action_form(action, sc)
        if self.action_form == "discrete":
            self.index: action_spaces.SuperArmIndex | None = action_spaces.SuperArmIndex(sc)
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
            return self.index.to_action(
                action_spaces.check_discrete_actions(actions, self.index.size, (self.num_envs,))
            )
        sc = self.scenario
        scores = action_spaces.check_score_actions(actions, sc.num_tx + sc.num_rx, (self.num_envs,))
        return action_spaces.scores_to_action(scores, sc.num_tx, sc.tx_per_step, sc.rx_per_step)

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
        return self.env.engine.xp.ones((self.num_envs, self.index.size), dtype=bool)

    def oracle_action(self) -> NDArray:
        """The optimal super arms of the coming step in this env's action space (reads the truth):
        their ``Discrete`` indices (B,), or station scores (B, M + N), +1 the selected stations.
        :meth:`oracle_env_action` gives them as the raw env's ``MultiBinary`` actions."""
        actions = self.env.oracle_action()
        if self.index is not None:
            return self.index.to_index(actions)
        return self.env.engine.xp.astype(2.0 * actions - 1.0, np.float32)

    def oracle_env_action(self) -> NDArray[np.int8]:
        """The optimal super arms of the coming step as the raw env's actions, (B, M + N)."""
        return self.env.oracle_action()
