"""``MimoRadarSelect``: transmitter/receiver selection for a distributed MIMO radar (v0 and v1).

The single env and the native vector env stand side by side, as in Gymnasium's
``cartpole.py``; both drive the same :class:`~mimo_radar_env.envs.engine.RadarEngine`.
"""

from __future__ import annotations

import dataclasses
import inspect
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.envs.registration import EnvSpec
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from ..core.arrays import check_precision, device_namespace, float_precision
from ..core.motion import positions
from ..core.superarm import random_super_arms
from ..rendering import draw_scenario, figure_to_rgb
from ..scenarios import Scenario
from ..tracking.planning import Forecast
from .engine import RadarEngine
from .options import EnvOptions, options_markdown, resolve
from .versions import check_scenario_version, versions_markdown


def observation_space(
    scenario: Scenario, num_models: int | None = 3, prediction_covariance: bool = False
) -> spaces.Dict:
    """The observation space of one trial (see :class:`MimoRadarSelectEnv`).

    ``num_models=None`` is the space without a tracker (``tracking=False``);
    ``prediction_covariance=True`` adds ``track_pred_pos_cov`` and ``track_pred_cov``.
    """
    K, M, N = scenario.num_targets, scenario.num_tx, scenario.num_rx
    big = np.finfo(np.float64).max  # unbounded in principle; finite so that Box samples are finite
    radar = {
        "sinr": spaces.Box(0.0, big, (K, M, N), np.float64),
        "probed": spaces.MultiBinary((M, N)),
    }
    if num_models is None:
        return spaces.Dict(radar)
    return spaces.Dict(
        radar
        | {
            "track": spaces.Box(-big, big, (K, 4), np.float64),
            "track_pred": spaces.Box(-big, big, (K, 4), np.float64),
            "track_pos_cov": spaces.Box(-big, big, (K, 2, 2), np.float64),
            "mode_prob": spaces.Box(0.0, 1.0, (K, num_models), np.float64),
        }
        | (
            {
                "track_pred_pos_cov": spaces.Box(-big, big, (K, 2, 2), np.float64),
                "track_pred_cov": spaces.Box(-big, big, (K, 4, 4), np.float64),
            }
            if prediction_covariance
            else {}
        )
    )


