"""Training the learned baselines: PPO (Stable-Baselines3), MaskablePPO and RecurrentPPO
(sb3-contrib), one seed or several; each trained policy is the registered agent of its learner
(``agents.ppo.LEARNERS``: ``ppo:PATH/model.zip`` in a benchmark run).

Needs the ``rl`` extra (``pip install torch==2.13.0 && pip install 'mimo-radar-env[rl]'``).
"""

from __future__ import annotations

import ast
import contextlib
import json
import time
from collections.abc import Iterator
from importlib import resources
from pathlib import Path
from typing import Any

from agents.ppo import (
    LEARNERS,
    MODEL_FILE,
    NORMALIZATION_FILE,
    SB3_NORMALIZATION_FILE,
    TORCH_PPO,
    WEIGHTS_FILE,
    Learner,
    learner,
    save_normalization,
)
from mimo_radar_env import DEFAULT_VERSION, VERSIONS, EnvOptions, Scenario, load_scenario
from mimo_radar_env.envs.device_forms import check_device_mode
from mimo_radar_env.extras import require
from mimo_radar_env.wrappers.flat import action_form

from .harness import CONFIG_FILE, HarnessError, RunInterrupted, check_device, output_lock
from .resources import duration
from .training_log import CURVE_FIGURE, CURVE_FILE, META_FILE, LearningCurve

_NOT_FOR_PPO = {"n_envs", "n_timesteps", "normalize"}


def load_hyperparams(
    path: str | Path | None = None,
    key: str | None = None,
    algo: str = "ppo",
) -> dict[str, Any]:
    """The rl-zoo3 entry ``key`` (default: the default version's Flat env id) of a YAML file
    (default: the shipped file of learner ``algo``, ``hyperparams/ppo.yml`` for PPO and for
    torch-ppo, which reads PPO's hyperparameters).

    ``policy_kwargs`` and a ``normalize`` given as ``"dict(...)"`` are parsed as rl-zoo3 reads
    them (without eval); ``normalize: true`` means observations and rewards, as in rl-zoo3.
    """
    import yaml

    spec = learner("ppo" if algo == TORCH_PPO else algo)
    key = key or VERSIONS[DEFAULT_VERSION].flat_env_id
    if path is None:
        text = (resources.files(__package__) / spec.hyperparams).read_text()
        path = spec.hyperparams
    else:
        try:
            text = Path(path).read_text()
        except (OSError, UnicodeDecodeError) as exc:
            raise ValueError(
                f"cannot read the hyperparameters {path}: {getattr(exc, 'strerror', None) or exc}"
            ) from None
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
    check_hyperparams(params, f"{path}: entry {key!r}", spec)
    return params


