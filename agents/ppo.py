"""Trained Stable-Baselines3 policies as batch-native agents: PPO (``ppo:PATH/model.zip``) and
sb3-contrib's MaskablePPO (``maskable-ppo:PATH``) and RecurrentPPO (``recurrent-ppo:PATH``).

:data:`LEARNERS` is the one home of what each learner is: its algorithm and policy classes,
rl-zoo3's name for it and its hyperparameter file; ``train-ppo --algo`` trains them and the
agents below evaluate them.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario
from mimo_radar_env.extras import require
from mimo_radar_env.wrappers import RadarFeatures, SuperArmIndex, make_ppo_env, scores_to_action

from .base import Agent, Observation
from .costs import BOOKKEEPING, NETWORK, Needs

#: Files written by ``mimo-radar-bench train-ppo`` into its output folder.
MODEL_FILE = "model.zip"
#: The weights and network shape of a torch-ppo training (:class:`~agents.networks.ActorCritic`).
WEIGHTS_FILE = "model.pt"
#: Observation normalisation statistics, as plain arrays (``np.load`` without pickles).
NORMALIZATION_FILE = "vecnormalize.npz"
#: The same statistics as SB3's ``VecNormalize.save`` writes them (a pickle), for SB3's
#: ``VecNormalize.load``; loaded here only when asked (``allow_pickle=True``).
SB3_NORMALIZATION_FILE = "vecnormalize.pkl"


@dataclass(frozen=True)
class Learner:
    """A deep-RL learner the project trains and evaluates.

    Attributes
    ----------
    name : str
        The agent's registered name and ``train-ppo --algo``'s choice.
    zoo_name : str
        rl-zoo3's ``--algo`` name (its hyperparameter file is ``hyperparams/ZOO_NAME.yml``).
    algorithm, policy : str
        ``module:Class`` of the algorithm and of its policy.
    policies : tuple of str
        The policy names an entry may give (``policy``).
    extra : str
        The optional dependency group that installs it.
    """

    name: str
    zoo_name: str
    algorithm: str
    policy: str
    policies: tuple[str, ...]
    extra: str = "rl"

    @property
    def hyperparams(self) -> str:
        return f"hyperparams/{self.zoo_name}.yml"

    def _load(self, target: str) -> Any:
        module, _, name = target.partition(":")
        require(module.split(".")[0], self.extra, self.algorithm.partition(":")[2])
        return getattr(importlib.import_module(module), name)

    def algorithm_class(self) -> Any:
        return self._load(self.algorithm)

    def policy_class(self) -> Any:
        return self._load(self.policy)


LEARNERS = {
    learner.name: learner
    for learner in (
        Learner(
            "ppo", "ppo", "stable_baselines3:PPO", "stable_baselines3.common.policies:ActorCriticPolicy",
            ("MlpPolicy",),
        ),
        Learner(
            "maskable-ppo", "ppo_mask", "sb3_contrib:MaskablePPO",
            "sb3_contrib.common.maskable.policies:MaskableActorCriticPolicy", ("MlpPolicy",),
        ),
        Learner(
            "recurrent-ppo", "ppo_lstm", "sb3_contrib:RecurrentPPO",
            "sb3_contrib.common.recurrent.policies:RecurrentActorCriticPolicy", ("MlpLstmPolicy",),
        ),
    )
}  # fmt: skip


def learner(name: str) -> Learner:
    """The learner called ``name``; ``ValueError`` naming those there are."""
    if name not in LEARNERS:
        raise ValueError(f"algo must be one of {list(LEARNERS)}, got {name!r}")
    return LEARNERS[name]


def save_normalization(path: Path, venv: Any) -> None:
    """The observation statistics of an SB3 ``VecNormalize`` as plain arrays."""
    rms = venv.obs_rms
    np.savez(
        path,
        mean=rms.mean,
        var=rms.var,
        count=np.array(rms.count),
        clip_obs=np.array(venv.clip_obs),
        epsilon=np.array(venv.epsilon),
    )


def load_normalization(path: Path, probe: Any) -> Any:
    """SB3's ``VecNormalize`` over ``probe`` with the statistics of ``path`` (no unpickling)."""
    from stable_baselines3.common.vec_env import VecNormalize

    with np.load(path, allow_pickle=False) as stats:
        normalization = VecNormalize(
            probe,
            training=False,
            norm_obs=True,
            norm_reward=False,
            clip_obs=float(stats["clip_obs"]),
            epsilon=float(stats["epsilon"]),
        )
        normalization.obs_rms.mean = stats["mean"]
        normalization.obs_rms.var = stats["var"]
        normalization.obs_rms.count = float(stats["count"])
    return normalization