def _squeeze(batch: dict[str, NDArray]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in batch.items():
        value = value[0]
        out[key] = value.item() if np.ndim(value) == 0 else value
    return out


class HorizonSpec:
    """``spec``, the registration spec, with ``max_episode_steps`` the scenario's horizon, where the
    env truncates (so Gymnasium adds no ``TimeLimit`` of its own): the single and the vector envs
    of both ids alike (:func:`with_horizon`)."""

    scenario: Scenario

    @property
    def spec(self) -> EnvSpec | None:
        return getattr(self, "_spec", None)

    @spec.setter
    def spec(self, value: EnvSpec | None) -> None:
        self._spec = with_horizon(value, self.scenario)


class MimoRadarSelectEnv(HorizonSpec, gym.Env[dict[str, NDArray], NDArray[np.int8]]):
    """
    ## Description

    A distributed MIMO radar with M transmitters (TX) and N receivers (RX) tracks
    K moving targets (Hao et al., "Combinatorial-restless-bandit-based
    Transmitter-Receiver Online Selection for Distributed MIMO Radars With
    Non-Stationary Channels"). Every step the controller selects exactly ``Ms``
    transmitters and ``Ns`` receivers; each selected TX-RX pair is a channel that
    returns, for every target, a Swerling-I SINR sample (Exponential with the
    channel's mean SINR, eq5) and a range-sum/azimuth measurement whose noise
    shrinks with the SINR (eq6, eq9, eq32). An IMM-UKF inside the env turns the
    measurements into target estimates, so a policy is judged on the SINR it
    collects and on how well the targets are tracked. The channel SINRs change
    as the targets move: the bandit is restless and non-stationary.

    ## Action Space

    ``MultiBinary(M + N)``: the first M bits select transmitters, the last N
    receivers. A valid action has exactly ``Ms`` ones among the first M bits and
    ``Ns`` among the last N. An action inside the space that breaks this probes
    nothing (reward 0, ``info["action_valid"] = False``, the tracker only
    predicts) unless the env is made with ``invalid_action="raise"``. An action
    outside the space (wrong shape, non-numeric dtype, values other than 0/1,
    NaN) raises ``ValueError``. ``env.unwrapped.sample_action()`` draws a valid
    action uniformly over the super arms (``action_space.sample()`` draws any
    ``MultiBinary`` vector, most of which probe nothing).

    ## Observation Space

    A ``Dict`` of what the radar controller knows after the step:

    | key | shape | meaning |
    |---|---|---|
    | ``sinr`` | (K, M, N) | SINR samples of the probed channels (linear), 0 elsewhere |
    | ``probed`` | (M, N) | 1 for the channels probed this step |
    | ``track`` | (K, 4) | fused IMM-UKF estimate ``[x, vx, y, vy]`` (eq22) |
    | ``track_pred`` | (K, 4) | one-step prediction for the next step (eq24) |
    | ``track_pos_cov`` | (K, 2, 2) | position covariance of ``track`` (m^2) |
    | ``mode_prob`` | (K, 3) | model probabilities: NCV, NCT(+3 deg/s), NCT(-3 deg/s) |
    | ``track_pred_pos_cov`` | (K, 2, 2) | predicted position covariance of ``track_pred`` (m^2) [1] |
    | ``track_pred_cov`` | (K, 4, 4) | the whole predicted covariance of ``track_pred`` [1] |

    [1] only with ``prediction_covariance=True`` (Arguments).

    The reset observation probes every channel once (Algorithm 1's
    initialisation): ``probed`` is all ones and ``track`` is the initial
    estimate ``X1_hat``.

    ## Rewards

    ``sum_k Omega_k sum_{(m, n) selected} gamma[k, m, n]`` (eq17): the weighted
    sum of the SINR samples of the selected channels; with ``reward="information"``, the
    tracker's position information gain of the step (Arguments). ``info`` carries both terms
    after every step: ``reward_sinr`` and (with the tracker) ``reward_information``.

    ## Info (truth, for evaluation only)

    ``mean_sinr`` (K, M, N), ``true_state`` (K, 4), ``position_error`` (K,) in
    metres; after a step also ``expected_reward`` (``mu_t`` of eq13 for the
    action), ``optimal_reward`` (``mu*_t``), ``optimal_action`` (M + N,),
    ``action_valid`` and, with the tracker, ``position_bound`` (K,): the posterior
    Cramer-Rao bound of the position error (m) for the selections made so far along the true
    trajectory (docs/model.md, section 14), and ``tracker_repairs``: how many covariances the
    tracker has repaired in this episode (docs/model.md, section 6; 0 in a healthy run).
    Non-oracle agents must not read them. The Best oracle reads
    the optimal super arm of the coming step with ``env.unwrapped.oracle_action()``.

    ## Starting State

    With ``truth="per-trial"`` (v0) the true state of each target is drawn from
    ``N(X1_hat, P1_hat)`` of the scenario and the tracker starts at ``X1_hat, P1_hat``; with
    ``truth="shared"`` (v1) the truth starts at ``X1_hat`` (one trajectory for all trials,
    from the scenario's ``truth_seed``) and the tracker at ``X1_hat + N(0, P1_hat)``.

    ## Episode End

    Truncation after the scenario's horizon ``T`` steps (1000 in the paper's
    scenarios), which ``env.spec.max_episode_steps`` reports. There is no termination.

    ## Arguments

    ``gym.make("MimoRadarSelect-v1", scenario=..., render_mode=None, **options,
    **scenario_overrides)``. ``scenario`` is a shipped scenario (each version's paper scenarios
    are listed below; another version's is refused with this one's name), a YAML/TOML file or a
    :class:`~mimo_radar_env.Scenario` (taken as given, under any version). The options
    (:class:`~mimo_radar_env.EnvOptions`, defaults first):

    {options}

    {versions}

    Any other keyword that names a scenario field overrides it (``horizon=200``); any other
    keyword raises ``TypeError``.

    ## Seeding

    ``reset(seed=s)`` determines every random draw of the episode. Trial ``i`` of
    the vector env reset with ``seed=s`` equals this env reset with ``seed=s + i``.
    The truth (initial states and process noise) has its own stream, so two
    policies run with the same seed see the same target trajectories.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 10}
    _spec: EnvSpec | None = None

    def __str__(self) -> str:
        return describe(type(self).__name__, self.spec, self.scenario, self.options)

    __repr__ = __str__

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}"
            )
        _refuse_vector_keywords(kwargs)
        self.options, self.scenario = _resolve(kwargs)
        self.engine = RadarEngine(self.options, self.scenario, batch_size=1)
        self.action_space = spaces.MultiBinary(self.engine.action_size)
        self.observation_space = _observation_space(self.engine)
        self.render_mode = render_mode
        self._truth_history: list[NDArray] = []
        self._track_history: list[NDArray] = []
        self._figure: Any = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, NDArray], dict[str, Any]]:
        """Start an episode: the truth, the channels and the tracker from ``seed`` (Seeding).

        Returns the reset observation, in which every channel is probed once (Algorithm 1's
        initialisation), and ``info`` with the truth (Info). ``options`` is accepted, as
        Gymnasium's API has it, and unused: the env's options are ``gym.make`` keywords.
        """
        check_reset(seed, options)
        super().reset(seed=seed)
        obs, info = self.engine.reset([self.np_random])
        self._truth_history = [positions(info["true_state"][0])]
        self._track_history = [positions(obs["track"][0])] if "track" in obs else []
        if self.render_mode == "human":
            self.render()
        return _squeeze(obs), _squeeze(info)

    def step(self, action: NDArray[np.int8]) -> tuple[dict[str, NDArray], float, bool, bool, dict[str, Any]]:
        """Probe the super arm ``action`` (``MultiBinary(M + N)``, Action Space) for one step.

        Returns ``(observation, reward, terminated, truncated, info)``: the SINR samples and the
        updated track, eq17's reward (or the information gain, per ``reward``), ``False``,
        ``True`` after the scenario's horizon, and the truth for evaluation (Info).
        """
        obs, reward, terminated, truncated, info = self.engine.step(
            _single_action(action, self.engine.action_size)
        )
        self._truth_history.append(positions(info["true_state"][0]))
        if "track" in obs:
            self._track_history.append(positions(obs["track"][0]))
        if self.render_mode == "human":
            self.render()
        return (
            _squeeze(obs),
            float(reward[0]),
            bool(terminated[0]),
            bool(truncated[0]),
            _squeeze(info),
        )

    def oracle_action(self) -> NDArray[np.int8]:
        """The optimal super arm for the coming step (reads the truth: oracle only)."""
        return self.engine.oracle_action()[0]

    def sample_action(self) -> NDArray[np.int8]:
        """A uniformly random *valid* action, (M + N,): exactly ``tx_per_step`` transmitters and
        ``rx_per_step`` receivers, drawn from the env's generator (``np_random``, seeded by
        ``reset(seed=...)``). ``action_space.sample()`` draws any ``MultiBinary`` vector, and most
        of those probe nothing."""
        return random_super_arms(self.np_random, 1, *_layout(self.scenario))[0]

    def tracking_oracle_action(self, criterion: str = "trace") -> NDArray[np.int8]:
        """The super arm for the coming step with the smallest predicted posterior position
        error (``"trace"``, m^2, or ``"logdet"``), from the tracker's prediction and the
        channels' true ``lambda`` (reads the truth: oracle only)."""
        return self.engine.tracking_oracle_action(criterion)[0]

    def tracking_forecast(self, horizon: int) -> Forecast:
        """The forecast a receding-horizon tracking oracle plans the next ``horizon`` steps on,
        as a batch of one trial (reads the truth: oracle only)."""
        return self.engine.tracking_forecast(horizon)

    def render(self) -> NDArray[np.uint8] | None:
        """Draw the stations, the true and estimated tracks and the current selection: an RGB
        array with ``render_mode="rgb_array"``, a matplotlib window with ``"human"`` (None);
        without a render mode it warns and returns None."""
        if self.render_mode is None:
            gym.logger.warn(
                "render() called without a render_mode; make the env with render_mode='rgb_array'"
            )
            return None
        if self.render_mode == "rgb_array":
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure

            fig = Figure(figsize=(6, 6), dpi=80)
            FigureCanvasAgg(fig)
            ax = fig.add_subplot()
        else:
            import matplotlib.pyplot as plt

            if self._figure is None:
                backend = plt.get_backend().lower()
                if backend in NON_INTERACTIVE_BACKENDS:
                    gym.logger.warn(
                        f"render_mode='human' shows nothing here: matplotlib's backend is {backend!r}, "
                        "which draws no window (no display: DISPLAY unset, or a headless machine). "
                        "Set a display or MPLBACKEND to an interactive backend, or make the env with "
                        "render_mode='rgb_array' to get the frames as arrays"
                    )
                plt.ion()
                self._figure = plt.figure(figsize=(6, 6), dpi=80)
            fig = self._figure
            fig.clf()
            ax = fig.add_subplot()
        draw_scenario(
            ax,
            self.scenario,
            true_tracks=np.array(self._truth_history),
            estimated_tracks=np.array(self._track_history),
            selection=self.engine.last_action[0] if self.engine.last_valid[0] else None,
            title=f"{self.scenario.name}  t = {self.engine.step_index}",
        )
        if self.render_mode == "rgb_array":
            return figure_to_rgb(fig)
        fig.canvas.draw_idle()
        fig.canvas.flush_events()
        return None

    def close(self) -> None:
        """Close the ``"human"`` render window, if one is open."""
        if self._figure is not None:
            import matplotlib.pyplot as plt

            plt.close(self._figure)
            self._figure = None


