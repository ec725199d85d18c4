"""Training PPO (Stable-Baselines3) as a learned baseline; the trained policy is the registered
agent ``ppo`` (``agents.PPOAgent``, ``ppo:PATH/model.zip`` in a benchmark run).

Needs the ``rl`` extra (``pip install torch==2.13.0 && pip install 'mimo-radar-env[rl]'``).
"""

from __future__ import annotations

import ast
import json
import time
from importlib import resources
from pathlib import Path
from typing import Any

from agents.ppo import MODEL_FILE, NORMALIZATION_FILE, require_sb3, save_normalization
from mimo_radar_env import DEFAULT_VERSION, VERSIONS, EnvOptions, Scenario, load_scenario

#: The hyperparameter file shipped with the package (rl-zoo3 style).
DEFAULT_HYPERPARAMS = "hyperparams/ppo.yml"
META_FILE = "ppo.json"
_NOT_FOR_PPO = {"n_envs", "n_timesteps", "normalize"}


def load_hyperparams(
    path: str | Path | None = None, key: str = VERSIONS[DEFAULT_VERSION].flat_env_id
) -> dict[str, Any]:
    """The rl-zoo3 entry ``key`` of a YAML file (default: the shipped ``hyperparams/ppo.yml``).

    ``policy_kwargs`` and a ``normalize`` given as ``"dict(...)"`` are parsed as rl-zoo3 reads
    them (without eval); ``normalize: true`` means observations and rewards, as in rl-zoo3.
    """
    import yaml

    if path is None:
        text = (resources.files(__package__) / DEFAULT_HYPERPARAMS).read_text()
        path = DEFAULT_HYPERPARAMS
    else:
        text = Path(path).read_text()
    data = yaml.safe_load(text) or {}
    if key not in data:
        raise ValueError(f"{path} has no entry {key!r}; entries: {sorted(data)}")
    params = dict(data[key])
    for name in ("policy_kwargs", "normalize"):
        if isinstance(params.get(name), str):
            params[name] = _parse_dict_call(params[name], name)
    return params


def normalize_kwargs(params: dict[str, Any]) -> dict[str, Any] | None:
    """VecNormalize's keywords for an entry's ``normalize`` (None: no normalisation), as rl-zoo3."""
    normalize = params.get("normalize", False)
    if normalize is False:
        return None
    kwargs = dict(normalize) if isinstance(normalize, dict) else {}
    if "gamma" in params:
        kwargs["gamma"] = params["gamma"]
    return kwargs


def _parse_dict_call(text: str, name: str) -> dict[str, Any]:
    """rl-zoo3 writes ``"dict(net_arch=[64, 64])"``; parse it without eval."""
    node = ast.parse(text, mode="eval").body
    if not (isinstance(node, ast.Call) and getattr(node.func, "id", "") == "dict" and not node.args):
        raise ValueError(f"{name} must look like dict(key=value, ...), got {text!r}")
    return {kw.arg: ast.literal_eval(kw.value) for kw in node.keywords}


def train_ppo(
    scenario: str | Path | Scenario,
    timesteps: int | None,
    out: str | Path,
    seed: int = 0,
    hyperparams: str | Path | None = None,
    hyperparams_key: str | None = None,
    action: str = "auto",
    tensorboard: bool = False,
    progress: bool = True,
    options: EnvOptions | None = None,
) -> dict[str, Any]:
    """Train PPO on the native vectorised env and save ``model.zip`` + normalisation stats in ``out``."""
    sb3 = require_sb3()
    from stable_baselines3.common.vec_env import VecNormalize

    from mimo_radar_env.sb3 import NativeVecEnv

    options = options or EnvOptions()
    sc = load_scenario(scenario)
    params = load_hyperparams(hyperparams, hyperparams_key or VERSIONS[DEFAULT_VERSION].flat_env_id)
    n_envs = int(params.get("n_envs", 8))
    if timesteps is not None and timesteps < 1:
        raise ValueError(f"timesteps must be >= 1, got {timesteps}")
    timesteps = int(timesteps or params.get("n_timesteps", 100_000))
    normalization = normalize_kwargs(params)
    ppo_kwargs = {k: v for k, v in params.items() if k not in _NOT_FOR_PPO}
    policy = ppo_kwargs.pop("policy", "MlpPolicy")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    venv = NativeVecEnv(sc, n_envs, seed, action=action, **options.to_dict())
    if normalization is not None:
        venv = VecNormalize(venv, **normalization)
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
    if normalization is not None:
        save_normalization(out / NORMALIZATION_FILE, venv)
    meta = {
        "scenario": sc.to_dict(),
        "env_options": options.to_dict(),
        "timesteps": timesteps,
        "seed": seed,
        "n_envs": n_envs,
        "action": "discrete" if model.action_space.__class__.__name__ == "Discrete" else "scores",
        "normalize": normalization,
        "hyperparams": dict(params),
        "train_wall_s": wall,
    }
    (out / META_FILE).write_text(json.dumps(meta, indent=2, default=str))
    return meta