def load_pickled_normalization(path: Path, probe: Any) -> Any:
    """SB3's ``VecNormalize.load`` of ``path`` over ``probe``, for evaluation: unpickling runs
    code from the file, so it warns, and callers reach it only when the user allowed it."""
    import warnings

    from stable_baselines3.common.vec_env import VecNormalize

    warnings.warn(
        f"unpickling {path} (allow_pickle=True): a pickle runs code from the file, so load only "
        "statistics you trust",
        UserWarning,
        stacklevel=3,
    )
    try:
        normalization = VecNormalize.load(str(path), probe)
    except Exception as exc:  # anything unpickling can raise
        raise ValueError(
            f"{path} is not a VecNormalize file SB3 can load ({type(exc).__name__}: {exc})"
        ) from exc
    if not isinstance(normalization, VecNormalize):
        raise ValueError(f"{path} does not hold SB3's VecNormalize statistics")
    normalization.training = False
    normalization.norm_reward = False
    return normalization


def normalization_file(model: Path, normalization: str | Path | None, allow_pickle: bool) -> Path | None:
    """The statistics a model is evaluated with: the file the user names (``normalization``),
    else the one beside the model (``vecnormalize.npz``, or with ``allow_pickle`` SB3's
    ``vecnormalize.pkl``), else none. Never from elsewhere: statistics in a subfolder (rl-zoo3
    keeps them in ``ENV_ID/vecnormalize.pkl`` beside the model) are refused by name, so that a
    model never runs silently without its normalisation."""
    if normalization is not None:
        path = Path(normalization)
        if not path.is_file():
            raise ValueError(f"normalization file {path} does not exist")
        if path.suffix not in (".npz", ".pkl"):
            raise ValueError(f"normalization must be a .npz (train-ppo's) or .pkl (SB3's) file, got {path}")
        if path.suffix == ".pkl" and not allow_pickle:
            raise ValueError(
                f"{path} is a pickle (SB3's VecNormalize.save), which runs code when loaded: "
                "pass allow_pickle=true to load it if you trust the file"
            )
        return path
    beside, pickled = model.parent / NORMALIZATION_FILE, model.parent / SB3_NORMALIZATION_FILE
    if beside.is_file():
        return beside
    if pickled.is_file():
        if allow_pickle:
            return pickled
        raise ValueError(
            f"{pickled} holds the model's normalisation as a pickle, which is not loaded unless "
            "asked (unpickling runs code): pass allow_pickle=true if you trust it"
        )
    elsewhere = sorted(model.parent.glob(f"*/{SB3_NORMALIZATION_FILE}"))
    if elsewhere:
        raise ValueError(
            f"the model was saved with normalisation statistics in {elsewhere[0]} (rl-zoo3's layout), "
            "which are not beside it: name them, normalization=PATH (with allow_pickle=true for a "
            ".pkl), or the model would run without them"
        )
    return None


def load_model(
    file: Path, observation_space: Any, num_stations: int, learner: Learner = LEARNERS["ppo"]
) -> Any:
    """``ALGORITHM.load`` of ``learner`` without unpickling anything: every cloudpickled entry of
    the model's data is supplied here (policy class, spaces, schedules), and SB3 reads the
    weights with ``torch.load(weights_only=True)``."""
    import json
    import zipfile

    from gymnasium import spaces

    try:
        with zipfile.ZipFile(file) as archive:
            data = json.loads(archive.read("data"))
    except (OSError, KeyError, ValueError, zipfile.BadZipFile) as exc:
        raise ValueError(f"{file} is not a Stable-Baselines3 model file ({exc})") from exc
    action = data.get("action_space", {})
    kind = str(action.get(":type:", ""))
    if "Discrete" in kind:
        action_space = spaces.Discrete(int(action["n"]))
    elif "Box" in kind:
        action_space = spaces.Box(-1.0, 1.0, (num_stations,), np.float32)  # StationScoreAction
    else:
        raise ValueError(f"{file}: unsupported action space {kind or 'missing'}")
    supplied = {
        "policy_class": learner.policy_class(),
        "observation_space": observation_space,
        "action_space": action_space,
        "lr_schedule": lambda _: 0.0,
        "learning_rate": 0.0,
        "clip_range": lambda _: 0.2,
        "clip_range_vf": None,
    }
    pickled = {key for key, value in data.items() if isinstance(value, dict) and ":serialized:" in value}
    custom = {key: supplied.get(key) for key in pickled} | {k: v for k, v in supplied.items() if k in data}
    return learner.algorithm_class().load(file, device="cpu", custom_objects=custom)


def model_file(path: str | Path) -> Path:
    """``PATH`` itself when it is a ``.zip`` file, else ``PATH/model.zip``."""
    path = Path(path)
    return path if path.suffix == ".zip" else path / MODEL_FILE