#: matplotlib backends that draw no window (``render_mode="human"`` warns on them).
NON_INTERACTIVE_BACKENDS = frozenset({"agg", "cairo", "pdf", "pgf", "ps", "svg", "template"})


def describe(kind: str, spec: EnvSpec | None, scenario: Scenario, options: EnvOptions) -> str:
    """``<Kind<Id> scenario='...', option=value, ...>`` with the options that differ from
    :class:`EnvOptions`' defaults (v0's)."""
    ident = f"<{spec.id}>" if spec is not None else ""
    parts = [f"scenario={scenario.name!r}", *(f"{k}={v!r}" for k, v in options.changed().items())]
    return f"<{kind}{ident} {', '.join(parts)}>"


def _observation_space(engine: RadarEngine) -> spaces.Dict:
    num_models = None if engine.tracker is None else engine.tracker.num_models
    return observation_space(engine.scenario, num_models, engine.options.prediction_covariance)


def check_reset(seed: Any, options: Any, batch: int | None = None) -> None:
    """Validate ``reset``'s arguments, for the single env and the vector envs alike: ``seed``
    None or an integer >= 0 (for a vector env of ``batch`` trials also a list of ``batch`` of
    them), ``options`` None or empty (the env's options are ``gym.make`` keywords). Raises
    ``ValueError`` showing the value as given."""
    seeds = seed if batch is not None and isinstance(seed, list | tuple) else [seed]
    if seed is not None and not all(
        isinstance(s, int | np.integer) and not isinstance(s, bool | np.bool_) and s >= 0 for s in seeds
    ):
        allowed = "an integer >= 0" + (" or a list of them" if batch is not None else "")
        raise ValueError(f"seed must be None or {allowed}, got {seed!r}")
    if batch is not None and isinstance(seed, list | tuple) and len(seed) != batch:
        raise ValueError(f"seed must be an int or a list of {batch} ints, got {len(seed)}")
    if options:
        raise ValueError(
            f"reset takes no options here, got {options!r}: the env's options are gym.make keywords "
            "(the Flat vector env takes reset_mask)"
        )


