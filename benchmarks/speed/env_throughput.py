"""Vector env throughput: trial-steps per second with random valid actions.

Run: ``python -m benchmarks.speed.env_throughput [--trials 500] [--steps 200] [--scenario paper-1]``.
Prints trial-steps/s with and without the in-loop IMM-UKF tracker; the issue's
target (200,000 trial-steps/s at 500 trials on 2 cores) applies to the
simulation itself.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import mimo_radar_env  # noqa: F401  (registers the env)
from mimo_radar_env.core.superarm import random_super_arms


def measure(scenario: str, trials: int, steps: int, tracking: bool, fusion: str = "average") -> float:
    """Trial-steps per second of the vector env (actions drawn beforehand, not timed)."""
    venv = gym.make_vec(
        "MimoRadarSelect-v0",
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
    venv.reset(seed=0)
    venv.step(actions[0])  # warm-up
    start = time.perf_counter()
    for action in actions[1:]:
        venv.step(action)
    elapsed = time.perf_counter() - start
    return trials * (steps - 1) / elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="paper-1")
    parser.add_argument("--trials", type=int, default=500)
    parser.add_argument("--steps", type=int, default=200)
    args = parser.parse_args()
    print(f"vector env, {args.scenario}, {args.trials} trials, {args.steps} steps, random valid actions")
    for label, tracking, fusion in (
        ("simulation only (tracking=False)", False, "average"),
        ("with IMM-UKF, fusion=average", True, "average"),
        ("with IMM-UKF, fusion=centralized", True, "centralized"),
    ):
        rate = measure(args.scenario, args.trials, args.steps, tracking, fusion)
        print(f"  {label:<36} {rate:>12,.0f} trial-steps/s")


if __name__ == "__main__":
    main()