class PPOAgent(Agent):
    """A trained PPO policy (Stable-Baselines3), acting deterministically on B trials at once.

    Loads ``model.zip`` and, when present beside it, the ``vecnormalize.npz`` observation
    statistics (applied by SB3's ``VecNormalize``); computes the same
    :class:`~mimo_radar_env.wrappers.RadarFeatures` as the training wrapper for all trials
    and runs one forward pass per step for the whole batch.

    Nothing in the files is unpickled: the model's pickled entries (policy class, spaces,
    schedules) are supplied by this class, the weights are read with
    ``torch.load(weights_only=True)`` and the statistics with ``np.load(allow_pickle=False)``.
    A file can still hold weights that act badly; it cannot run code.

    Parameters
    ----------
    path : str or Path
        ``model.zip`` or the folder holding it.
    deterministic : bool
        Take the policy's most likely action (default) rather than sampling.
    normalization : str or Path, optional
        The observation statistics to apply (default: the file beside the model, see
        :func:`normalization_file`): ``train-ppo``'s ``.npz`` or SB3's ``.pkl``.
    allow_pickle : bool
        Allow loading SB3's pickled ``vecnormalize.pkl`` (default False: a pickle runs code
        from the file; it warns when it does).
    """

    name = "ppo"
    needs = Needs(tracking=True)
    costs = (BOOKKEEPING, NETWORK)
    learner: ClassVar[Learner] = LEARNERS["ppo"]

    def __init__(
        self,
        scenario: Scenario | str,
        path: str | Path,
        seed: int | None = None,
        deterministic: bool = True,
        normalization: str | Path | None = None,
        allow_pickle: bool = False,
    ) -> None:
        super().__init__(scenario, seed)
        self.learner.algorithm_class()  # DependencyNotInstalled naming the extra, before anything else
        file = model_file(path)
        if not file.is_file():
            raise ValueError(
                f"{self.name} model {file} does not exist: give a model's .zip file or the folder "
                f"train-ppo wrote, which holds its {MODEL_FILE}"
            )
        if not isinstance(allow_pickle, bool):
            raise ValueError(f"allow_pickle must be true or false, got {allow_pickle!r}")
        if normalization is not None and not isinstance(normalization, str | Path):
            raise ValueError(f"normalization must be the path of a statistics file, got {normalization!r}")
        stats = normalization_file(file, normalization, allow_pickle)
        self.features = RadarFeatures(self.scenario)
        from gymnasium import spaces

        observation_space = spaces.Box(-np.inf, np.inf, (self.features.size,), np.float32)
        try:
            self.model = load_model(file, observation_space, self.num_tx + self.num_rx, self.learner)
        except RuntimeError as exc:  # weights of another shape
            raise ValueError(
                f"the model at {file} does not fit this scenario's {self.features.size} features: "
                "train it on this layout"
            ) from exc
        self.deterministic = deterministic
        self.discrete = self.model.action_space.__class__.__name__ == "Discrete"
        self.index = SuperArmIndex(self.scenario) if self.discrete else None
        self.normalization = None
        self.normalization_file = stats
        if stats is not None:
            from stable_baselines3.common.vec_env import DummyVecEnv

            action = "discrete" if self.discrete else "scores"
            probe = DummyVecEnv([lambda: make_ppo_env(self.scenario, action=action)])
            if stats.suffix == ".pkl":
                self.normalization = load_pickled_normalization(stats, probe)
            else:
                self.normalization = load_normalization(stats, probe)
            if self.normalization.observation_space.shape != observation_space.shape:
                raise ValueError(
                    f"the statistics in {stats} are for {self.normalization.observation_space.shape} "
                    f"features, the scenario has {observation_space.shape}"
                )
        self._features: NDArray[np.float32] | None = None

    @property
    def network_weights(self) -> int:
        """The weights of the policy's network (its cost, ``agents.costs.NETWORK``)."""
        return sum(int(p.numel()) for p in self.model.policy.parameters())

    def _reset(self, obs: Observation) -> None:
        self._features = self.features.reset(obs)

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        features = self._features
        if self.normalization is not None:
            features = self.normalization.normalize_obs(features)
        actions = self._predict(features)
        if self.discrete:
            return self.index.to_action(actions)
        return scores_to_action(actions, self.num_tx, self.tx_count, self.rx_count)

    def _predict(self, features: NDArray[np.float32]) -> NDArray:
        """The policy's actions for the batch's (normalised) features."""
        actions, _ = self.model.predict(features, deterministic=self.deterministic)
        return actions

    def _update(self, obs: Observation, reward: NDArray[np.float64]) -> None:
        self._features = self.features.step(obs)