#: The integer and number hyperparameters train-ppo checks, with their ranges (``n_envs`` up to the
#: thousands torch-ppo runs on a device).
INTEGER_HYPERPARAMS = {
    "n_envs": (1, 1 << 20),
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


def check_hyperparams(params: dict[str, Any], where: str, spec: Learner = LEARNERS["ppo"]) -> None:
    """Refuse, naming the entry, a key train-ppo does not know for learner ``spec`` and a value
    outside its range, before anything is trained or written."""
    from agents.parameters import check_integer, check_parameter

    known = _ppo_keywords(spec) | _NOT_FOR_PPO | {"policy"}
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
    if params.get("policy", spec.policies[0]) not in spec.policies:
        raise ValueError(
            f"{where}: policy must be one of {list(spec.policies)} for {spec.name}, got {params['policy']!r}"
        )
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


def _ppo_keywords(spec: Learner = LEARNERS["ppo"]) -> set[str]:
    """The keywords of the learner's algorithm (``stable_baselines3.PPO``...) an entry may set
    (those train-ppo sets itself excluded), or PPO's usual ones when it is not installed."""
    import inspect

    from gymnasium.error import DependencyNotInstalled

    try:
        algorithm = spec.algorithm_class()
    except (ImportError, DependencyNotInstalled):
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
    return set(inspect.signature(algorithm.__init__).parameters) - own


def algorithm_kwargs(params: dict[str, Any], spec: Learner = LEARNERS["ppo"]) -> tuple[str, dict[str, Any]]:
    """The policy name and the algorithm's keywords of an entry (the keys train-ppo reads itself,
    ``n_envs``, ``n_timesteps`` and ``normalize``, left out)."""
    kwargs = {k: v for k, v in params.items() if k not in _NOT_FOR_PPO}
    return kwargs.pop("policy", spec.policies[0]), kwargs


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


#: Training timesteps per second of one worker process, on the developers' machine (paper
#: scenario 1, the shipped hyperparameters): the scale of a training's time estimate.
TRAINING_STEPS_PER_S = {"ppo": 3000.0, "maskable-ppo": 3000.0, "recurrent-ppo": 1280.0}
#: torch-ppo's seconds per step of its B parallel trials (a rollout step and its share of the
#: update), ``fixed + per_trial * B``: fitted to the training benchmark
#: (``benchmarks.speed.training_rate``) on CPU torch on the developers' two cores (B = 8, 64, 512:
#: 800 to 7,700 env steps per second) and on one H200 (B = 8 to 16,384: 440 to 713,000).
TORCH_PPO_STEP_SECONDS = {"cpu": (9e-3, 1.1e-4), "cuda": (1.7e-2, 3.4e-7)}
#: Trainings sharing a CUDA device run together at most this many times one training's rate:
#: eight of 4,096 trials on an H200 trained 364,498 env steps per second together (the RL study,
#: results/perf/device-checks.json), one alone 233,398 (the training benchmark). Measured at eight
#: only; fewer are assumed to reach it as soon as they can.
SHARED_DEVICE_GAIN = 1.56


def estimate_training_seconds(
    algo: str, timesteps: int, device: str | None = None, n_envs: int = 8, at_once: int = 1
) -> float:
    """One training's wall time, roughly, with ``at_once`` such trainings running together (one
    process each): ``timesteps`` at :data:`TRAINING_STEPS_PER_S`; torch-ppo's from
    :data:`TORCH_PPO_STEP_SECONDS` on ``device`` (CPU torch unless a CUDA device) with ``n_envs``
    parallel trials, which set its speed. On the CPU each training has its own core; on a CUDA
    device ``at_once`` trainings share it, together at most :data:`SHARED_DEVICE_GAIN` times one's
    rate."""
    if algo == TORCH_PPO:
        on_cuda = str(device).startswith("cuda")
        fixed, per_trial = TORCH_PPO_STEP_SECONDS["cuda" if on_cuda else "cpu"]
        alone = timesteps / n_envs * (fixed + per_trial * n_envs)
        sharing = max(1, at_once) if on_cuda else 1
        return alone * sharing / min(sharing, SHARED_DEVICE_GAIN)
    return timesteps / TRAINING_STEPS_PER_S[algo]


def _check_training_time(
    algo: str,
    timesteps: int,
    seeds: int,
    workers: int,
    device: str | None,
    max_hours: float | None,
    say,
    n_envs: int,
) -> None:
    """Says the trainings' estimated time when it is a minute or more; refuses them beyond
    ``max_hours`` (seeds ``workers`` at a time, sharing a device where one is given)."""
    at_once = min(workers, seeds)
    seconds = estimate_training_seconds(algo, timesteps, device, n_envs, at_once) * -(-seeds // at_once)
    what = f"{seeds} training(s) of {timesteps:,} `timesteps` of {algo}"
    if max_hours is not None and seconds > 3600 * max_hours:
        raise HarnessError(
            f"{what} would take about {duration(seconds)}, more than `max_hours` {max_hours:g}: use fewer "
            "`timesteps` or `seeds`, or a larger `max_hours`"
        )
    if seconds >= 60:
        say(f"{what}: about {duration(seconds)} on a machine like the developers' (a rough estimate)")


@contextlib.contextmanager
def _saved_only_at_its_end(out: Path) -> Iterator[None]:
    """Ctrl-C or SIGTERM during a single training, said as what it means: nothing of it is kept."""
    try:
        yield
    except KeyboardInterrupt:
        raise RunInterrupted(
            f"interrupted: the training into {out} had not finished, and a training is saved only at "
            "its end; run the same command again to train it from its first step"
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
    algo: str = "ppo",
    seeds: int = 1,
    workers: int = 1,
    record: dict[str, Any] | None = None,
    seed_folders: bool = False,
    device: str | None = None,
    n_envs: int | None = None,
    max_hours: float | None = None,
    say=print,
    device_mode: str = "eager",
) -> dict[str, Any]:
    """Train learner ``algo`` (PPO, MaskablePPO or RecurrentPPO, or the project's own torch-ppo)
    on the native vectorised env and save the model (``model.zip``; torch-ppo's ``model.pt``), the
    normalisation statistics, the learning curve and ``ppo.json`` in ``out``; with ``seeds`` > 1,
    seeds ``seed``, ``seed + 1``, ... each into ``out/seed-S``, ``workers`` at a time, resumably
    (a finished seed is kept); ``seed_folders`` uses that layout for a single seed too. torch-ppo
    trains on ``device`` (default ``"cpu"``; the SB3 learners take none), its env's step in form
    ``device_mode`` (:mod:`mimo_radar_env.envs.device_forms`; the same numbers), with PPO's
    hyperparameter entry; ``n_envs`` overrides the entry's number of parallel trials. The
    trainings' estimated time (:func:`estimate_training_seconds`) is said through ``say`` when
    it is a minute or more, and refused beyond ``max_hours``.

    Everything is checked before anything is written: the scenario, the hyperparameter entry
    (:func:`check_hyperparams`) and the folder, which is locked for the training: one of a
    benchmark run is refused, one of a model unless ``overwrite``, which first removes every file
    of the old model (so that no stale normalisation outlives it). Returns the training's ``ppo.json``
    (with ``seeds`` > 1: ``{"seeds": {S: ppo.json}, ...}``), with ``record``'s entries added."""
    spec, device = _learner_and_device(algo, device, device_mode)
    options = options or EnvOptions()
    sc = load_scenario(scenario)
    params = load_hyperparams(
        hyperparams, hyperparams_key or VERSIONS[DEFAULT_VERSION].flat_env_id, spec.name
    )
    if spec.name == "maskable-ppo" and action == "scores":
        raise ValueError("maskable-ppo masks a Discrete action: use --action discrete or auto")
    _check_counts(n_envs, timesteps, seeds, workers)
    config = _torch_config(params, n_envs, action, sc) if algo == TORCH_PPO else None
    n_envs = int(n_envs or params.get("n_envs", 8))
    timesteps = int(timesteps or params.get("n_timesteps", 100_000))
    _check_training_time(algo, timesteps, seeds, workers, device, max_hours, say, n_envs)
    out = _training_folder(out)
    job = training_job(sc, timesteps, algo, options, hyperparams, hyperparams_key, action)
    if n_envs != params.get("n_envs", 8):
        job["n_envs"] = n_envs  # recorded only when it overrides the entry's
    if seeds == 1 and not seed_folders:
        with output_lock(out), _saved_only_at_its_end(out):
            _clear_model(out, overwrite)
            if config is None:
                meta = _train(
                    spec, sc, params, timesteps, out, seed, action, tensorboard, progress, options, n_envs
                )
            else:
                meta = _train_torch(sc, timesteps, out, seed, config, options, device, device_mode, progress)
            return _recorded(meta, record, out)
    with output_lock(out):
        done = train_jobs(
            [(job, out, s) for s in range(seed, seed + seeds)],
            workers,
            overwrite,
            progress,
            device,
            device_mode,
        )
    return {
        "seeds": {s: done[out, s] for s in range(seed, seed + seeds)},
        "timesteps": timesteps,
        "algo": algo,
    }


def _train_torch(
    sc: Scenario,
    timesteps: int,
    out: Path,
    seed: int,
    config: Any,
    options: EnvOptions,
    device: str,
    device_mode: str,
    progress: bool,
) -> dict[str, Any]:
    """One torch-ppo training into ``out`` (:func:`benchmarks.torch_ppo.train`), its curve logged."""
    from . import torch_ppo

    log = LearningCurve(timesteps, progress, name=TORCH_PPO)
    return torch_ppo.train(
        sc, timesteps, out, seed, config, options, device=device, device_mode=device_mode, log=log
    )


def _recorded(meta: dict[str, Any], record: dict[str, Any] | None, out: Path) -> dict[str, Any]:
    """A training's ppo.json with ``record``'s entries added (and written again where there are any)."""
    if record:
        meta.update(record)
        (out / META_FILE).write_text(json.dumps(meta, indent=2, default=str))
    return meta


def _check_counts(n_envs: int | None, timesteps: int | None, seeds: int, workers: int) -> None:
    if n_envs is not None:
        from agents.parameters import check_integer

        check_integer("n_envs", n_envs, *INTEGER_HYPERPARAMS["n_envs"])
    if timesteps is not None and timesteps < 1:
        raise ValueError(f"timesteps must be >= 1, got {timesteps}")
    for name, value in (("seeds", seeds), ("workers", workers)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {value!r}")


def _torch_config(params: dict[str, Any], n_envs: int | None, action: str, scenario: Scenario) -> Any:
    """torch-ppo's configuration of a checked entry; it learns the Discrete action only."""
    from .torch_ppo import PPOConfig

    if action_form(action, scenario) != "discrete":
        raise ValueError(f"{TORCH_PPO} learns the Discrete super-arm action: use --action discrete or auto")
    return PPOConfig.from_hyperparams(params, n_envs, normalize_kwargs(params))


def _learner_and_device(
    algo: str, device: str | None, device_mode: str = "eager"
) -> tuple[Learner, str | None]:
    """The learner whose hyperparameters ``algo`` reads (torch-ppo reads PPO's) and the device it
    trains on (torch-ppo: ``device`` or ``"cpu"``; the SB3 learners: none), its dependencies
    checked first; ``ValueError`` for a device or a traced form of the step (``device_mode``)
    given to an SB3 learner, or a device or form not there."""
    if algo == TORCH_PPO:
        require("torch", "rl", TORCH_PPO)
        device = "cpu" if device is None else device
        check_device(device)  # a bad device is refused before anything is written
        check_device_mode(device_mode, device)
        return learner("ppo"), device
    spec = learner(algo)
    spec.algorithm_class()  # DependencyNotInstalled naming the extra, before anything else
    if device is not None or device_mode != "eager":
        what = "no device" if device is not None else f"no device_mode ({device_mode!r})"
        raise ValueError(
            f"{algo} (Stable-Baselines3) trains on the numpy env and takes {what}; "
            f"the project's own PPO does: algo={TORCH_PPO!r} (--algo {TORCH_PPO})"
        )
    return spec, None


def seed_folder(out: str | Path, seed: int) -> Path:
    """Where seed ``seed`` of a several-seed training is saved."""
    return Path(out) / f"seed-{seed}"


def training_job(
    scenario: Scenario,
    timesteps: int,
    algo: str = "ppo",
    options: EnvOptions | None = None,
    hyperparams: str | Path | None = None,
    hyperparams_key: str | None = None,
    action: str = "auto",
) -> dict[str, Any]:
    """What a training is, as recorded in each seed's ``ppo.json`` (a finished seed is kept only
    when its job is the same)."""
    return {
        "scenario": scenario.to_dict(), "timesteps": timesteps, "hyperparams": hyperparams,
        "hyperparams_key": hyperparams_key, "action": action,
        "options": (options or EnvOptions()).to_dict(), "algo": algo,
    }  # fmt: skip


def train_jobs(
    tasks: list[tuple[dict[str, Any], Path, int]],
    workers: int,
    overwrite: bool = False,
    progress: bool = True,
    device: str | None = None,
    device_mode: str = "eager",
) -> dict[tuple[Path, int], dict[str, Any]]:
    """Every ``(job, out, seed)`` trained into ``seed_folder(out, seed)``, ``workers`` processes at
    once, resumably: a seed whose ``ppo.json`` records the same job is kept, one that records
    another is refused unless ``overwrite``; an unfinished one is trained again. Returns each
    task's ``ppo.json`` by ``(out, seed)``. torch-ppo's jobs run on ``device`` (with one worker in
    this process; with more, their processes share the device), the step in form ``device_mode``
    (an execution setting, not part of a job)."""
    done, todo = {}, []
    for job, out, seed in tasks:
        meta_file = seed_folder(out, seed) / META_FILE
        meta = json.loads(meta_file.read_text()) if meta_file.is_file() else {}
        if "job" in meta and not overwrite:  # finished (the job is written last)
            if json.loads(json.dumps(meta["job"], default=str)) != json.loads(json.dumps(job, default=str)):
                raise ValueError(
                    f"{meta_file.parent} holds another training (a different scenario, budget or "
                    "hyperparameters); pass --overwrite to replace it, or choose another --out"
                )
            done[Path(out), seed] = meta
        else:
            todo.append((job, Path(out), seed))
    if done and progress:
        print(f"train-ppo: {len(done)} of {len(tasks)} trainings already done; training {len(todo)}")
    try:
        _train_todo(todo, workers, progress, device, done, len(tasks), device_mode)
    except KeyboardInterrupt:
        import os

        folder = os.path.commonpath([str(out) for _, out, _ in tasks])
        raise RunInterrupted(
            f"interrupted: {len(done)} of {len(tasks)} trainings finished and saved in {folder} "
            "(an unfinished one is trained again); run the same command again to resume"
        ) from None
    return done


def _train_todo(
    todo: list[tuple[dict[str, Any], Path, int]],
    workers: int,
    progress: bool,
    device: str | None,
    done: dict[tuple[Path, int], dict[str, Any]],
    total: int,
    device_mode: str = "eager",
) -> None:
    """Train ``todo`` into ``done``: in ``workers`` processes (on ``device``, sharing it), or with
    one worker and a device, one after another in this process."""
    if todo and device is not None and workers == 1:
        for job, out, seed in todo:
            done[out, seed] = _train_one_seed(job, str(out), seed, device, device_mode)
            if progress:
                print(f"train-ppo: {seed_folder(out, seed)} trained ({len(done)}/{total})")
    elif todo:
        from .backends import each_finished, worker_pool

        # the longest trainings first, so that the last ones to finish are short (results do not
        # depend on the order: each training is its own seeded run)
        longest_first = sorted(todo, key=lambda task: -task[0]["timesteps"])
        with worker_pool(min(workers, len(todo))) as pool:
            futures = {
                pool.submit(_train_one_seed, job, str(out), seed, device, device_mode, True): (out, seed)
                for job, out, seed in longest_first
            }
            pool.close()

            def trained(future: Any) -> None:
                done[futures[future]] = future.result()
                if progress:
                    out, seed = futures[future]
                    print(f"train-ppo: {seed_folder(out, seed)} trained ({len(done)}/{total})")

            each_finished(futures, trained)


def _train_one_seed(
    job: dict[str, Any],
    out: str,
    seed: int,
    device: str | None = None,
    device_mode: str = "eager",
    in_worker: bool = False,
) -> dict[str, Any]:
    import torch

    if in_worker:
        torch.set_num_threads(1)  # one compute thread per worker, as the harness's
    options = EnvOptions(**job["options"])
    return train_ppo(
        Scenario.from_dict(job["scenario"]), job["timesteps"], seed_folder(out, seed), seed=seed,
        hyperparams=job["hyperparams"], hyperparams_key=job["hyperparams_key"], action=job["action"],
        progress=False, options=options, overwrite=True, algo=job["algo"], record={"job": job},
        device=device, n_envs=job.get("n_envs"), device_mode=device_mode,
        say=lambda message: None,  # the time of the whole group was said (or refused) before it
    )  # fmt: skip


#: The files a trained model leaves in its folder.
MODEL_FILES = (MODEL_FILE, WEIGHTS_FILE, NORMALIZATION_FILE, SB3_NORMALIZATION_FILE, META_FILE, CURVE_FIGURE)


def _training_folder(out: str | Path) -> Path:
    """``out`` as a path, refused where it holds a benchmark run (a model beside its files)."""
    out = Path(out)
    if (out / CONFIG_FILE).is_file() or (out / "shards").is_dir():
        raise ValueError(f"{out} holds a benchmark run (its {CONFIG_FILE} or shards/): choose another --out")
    return out


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
    spec: Learner, sc, params, timesteps, out, seed, action, tensorboard, progress, options, n_envs
) -> dict[str, Any]:
    from stable_baselines3.common.vec_env import VecNormalize

    from mimo_radar_env.sb3 import NativeVecEnv

    normalization = normalize_kwargs(params)
    policy, ppo_kwargs = algorithm_kwargs(params, spec)
    venv = NativeVecEnv(sc, n_envs, seed, action=action, **options.to_dict())
    if normalization is not None:
        venv = VecNormalize(venv, **normalization)
    model = spec.algorithm_class()(
        policy,
        venv,
        seed=seed,
        verbose=0,
        tensorboard_log=str(out / "tensorboard") if tensorboard else None,
        **ppo_kwargs,
    )
    curve = LearningCurve(timesteps, progress, name=spec.name)
    rollout = model.n_steps * n_envs
    curve.start(-(-timesteps // rollout) * rollout)
    start = time.perf_counter()
    model.learn(total_timesteps=timesteps, callback=curve.callback())
    wall = time.perf_counter() - start
    out.mkdir(parents=True, exist_ok=True)
    model.save(out / MODEL_FILE)
    if normalization is not None:
        save_normalization(out / NORMALIZATION_FILE, venv)  # plain arrays: what the harness reads
        venv.save(str(out / SB3_NORMALIZATION_FILE))  # SB3's own format: VecNormalize.load reads it
    curve.write(out / CURVE_FILE, f"{spec.name} on {sc.name}")
    meta = {
        "algo": spec.name,
        "scenario": sc.to_dict(),
        "env_options": options.to_dict(),
        "timesteps": timesteps,
        # what the learner ran: whole rollouts of n_steps x n_envs, at least the timesteps asked
        "trained_timesteps": int(model.num_timesteps),
        "seed": seed,
        "n_envs": n_envs,
        "action": "discrete" if model.action_space.__class__.__name__ == "Discrete" else "scores",
        "normalize": normalization,
        "hyperparams": dict(params),
        "train_wall_s": wall,
    }
    (out / META_FILE).write_text(json.dumps(meta, indent=2, default=str))
    return meta