def with_horizon(spec: EnvSpec | None, scenario: Scenario) -> EnvSpec | None:
    """``spec`` with ``max_episode_steps`` the scenario's horizon, where every env truncates (so
    Gymnasium adds no ``TimeLimit`` of its own): the single and the vector envs alike."""
    if spec is not None and spec.max_episode_steps is None:
        spec = dataclasses.replace(spec, max_episode_steps=scenario.horizon)
    return spec


#: The autoreset modes of the native vector envs: Gymnasium's next-step (default), or none.
AUTORESET_MODES = {"next-step": AutoresetMode.NEXT_STEP, "disabled": AutoresetMode.DISABLED}


def autoreset_mode_of(value: str | AutoresetMode) -> AutoresetMode:
    """The :class:`AutoresetMode` of ``value`` (a name of :data:`AUTORESET_MODES` or a member)."""
    mode = AUTORESET_MODES.get(value, value) if isinstance(value, str) else value
    if mode not in AUTORESET_MODES.values():
        raise ValueError(
            f"autoreset_mode must be one of {list(AUTORESET_MODES)} (or those AutoresetMode members), "
            f"got {value!r}"
        )
    return mode


def _refuse_vector_keywords(kwargs: dict[str, Any]) -> None:
    """A keyword of the vector env alone (``device``, ``device_mode``, ``precision``...) given to
    the single env: the ``TypeError`` of an unexpected keyword, saying where it belongs."""
    own = inspect.signature(MimoRadarSelectVectorEnv.__init__).parameters
    vector_only = [name for name in own if name in kwargs and name not in ("self", "render_mode", "kwargs")]
    if vector_only:
        name = vector_only[0]
        given = "" if name == "num_envs" else f", {name}=..."
        raise TypeError(
            f"MimoRadarSelect got an unexpected keyword argument {name!r}: it is a keyword of the "
            "vector env, whose trials may run on torch: gym.make_vec('MimoRadarSelect-v1', num_envs=N, "
            f"vectorization_mode='vector_entry_point'{given}) (num_envs=1 for one trial)"
        )