class MaskablePPOAgent(PPOAgent):
    """A trained MaskablePPO policy (sb3-contrib), acting on B trials at once with the env's
    action masks (every super arm of the Discrete action is valid, so the mask allows all).

    Parameters as :class:`PPOAgent`.
    """

    name = "maskable-ppo"
    learner = LEARNERS["maskable-ppo"]

    def _predict(self, features: NDArray[np.float32]) -> NDArray:
        if self.index is None:
            raise ValueError("MaskablePPO needs the Discrete action; retrain with --action discrete")
        masks = np.ones((features.shape[0], self.index.size), dtype=bool)
        actions, _ = self.model.predict(features, action_masks=masks, deterministic=self.deterministic)
        return actions


class RecurrentPPOAgent(PPOAgent):
    """A trained RecurrentPPO policy (sb3-contrib, an LSTM policy), acting on B trials at once;
    it carries each trial's LSTM state from step to step and starts it afresh at reset.

    Parameters as :class:`PPOAgent`.
    """

    name = "recurrent-ppo"
    learner = LEARNERS["recurrent-ppo"]

    def _reset(self, obs: Observation) -> None:
        super()._reset(obs)
        self._state: Any = None
        self._starts = np.ones(self.batch_size, dtype=bool)

    def _predict(self, features: NDArray[np.float32]) -> NDArray:
        actions, self._state = self.model.predict(
            features, state=self._state, episode_start=self._starts, deterministic=self.deterministic
        )
        self._starts = np.zeros(self.batch_size, dtype=bool)
        return actions


#: The project's own PPO (``train-ppo --algo torch-ppo``, plain torch, on any device), beside the
#: SB3 learners of :data:`LEARNERS`.
TORCH_PPO = "torch-ppo"
#: Every learner ``train-ppo --algo`` trains.
LEARNER_NAMES = (*LEARNERS, TORCH_PPO)


class TorchPPOAgent(Agent):
    """A policy trained by ``train-ppo --algo torch-ppo`` (``torch-ppo:PATH``), acting
    deterministically (the most likely super arm) on B trials at once, on the env's device.

    Loads ``model.pt`` (:class:`~agents.networks.ActorCritic`, read with ``weights_only=True``)
    and the ``vecnormalize.npz`` statistics beside it, computes the training env's features
    (:class:`~mimo_radar_env.wrappers.RadarFeatures`) for the batch and runs one forward pass per
    step. On an env made with ``device=`` everything stays on that device.

    Parameters
    ----------
    path : str or Path
        ``model.pt`` or the folder holding it.
    """

    name = TORCH_PPO
    needs = Needs(tracking=True, device=True)
    costs = (BOOKKEEPING, NETWORK)

    def __init__(self, scenario: Scenario | str, path: str | Path, seed: int | None = None) -> None:
        super().__init__(scenario, seed)
        require("torch", "rl", "the torch-ppo agent")
        from .networks import ActorCritic, RunningNormalization

        path = Path(path)
        file = path if path.suffix else path / WEIGHTS_FILE
        if not file.is_file():
            raise ValueError(
                f"torch-ppo model {file} does not exist: give the folder train-ppo --algo torch-ppo "
                f"wrote, or its {WEIGHTS_FILE}"
            )
        self.features = RadarFeatures(self.scenario)
        self.index = SuperArmIndex(self.scenario)
        self.network = ActorCritic.load(file)
        shape = self.network.shape
        if (shape["observation_size"], shape["action_count"]) != (self.features.size, self.index.size):
            raise ValueError(
                f"the model at {file} takes {shape['observation_size']} features and "
                f"{shape['action_count']} super arms; this scenario has {self.features.size} and "
                f"{self.index.size}: train it on this layout"
            )
        stats = file.parent / NORMALIZATION_FILE
        self.normalization_file = stats if stats.is_file() else None
        self.normalization = RunningNormalization.load(stats) if self.normalization_file else None

    @property
    def network_weights(self) -> int:
        """The weights of the actor-critic (its cost, ``agents.costs.NETWORK``)."""
        return sum(int(p.numel()) for p in self.network.parameters())

    def _reset(self, obs: Observation) -> None:
        import torch

        device = obs["sinr"].device if self.xp.is_torch else torch.device("cpu")
        self.network.to(device)
        if self.normalization is not None:
            self.normalization = self.normalization.to(device)
        self._features = self.features.reset(obs)

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        import torch

        features = self._features
        on_numpy = not self.xp.is_torch
        if on_numpy:
            features = torch.as_tensor(features)
        if self.normalization is not None:
            features = self.normalization(features)
        with torch.no_grad():
            logits, _ = self.network(features)
        choice = torch.argmax(logits, dim=-1)
        return self.index.to_action(choice.numpy() if on_numpy else choice)

    def _update(self, obs: Observation, reward: NDArray[np.float64]) -> None:
        self._features = self.features.step(obs)
