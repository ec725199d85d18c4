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

from agents.ppo import (
    MODEL_FILE,
    NORMALIZATION_FILE,
    SB3_NORMALIZATION_FILE,
    require_sb3,
    save_normalization,
)
from mimo_radar_env import DEFAULT_VERSION, VERSIONS, EnvOptions, Scenario, load_scenario

from .harness import output_lock

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
    try:
        data = yaml.safe_load(text) or {}
    except yaml.YAMLError as exc:
        raise ValueError(f"{path} is not YAML: {' '.join(str(exc).split())}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path} must map env ids to hyperparameter entries, got {type(data).__name__}")
    if key not in data:
        raise ValueError(f"{path} has no entry {key!r}; entries: {sorted(map(str, data))}")
    if not isinstance(data[key], dict):
        raise ValueError(f"{path}: entry {key!r} must be a mapping of hyperparameters, got {data[key]!r}")
    params = dict(data[key])
    for name in ("policy_kwargs", "normalize"):
        if isinstance(params.get(name), str):
            params[name] = _parse_dict_call(params[name], name)
    check_hyperparams(params, f"{path}: entry {key!r}")
    return params


#: The integer and number hyperparameters train-ppo checks, with their ranges.
INTEGER_HYPERPARAMS = {
    "n_envs": (1, 256),
    "n_timesteps": (1, 10**9),
    "n_steps": (1, 10**6),
    "batch_size": (1, 10**7),
    "n_epochs": (1, 1000),
}
NUMBER_HYPERPARAMS = {
    "learning_rate": (0.0, 1.0),
    "gamma": (0.0, 1.0),
    "gae_lambda": (0.0, 1.0),
    "ent_coef": (0.0, 1.0),
    "vf_coef": (0.0, 10.0),
    "clip_range": (0.0, 10.0),
    "max_grad_norm": (0.0, 1e6),
}
#: VecNormalize's keywords an entry's ``normalize`` may give.
NORMALIZE_KEYS = ("norm_obs", "norm_reward", "clip_obs", "clip_reward", "gamma", "epsilon")
POLICIES = ("MlpPolicy",)


def check_hyperparams(params: dict[str, Any], where: str) -> None:
    """Refuse, naming the entry, a key train-ppo does not know and a value outside its range,
    before anything is trained or written."""
    from agents.parameters import check_integer, check_parameter

    known = _ppo_keywords() | _NOT_FOR_PPO | {"policy"}
    unknown = sorted(set(params) - known)
    if unknown:
        raise ValueError(f"{where}: unknown hyperparameter(s) {unknown}; known: {sorted(known)}")
    try:
        for name, (low, high) in INTEGER_HYPERPARAMS.items():
            if name in params:
                check_integer(name, params[name], low, high)
        for name, (low, high) in NUMBER_HYPERPARAMS.items():
            if name in params:
                check_parameter(name, params[name], low, high, low_open=name != "ent_coef")
    except ValueError as exc:
        hint = (
            " (rl-zoo3's 'lin_' schedules are not supported)"
            if isinstance(params.get("learning_rate"), str)
            else ""
        )
        raise ValueError(f"{where}: {exc}{hint}") from None
    if params.get("policy", POLICIES[0]) not in POLICIES:
        raise ValueError(f"{where}: policy must be one of {list(POLICIES)}, got {params['policy']!r}")
    normalize = params.get("normalize", False)
    if not isinstance(normalize, bool | dict):
        raise ValueError(f"{where}: normalize must be true, false or dict(...), got {normalize!r}")
    if isinstance(normalize, dict) and set(normalize) - set(NORMALIZE_KEYS):
        raise ValueError(
            f"{where}: normalize has unknown key(s) {sorted(set(normalize) - set(NORMALIZE_KEYS))}; "
            f"known: {list(NORMALIZE_KEYS)}"
        )
    kwargs = params.get("policy_kwargs", {})
    if not isinstance(kwargs, dict):
        raise ValueError(f"{where}: policy_kwargs must be dict(...), got {kwargs!r}")
    arch = kwargs.get("net_arch", [64])
    if not (isinstance(arch, list) and arch and all(isinstance(u, int) and 1 <= u <= 4096 for u in arch)):
        raise ValueError(
            f"{where}: policy_kwargs net_arch must be a list of layer sizes in [1, 4096], got {arch!r}"
        )
    steps, envs = params.get("n_steps", 2048), params.get("n_envs", 8)
    if params.get("batch_size", 64) > steps * envs:
        raise ValueError(
            f"{where}: batch_size {params['batch_size']} is more than a rollout's "
            f"n_steps x n_envs = {steps * envs}"
        )