def _resolve(kwargs: dict[str, Any]) -> tuple[EnvOptions, Scenario]:
    """The options and scenario of the keywords; a registered id passes its version
    (``env_version``), under which another version's paper scenario name is refused."""
    kwargs = dict(kwargs)
    check_scenario_version(kwargs.get("scenario"), kwargs.pop("env_version", None))
    return resolve(kwargs)


def _layout(scenario: Scenario) -> tuple[int, int, int, int]:
    """``M, N, Ms, Ns``: what a random super arm is drawn over."""
    return scenario.num_tx, scenario.num_rx, scenario.tx_per_step, scenario.rx_per_step


def _single_action(action: Any, size: int) -> NDArray:
    arr = np.asarray(action)
    if arr.shape != (size,):
        raise ValueError(
            f"action must have shape ({size},) (first M bits choose transmitters, the last N "
            f"receivers), got shape {arr.shape}"
        )
    return arr[None]


MimoRadarSelectEnv.__doc__ = (
    (MimoRadarSelectEnv.__doc__ or "")
    .replace("    {options}", options_markdown(indent="    "))
    .replace("    {versions}", versions_markdown(indent="    "))
)


class MimoRadarSelectVectorEnv(HorizonSpec, VectorEnv):
    """B trials of :class:`MimoRadarSelectEnv` as one numpy computation.

    Observations, rewards and every ``info`` entry carry a leading trial axis.
    All trials run in lockstep and end together after ``T`` steps; the step
    after that resets them all (``AutoresetMode.NEXT_STEP``) and returns the
    reset observation, or, with ``autoreset_mode="disabled"``, raises until the
    caller resets. ``spec.max_episode_steps`` is the horizon. ``device="cuda"``
    (or ``"cpu"``, ``"cuda:1"``) runs it on torch there, every array a tensor;
    ``device_mode="graph"`` replays each step as one CUDA graph and ``"compiled"`` runs it
    through ``torch.compile`` (:mod:`~mimo_radar_env.envs.device_forms`; default ``"eager"``);
    ``precision="float32"`` computes there in float32 (faster on a device, not the same numbers:
    docs/performance.md gives the measured difference; default ``"float64"``).
    ``reset(seed=s)`` seeds trial ``i`` with ``s + i``, exactly like a single env
    reset with ``seed=s + i``; ``seed`` may also be a list of per-trial seeds.
    :meth:`oracle_action` returns the optimal super arms of the coming step,
    (B, M + N); :meth:`sample_action` random valid ones.
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}
    #: As Gymnasium's own vector envs have it (torchrl's ``GymWrapper`` reads it).
    autoreset_mode = AutoresetMode.NEXT_STEP

    def __str__(self) -> str:
        text = describe(type(self).__name__, self.spec, self.scenario, self.options)
        return f"{text[:-1]}, num_envs={self.num_envs}>"

    __repr__ = __str__

    def __init__(
        self,
        num_envs: int = 1,
        render_mode: str | None = None,
        device: Any = None,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        device_mode: str = "eager",
        precision: str = "float64",
        **kwargs: Any,
    ) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
            raise ValueError(f"num_envs must be an integer >= 1, got {num_envs!r}")
        if render_mode is not None:
            raise ValueError("the vector env does not render; render a single MimoRadarSelect-v0 env")
        xp = device_namespace(device)  # a bad device is refused before the scenario is built
        check_precision(precision, device)
        self.options, self.scenario = _resolve(kwargs)
        self.num_envs = num_envs
        self.engine = RadarEngine(
            self.options,
            self.scenario,
            batch_size=num_envs,
            device=device,
            device_mode=device_mode,
            precision=precision,
        )
        #: where the trials run: ``None`` for numpy, else the ``torch.device`` of every tensor returned
        self.device = xp.device
        #: the step's form on torch (``"eager"``, ``"graph"``, ``"compiled"``)
        self.device_mode = device_mode
        #: As Gymnasium's own vector envs have it (torchrl's ``GymWrapper`` reads it).
        self.autoreset_mode = autoreset_mode_of(autoreset_mode)
        self.metadata = {**self.metadata, "autoreset_mode": self.autoreset_mode}
        self.single_action_space = spaces.MultiBinary(self.engine.action_size)
        self.single_observation_space = _observation_space(self.engine)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.render_mode = None
        self._trial_generators: list[np.random.Generator] | None = None
        self._needs_reset = False

    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, NDArray], dict[str, NDArray]]:
        """Start every trial: trial ``i`` seeded ``seed + i`` (or ``seed[i]`` for a list), as the
        single env reset with that seed. Returns the batched reset observation and info."""
        check_reset(seed, options, batch=self.num_envs)
        if seed is None and self._trial_generators is None:
            base = int(
                np.random.SeedSequence().entropy % (2**62)
            )  # fresh entropy, like gym's np_random(None)
            seed = base
        if seed is not None:
            seeds = [seed + i for i in range(self.num_envs)] if np.ndim(seed) == 0 else list(seed)
            self._trial_generators = [seeding.np_random(int(s))[0] for s in seeds]
            self._np_random, self._np_random_seed = seeding.np_random(int(seeds[0]))
        assert self._trial_generators is not None
        self._needs_reset = False
        return self.engine.reset(self._trial_generators)

    def step(
        self, actions: NDArray[np.int8]
    ) -> tuple[dict[str, NDArray], NDArray, NDArray, NDArray, dict[str, NDArray]]:
        """One step of every trial with actions (B, M + N); after the horizon the next call
        resets all trials (Gymnasium's next-step autoreset)."""
        if self._trial_generators is None:
            raise RuntimeError("call reset() before step()")
        if self._needs_reset and self.autoreset_mode == AutoresetMode.DISABLED:
            raise RuntimeError(
                "the episode ended after the horizon; call reset() (autoreset_mode='disabled')"
            )
        if self._needs_reset:
            obs, info = self.reset()
            xp = self.engine.xp
            zeros = xp.zeros(self.num_envs, dtype=bool)
            with float_precision(self.engine.precision):
                reward = xp.zeros(self.num_envs)
            return obs, reward, zeros, xp.copy(zeros), info
        obs, reward, terminated, truncated, info = self.engine.step(actions)
        self._needs_reset = bool(self.engine.step_index >= self.engine.horizon)
        return obs, reward, terminated, truncated, info

    def oracle_action(self) -> NDArray[np.int8]:
        """Optimal super arms for the coming step, (B, M + N) (reads the truth: oracle only)."""
        return self.engine.oracle_action()

    def sample_action(self) -> NDArray[np.int8]:
        """Uniformly random *valid* actions, (B, M + N), drawn from the env's generator
        (``np_random``, seeded by ``reset(seed=...)``); on a device, a tensor there."""
        actions = random_super_arms(self.np_random, self.num_envs, *_layout(self.scenario))
        return self.engine.xp.asarray(actions)

    def tracking_oracle_action(self, criterion: str = "trace") -> NDArray[np.int8]:
        """Super arms of the coming step with the smallest predicted posterior position error,
        (B, M + N) (reads the truth: oracle only)."""
        return self.engine.tracking_oracle_action(criterion)

    def tracking_forecast(self, horizon: int) -> Forecast:
        """The forecast a receding-horizon tracking oracle plans the next ``horizon`` steps of
        every trial on (reads the truth: oracle only)."""
        return self.engine.tracking_forecast(horizon)
