"""PPO (Stable-Baselines3) as a learned baseline: training, saving, and an agent for the harness.

Needs the ``rl`` extra (``pip install torch==2.13.0 && pip install -e ".[rl]"``).
"""

from __future__ import annotations

import ast
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

import agents
from mimo_radar_env import Scenario, load_scenario
from mimo_radar_env.wrappers import RadarFeatures, SuperArmIndex, make_ppo_env, scores_to_action

DEFAULT_HYPERPARAMS = Path(__file__).with_name("hyperparams") / "ppo.yml"
MODEL_FILE = "model.zip"
NORMALIZATION_FILE = "vecnormalize.pkl"
META_FILE = "ppo.json"
_NOT_FOR_PPO = {"n_envs", "n_timesteps", "normalize"}


def require_sb3() -> Any:
    try:
        import stable_baselines3
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise ImportError(
            "PPO needs the rl extra: pip install torch==2.13.0 && pip install -e '.[rl]'"
        ) from exc
    return stable_baselines3


def load_hyperparams(path: str | Path | None = None, key: str = "MimoRadarSelect-v0") -> dict[str, Any]:
    """The rl-zoo3-style entry ``key`` of a YAML file (default: benchmarks/hyperparams/ppo.yml)."""
    import yaml

    path = Path(path) if path else DEFAULT_HYPERPARAMS
    data = yaml.safe_load(path.read_text()) or {}
    if key not in data:
        raise ValueError(f"{path} has no entry {key!r}; entries: {sorted(data)}")
    params = dict(data[key])
    if isinstance(params.get("policy_kwargs"), str):
        params["policy_kwargs"] = _parse_dict_call(params["policy_kwargs"])
    return params


def _parse_dict_call(text: str) -> dict[str, Any]:
    """rl-zoo3 writes ``"dict(net_arch=[64, 64])"``; parse it without eval."""
    node = ast.parse(text, mode="eval").body
    if not (isinstance(node, ast.Call) and getattr(node.func, "id", "") == "dict" and not node.args):
        raise ValueError(f"policy_kwargs must look like dict(key=value, ...), got {text!r}")
    return {kw.arg: ast.literal_eval(kw.value) for kw in node.keywords}


def train_ppo(
    scenario: str | Path | Scenario,
    timesteps: int | None,
    out: str | Path,
    seed: int = 0,
    hyperparams: str | Path | None = None,
    hyperparams_key: str = "MimoRadarSelect-v0",
    action: str = "auto",
    tensorboard: bool = False,
    progress: bool = True,
    fusion: str = "average",
) -> dict[str, Any]:
    """Train PPO on vectorised training envs and save ``model.zip`` + normalisation stats in ``out``."""
    sb3 = require_sb3()
    from stable_baselines3.common.vec_env import VecNormalize

    sc = load_scenario(scenario)
    params = load_hyperparams(hyperparams, hyperparams_key)
    n_envs = int(params.get("n_envs", 8))
    timesteps = int(timesteps or params.get("n_timesteps", 100_000))
    normalize = bool(params.get("normalize", True))
    ppo_kwargs = {k: v for k, v in params.items() if k not in _NOT_FOR_PPO}
    policy = ppo_kwargs.pop("policy", "MlpPolicy")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    venv = make_native_vec_env(sc, n_envs, seed, action=action, fusion=fusion)
    if normalize:
        venv = VecNormalize(venv, norm_obs=True, norm_reward=False)
    model = sb3.PPO(
        policy,
        venv,
        seed=seed,
        verbose=0,
        tensorboard_log=str(out / "tensorboard") if tensorboard else None,
        **ppo_kwargs,
    )
    start = time.perf_counter()
    model.learn(total_timesteps=timesteps, progress_bar=progress)
    wall = time.perf_counter() - start
    model.save(out / MODEL_FILE)
    if normalize:
        venv.save(str(out / NORMALIZATION_FILE))
    meta = {
        "scenario": sc.to_dict(),
        "timesteps": timesteps,
        "seed": seed,
        "n_envs": n_envs,
        "action": "discrete" if model.action_space.__class__.__name__ == "Discrete" else "scores",
        "normalize": normalize,
        "hyperparams": {k: v for k, v in params.items()},
        "train_wall_s": wall,
        "fusion": fusion,
    }
    (out / META_FILE).write_text(json.dumps(meta, indent=2, default=str))
    return meta


