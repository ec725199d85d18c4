"""Vector env throughput: trial-steps per second with random valid actions.

Run: ``python -m benchmarks.speed.env_throughput [--trials 500] [--steps 200] [--scenario paper-1-v1]``.
Prints trial-steps/s with and without the in-loop IMM-UKF tracker (and, under v1, its position
bound), each fusion also on the numpy twins of its numba kernels, then those of the Flat
id (``MimoRadarSelectFlat-v1``, what learners train on) through its native vector entry point
against Gymnasium's sync vector env of single Flat envs (at most 50 of them), in the same run.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import time
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np

from mimo_radar_env import DEFAULT_VERSION  # importing the package registers the env
from mimo_radar_env.core.superarm import random_super_arms
from mimo_radar_env.envs import engine as engine_module
from mimo_radar_env.tracking import bound

from ..settings import integer


def measure(
    scenario: str,
    trials: int,
    steps: int,
    tracking: bool,
    fusion: str = "average",
    version: str = DEFAULT_VERSION,
    compiled: bool = True,
) -> float:
    """Trial-steps per second of the vector env (actions drawn beforehand, not timed): the env id
    of ``version`` with its defaults (the tracker's position bound is computed every step).
    ``compiled=False`` runs the numpy twins of the fusion's and the bound's numba kernels, the
    reference the compiled paths are measured against."""
    venv = gym.make_vec(
        f"MimoRadarSelect-{version}",
        num_envs=trials,
        vectorization_mode="vector_entry_point",
        scenario=scenario,
        tracking=tracking,
        fusion=fusion,
    )
    sc = venv.scenario
    rng = np.random.default_rng(0)
    actions = [
        random_super_arms(rng, trials, sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        for _ in range(steps)
    ]
    with contextlib.nullcontext() if compiled else numpy_paths(venv):
        return _trial_steps_per_s(venv, actions, trials)


@contextlib.contextmanager
def numpy_paths(venv: Any) -> Iterator[None]:
    """The env's fusion and position bound on their numpy paths (the numba kernels' twins, equal
    to 1e-10 and 1e-12) while the block runs."""
    engine = venv.unwrapped.engine if hasattr(venv, "unwrapped") else venv.engine
    fusion = engine.tracker.fusion if engine.tracker is not None else None
    original = engine_module.bound_step
    was = fusion.use_numba if fusion is not None else None
    engine_module.bound_step = functools.partial(bound.bound_step, use_numba=False)
    if fusion is not None:
        fusion.use_numba = False
    try:
        yield
    finally:
        engine_module.bound_step = original
        if fusion is not None:
            fusion.use_numba = was


def _trial_steps_per_s(venv, actions: list, trials: int) -> float:
    """Trial-steps per second of stepping ``venv`` through ``actions`` after a warm-up step."""
    venv.reset(seed=0)
    venv.step(actions[0])  # warm-up
    start = time.perf_counter()
    for action in actions[1:]:
        venv.step(action)
    elapsed = time.perf_counter() - start
    return trials * (len(actions) - 1) / elapsed


def flat_measure(scenario: str, trials: int, steps: int, mode: str) -> float:
    """Trial-steps per second of ``MimoRadarSelectFlat-v1`` through ``gym.make_vec`` with
    ``vectorization_mode`` ``mode``: ``"vector_entry_point"`` (the batch engine) or ``"sync"``
    (``trials`` single Flat envs stepped in turn); random Discrete actions drawn beforehand."""
    venv = gym.make_vec(
        "MimoRadarSelectFlat-v1",
        num_envs=trials,
        vectorization_mode=mode,
        scenario=scenario,
        action="discrete",
    )
    rng = np.random.default_rng(0)
    count = int(venv.single_action_space.n)
    actions = [rng.integers(0, count, trials) for _ in range(steps)]
    rate = _trial_steps_per_s(venv, actions, trials)
    venv.close()
    return rate


def ppo_training_rate(scenario: str, timesteps: int, native: bool, n_envs: int = 8) -> float:
    """Environment steps per second of SB3 PPO training (the shipped hyperparameters, one thread)
    on ``n_envs`` envs of ``scenario``: through the native vector env (``NativeVecEnv``, what
    ``train-ppo`` uses) or through SB3's ``DummyVecEnv`` of single Flat envs (``make_vec_env``)."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    from mimo_radar_env.sb3 import NativeVecEnv

    from ..training import algorithm_kwargs, load_hyperparams

    torch.set_num_threads(1)
    policy, params = algorithm_kwargs(load_hyperparams())
    if native:
        venv = NativeVecEnv(scenario, n_envs, seed=0, action="discrete")
    else:
        venv = make_vec_env(
            "MimoRadarSelectFlat-v1", n_envs=n_envs, seed=0, env_kwargs={"scenario": scenario}
        )
    model = PPO(policy, venv, seed=0, verbose=0, **params)
    start = time.perf_counter()
    model.learn(total_timesteps=timesteps)
    return model.num_timesteps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="paper-1-v1")
    parser.add_argument(
        "--env-version", default=DEFAULT_VERSION, help="the env id's version (default %(default)s)"
    )
    parser.add_argument("--trials", type=integer(1), default=500)
    parser.add_argument("--steps", type=integer(1), default=200)
    args = parser.parse_args()
    print(f"vector env, {args.scenario}, {args.trials} trials, {args.steps} steps, random valid actions")
    for label, tracking, fusion, compiled in (
        ("simulation only (tracking=False)", False, "average", True),
        ("with IMM-UKF, fusion=average", True, "average", True),
        ("  the same on the numpy paths", True, "average", False),
        ("with IMM-UKF, fusion=centralized", True, "centralized", True),
        ("  the same on the numpy paths", True, "centralized", False),
    ):
        rate = measure(args.scenario, args.trials, args.steps, tracking, fusion, args.env_version, compiled)
        print(f"  {label:<36} {rate:>12,.0f} trial-steps/s")
    flat = f"{args.scenario}-v1" if not args.scenario.endswith("-v1") else args.scenario
    for label, mode, trials in (
        ("Flat-v1, native vector entry point", "vector_entry_point", args.trials),
        ("Flat-v1, sync vector env (reference)", "sync", min(args.trials, 50)),
    ):
        rate = flat_measure(flat, trials, min(args.steps, 20), mode)
        print(f"  {label:<36} {rate:>12,.0f} trial-steps/s ({trials} trials)")


if __name__ == "__main__":
    main()
