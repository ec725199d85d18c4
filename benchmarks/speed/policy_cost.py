"""Every policy's cost per trial-step: time, and peak memory beside what it declares.

Run: ``python -m benchmarks.speed.policy_cost [--trials 4] [--steps 7] [--json FILE]``.

For each registered policy (``ppo`` needs a trained model and is left out) on random layouts
of 4 x 6 (``Ms, Ns = 2, 3``), 16 x 16 and 64 x 64 (``Ms = Ns = 4``) stations with K = 1 and
5 targets (``mimo_radar_env.random_scenario``, seed 0; ``fix1`` and ``fix2`` name stations of
the 4 x 6 paper layout, so there only), one vector env of ``--trials`` trials
and the tracker runs ``--steps`` steps after a warm-up step; it records the median time of
``act`` + ``step`` + ``update`` over the steps, per trial and the peak of numpy allocations
(tracemalloc) per trial, beside the memory the env and the policy declare per trial
(``memory_parts``, ``Agent.memory_per_trial``): the ratio ``measured / declared`` is at most
1 when the declarations are upper estimates. Beside the time, the time the harness estimates
from the declared operations (``benchmarks.harness.estimate_seconds`` for one shard of
``--trials`` trials). Index policies use the exact solver where the
smaller side has at most 200,000 subsets and ``alternating`` beyond (at 64 x 64).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
import tracemalloc
from pathlib import Path
from typing import Any

import numpy as np

import agents
from mimo_radar_env import VERSIONS, random_scenario
from mimo_radar_env.core.superarm import is_exact_affordable
from mimo_radar_env.envs.cost import memory_parts

from ..harness import estimate_seconds

#: (M, N, Ms, Ns) of the layouts measured.
LAYOUTS = ((4, 6, 2, 3), (16, 16, 4, 4), (64, 64, 4, 4))
TARGETS = (1, 5)
# trained models; station lists of the layout's own (fix1, fix2: 4 x 6)
SKIPPED = (*agents.learned_agents(), "fixed")


def measure_policy(policy: str, scenario: Any, trials: int, steps: int) -> dict[str, Any]:
    """One policy on one scenario: seconds per trial-step, measured and declared MiB per trial."""
    params: dict[str, Any] = {}
    cls = agents.agent_class(policy)
    if issubclass(cls, agents.IndexPolicy) and not is_exact_affordable(
        scenario.num_tx, scenario.num_rx, scenario.tx_per_step, scenario.rx_per_step
    ):
        params["solver"] = "alternating"
    agent = agents.make_agent(policy, scenario, seed=0, **params)
    env = agents.make_env(agent, trials, VERSIONS["v1"].options().to_dict(), scenario)
    episode = agents.Rollout(agent, env, seed=0)
    episode.step()  # warm-up: compilation and first allocations
    tracemalloc.start()
    try:
        times = []
        for _ in range(steps):
            start = time.perf_counter()
            episode.step()
            times.append(time.perf_counter() - start)
        seconds = steps * float(np.median(times))  # a one-off pause (collection, compilation) left out
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    env.close()
    _, env_per_trial = memory_parts(scenario)
    declared = env_per_trial + agents.costs.memory_per_trial(agent)
    options = dataclasses.replace(VERSIONS["v1"].options(), **agent.needs.observation_options)
    estimate = estimate_seconds(
        scenario,
        options,
        {policy: agents.costs.operations_per_trial_step(agent)},
        trials,
        1,
        trials,
        agent_seconds={policy: agents.costs.seconds_per_step(agent)},
    )
    return {
        "policy": policy,
        "solver": params.get("solver", getattr(getattr(agent, "solver", None), "name", "-")),
        "ms_per_trial_step": 1e3 * seconds / (steps * trials),
        "declared_ms_per_trial_step": 1e3 * estimate / trials,
        "measured_mib_per_trial": peak / trials / 2**20,
        "declared_mib_per_trial": declared / 2**20,
    }


def measure(
    trials: int = 4, steps: int = 5, progress: Any = print, layouts: tuple[tuple[int, ...], ...] = LAYOUTS
) -> list[dict[str, Any]]:
    """Every policy on every layout of ``layouts`` ((M, N, Ms, Ns)) and target count."""
    rows = []
    for num_tx, num_rx, ms, ns in layouts:
        for k in TARGETS:
            scenario = random_scenario(num_tx, num_rx, k, ms, ns, horizon=steps + 2, seed=0)
            for policy in agents.available_agents():
                if policy in SKIPPED or (policy in ("fix1", "fix2") and (num_tx, num_rx) != (4, 6)):
                    continue
                try:
                    row = measure_policy(policy, scenario, trials, steps)
                except (
                    ValueError
                ) as exc:  # a policy that refuses the layout (the planners: too many super arms)
                    progress(f"{num_tx} x {num_rx} K={k} {policy:<20} refused: {exc}")
                    continue
                rows.append({"M": num_tx, "N": num_rx, "Ms": ms, "Ns": ns, "K": k, **row})
                progress(
                    f"{num_tx} x {num_rx} K={k} {policy:<20} {row['ms_per_trial_step']:9.2f} ms/trial-step "
                    f"(declared {row['declared_ms_per_trial_step']:.2f}) "
                    f"{row['measured_mib_per_trial']:8.2f} MiB (declared {row['declared_mib_per_trial']:.2f})"
                )
    return rows


def record(rows: list[dict[str, Any]], trials: int, steps: int, seconds: float) -> dict[str, Any]:
    """The JSON record of a measurement (``docs/results/perf/policy_cost.json``)."""
    from ..studies.base import machine

    return {
        "command": f"python -m benchmarks.speed.policy_cost --trials {trials} --steps {steps}",
        "trials": trials,
        "steps": steps,
        "wall_s": round(seconds, 1),
        "machine": machine(),
        "rows": rows,
    }


def ratios(rows: list[dict[str, Any]]) -> dict[str, float]:
    """The largest measured / declared memory and the range of measured / estimated time."""
    times = [r["ms_per_trial_step"] / r["declared_ms_per_trial_step"] for r in rows]
    return {
        "policy_memory_measured_over_declared_max": max(
            r["measured_mib_per_trial"] / r["declared_mib_per_trial"] for r in rows
        ),
        "policy_time_measured_over_estimated_min": min(times),
        "policy_time_measured_over_estimated_max": max(times),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description="every policy's time and memory per trial-step")
    parser.add_argument("--trials", type=int, default=4)
    parser.add_argument("--steps", type=int, default=7)
    parser.add_argument("--json", default=None, help="write the rows to this file")
    args = parser.parse_args()
    start = time.perf_counter()
    rows = measure(args.trials, args.steps)
    figures = ratios(rows)
    print(f"largest measured / declared memory: {figures['policy_memory_measured_over_declared_max']:.2f}")
    print(
        f"measured / estimated time: from {figures['policy_time_measured_over_estimated_min']:.2f} "
        f"to {figures['policy_time_measured_over_estimated_max']:.2f}"
    )
    if args.json:
        result = record(rows, args.trials, args.steps, time.perf_counter() - start)
        Path(args.json).write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