def make_native_vec_env(
    scenario: Scenario, n_envs: int, seed: int, action: str = "auto", fusion: str = "average"
):
    """An SB3 ``VecEnv`` over the native batch env: one numpy step for all training envs."""
    require_sb3()
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv

    from mimo_radar_env import MimoRadarSelectVectorEnv
    from mimo_radar_env.wrappers import StationScoreAction, SuperArmDiscreteAction

    class NativeVecEnv(VecEnv):
        """SB3 view of :class:`MimoRadarSelectVectorEnv` with the PPO features and actions.

        All envs end together after T steps; they are reset at once and the last
        features are returned as ``terminal_observation`` (SB3's convention).
        """

        render_mode = None

        def __init__(self) -> None:
            self.env = MimoRadarSelectVectorEnv(num_envs=n_envs, scenario=scenario, fusion=fusion)
            probe = make_ppo_env(scenario, action=action, fusion=fusion)
            self.discrete = isinstance(probe.env, SuperArmDiscreteAction)
            assert self.discrete or isinstance(probe.env, StationScoreAction)
            self.index = SuperArmIndex(scenario) if self.discrete else None
            self.features = RadarFeatures(scenario)
            self.seed_value = seed
            self.episode = 0
            self._actions: NDArray | None = None
            super().__init__(n_envs, probe.observation_space, probe.action_space)

        def reset(self) -> NDArray[np.float32]:
            obs, _ = self.env.reset(seed=self.seed_value + self.episode * self.num_envs)
            self.episode += 1
            self.returns = np.zeros(self.num_envs)
            self.lengths = 0
            return self.features.reset(obs)

        def step_async(self, actions: NDArray) -> None:
            self._actions = actions

        def step_wait(self):
            assert self._actions is not None
            if self.discrete:
                env_actions = self.index.to_action(np.asarray(self._actions).reshape(-1))
            else:
                env_actions = scores_to_action(
                    self._actions, scenario.num_tx, scenario.tx_per_step, scenario.rx_per_step
                )
            obs, reward, terminated, truncated, _ = self.env.step(env_actions)
            features = self.features.step(obs)
            self.returns += reward
            self.lengths += 1
            dones = terminated | truncated
            infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
            if dones.all():
                for i in range(self.num_envs):
                    infos[i] = {
                        "terminal_observation": features[i],
                        "TimeLimit.truncated": bool(truncated[i]),
                        "episode": {"r": float(self.returns[i]), "l": self.lengths, "t": 0.0},
                    }
                features = self.reset()
            return features, reward.astype(np.float32), dones, infos

        def close(self) -> None:
            pass

        def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
            return [getattr(self, attr_name)] * len(self._indices(indices))

        def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
            setattr(self, attr_name, value)

        def env_method(self, method_name: str, *args: Any, indices: Any = None, **kwargs: Any) -> list[Any]:
            raise NotImplementedError("NativeVecEnv has no per-env methods")

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

    return NativeVecEnv()


class PPOAgent(agents.Agent):
    """A trained PPO policy as a batch-native agent (for the harness and users).

    Loads ``model.zip`` and, when present beside it, the ``vecnormalize.pkl``
    observation statistics; computes the same :class:`RadarFeatures` as the training
    wrapper for B trials at once and acts deterministically.
    """

    name = "ppo"

    def __init__(
        self, scenario: Scenario | str, path: str | Path, seed: int | None = None, deterministic: bool = True
    ) -> None:
        super().__init__(scenario, seed)
        require_sb3()
        from stable_baselines3 import PPO

        path = Path(path)
        folder = path.parent if path.suffix == ".zip" else path
        model_file = path if path.suffix == ".zip" else path / MODEL_FILE
        if not model_file.exists():
            raise FileNotFoundError(f"no PPO model at {model_file}")
        self.model = PPO.load(model_file, device="cpu")
        self.deterministic = deterministic
        self.features = RadarFeatures(self.scenario)
        if self.model.observation_space.shape != (self.features.size,):
            raise ValueError(
                f"the model at {model_file} was trained on {self.model.observation_space.shape[0]} features; "
                f"this scenario has {self.features.size}: train it on this layout"
            )
        self.obs_rms = None
        norm_file = folder / NORMALIZATION_FILE
        if norm_file.exists():
            import pickle

            with open(norm_file, "rb") as handle:
                stats = pickle.load(handle)
            self.obs_rms, self.clip_obs, self.epsilon = stats.obs_rms, stats.clip_obs, stats.epsilon
        self.discrete = self.model.action_space.__class__.__name__ == "Discrete"
        self.index = SuperArmIndex(self.scenario) if self.discrete else None
        self._features: NDArray[np.float32] | None = None

    def _normalize(self, features: NDArray[np.float32]) -> NDArray[np.float32]:
        if self.obs_rms is None:
            return features
        scaled = (features - self.obs_rms.mean) / np.sqrt(self.obs_rms.var + self.epsilon)
        return np.clip(scaled, -self.clip_obs, self.clip_obs).astype(np.float32)

    def _reset(self, obs: dict[str, NDArray]) -> None:
        self._features = self.features.reset(obs)

    def _act(self, obs: dict[str, NDArray]) -> NDArray[np.int8]:
        actions, _ = self.model.predict(self._normalize(self._features), deterministic=self.deterministic)
        if self.discrete:
            return self.index.to_action(actions)
        return scores_to_action(actions, self.num_tx, self.tx_count, self.rx_count)

    def _update(self, obs: dict[str, NDArray], reward: NDArray[np.float64]) -> None:
        self._features = self.features.step(obs)