def _ppo_keywords() -> set[str]:
    """The keywords of ``stable_baselines3.PPO`` an entry may set (those train-ppo sets itself
    excluded), or the usual ones when SB3 is not installed."""
    try:
        import inspect

        from stable_baselines3 import PPO
    except ImportError:
        return {
            "n_steps",
            "batch_size",
            "n_epochs",
            "learning_rate",
            "gamma",
            "gae_lambda",
            "ent_coef",
            "vf_coef",
            "clip_range",
            "clip_range_vf",
            "max_grad_norm",
            "target_kl",
            "policy_kwargs",
            "normalize_advantage",
            "use_sde",
            "sde_sample_freq",
            "stats_window_size",
        }
    own = {"self", "policy", "env", "seed", "verbose", "tensorboard_log", "device", "_init_setup_model"}
    return set(inspect.signature(PPO.__init__).parameters) - own


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
    try:
        node = ast.parse(text, mode="eval").body
        if not (isinstance(node, ast.Call) and getattr(node.func, "id", "") == "dict" and not node.args):
            raise ValueError
        return {kw.arg: ast.literal_eval(kw.value) for kw in node.keywords}
    except (SyntaxError, ValueError, TypeError):
        raise ValueError(
            f"{name} must look like dict(key=value, ...) with literal values, got {text!r}"
        ) from None


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
    overwrite: bool = False,
) -> dict[str, Any]:
    """Train PPO on the native vectorised env and save ``model.zip`` + normalisation stats in ``out``.

    Everything is checked before anything is written: the scenario, the hyperparameter entry
    (:func:`check_hyperparams`) and the folder, which is locked for the training. A folder that
    already holds a model is refused unless ``overwrite``, which first removes every file of the
    old model (so that no stale normalisation outlives it)."""
    sb3 = require_sb3()
    options = options or EnvOptions()
    sc = load_scenario(scenario)
    params = load_hyperparams(hyperparams, hyperparams_key or VERSIONS[DEFAULT_VERSION].flat_env_id)
    n_envs = int(params.get("n_envs", 8))
    if timesteps is not None and timesteps < 1:
        raise ValueError(f"timesteps must be >= 1, got {timesteps}")
    timesteps = int(timesteps or params.get("n_timesteps", 100_000))
    out = Path(out)
    with output_lock(out):
        _clear_model(out, overwrite)
        return _train(sb3, sc, params, timesteps, out, seed, action, tensorboard, progress, options, n_envs)


#: The files a trained model leaves in its folder.
MODEL_FILES = (MODEL_FILE, NORMALIZATION_FILE, SB3_NORMALIZATION_FILE, META_FILE)


def _clear_model(out: Path, overwrite: bool) -> None:
    old = [out / name for name in MODEL_FILES if (out / name).exists()]
    if old and not overwrite:
        raise ValueError(
            f"{out} already holds a trained model ({', '.join(p.name for p in old)}); "
            "pass --overwrite to replace it, or choose another --out"
        )
    for path in old:
        path.unlink()


def _train(
    sb3, sc, params, timesteps, out, seed, action, tensorboard, progress, options, n_envs
) -> dict[str, Any]:
    from stable_baselines3.common.vec_env import VecNormalize

    from mimo_radar_env.sb3 import NativeVecEnv

    normalization = normalize_kwargs(params)
    ppo_kwargs = {k: v for k, v in params.items() if k not in _NOT_FOR_PPO}
    policy = ppo_kwargs.pop("policy", "MlpPolicy")
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
        save_normalization(out / NORMALIZATION_FILE, venv)  # plain arrays: what the harness reads
        venv.save(str(out / SB3_NORMALIZATION_FILE))  # SB3's own format: VecNormalize.load reads it
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
