"""Every policy's cost per trial-step: time beside the harness's estimate, and peak memory beside
what it declares.

Run: ``python -m benchmarks.speed.policy_cost [--trials 4,50] [--steps 5] [--json FILE]``.

For each registered policy (``ppo`` needs a trained model and is left out) on random layouts
of 4 x 6 (``Ms, Ns = 2, 3``), 16 x 16 and 64 x 64 (``Ms = Ns = 4``) stations with K = 1 and
5 targets (``mimo_radar_env.random_scenario``, seed 0; ``fix1`` and ``fix2`` name stations of
the 4 x 6 paper layout, so there only), one vector env of each of ``--trials`` trial counts
runs ``--steps`` steps after a warm-up step, with one compute thread as a harness worker has;
it records the median time of ``act`` + ``step`` +
``update`` over the steps, per trial, and the peak of numpy allocations (tracemalloc) per trial
in one more step (traced apart: tracing slows a small batch's step several times),
beside the memory the env and the policy declare per trial (``memory_parts``,
``agents.costs.memory_per_trial``): the ratio ``measured / declared`` is at most 1 when the
declarations are upper estimates. Beside the time, the time the harness estimates from the
declared operations (``benchmarks.resources.estimate_seconds`` for one shard of that many trials).
The smallest trial count shows the per-step overhead, the larger one each trial's own work.
Index policies use the exact solver where the smaller side has at most 200,000 subsets and
``alternating`` beyond (at 64 x 64).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
import tracemalloc
from collections.abc import Sequence
from typing import Any

import numpy as np

import agents
from mimo_radar_env import VERSIONS, random_scenario
from mimo_radar_env.core.compiled import with_threads
from mimo_radar_env.core.superarm import is_exact_affordable
from mimo_radar_env.envs.cost import memory_parts

from ..outputs import output_file, write_json
from ..resources import estimate_seconds
from ..settings import integer

#: (M, N, Ms, Ns) of the layouts measured.
LAYOUTS = ((4, 6, 2, 3), (16, 16, 4, 4), (64, 64, 4, 4))
TARGETS = (1, 5)
#: The trial counts measured: the per-step overhead dominates the first, each trial's work the
#: second.
TRIALS = (4, 50)
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
    with with_threads(1):  # as in a harness worker (what the estimates are for)
        episode.step()  # warm-up: compilation and first allocations
        times = []
        for _ in range(steps):
            start = time.perf_counter()
            episode.step()
            times.append(time.perf_counter() - start)
        # the memory of one more step, traced apart: tracing slows a small batch's step several times
        tracemalloc.start()
        try:
            episode.step()
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    seconds = steps * float(np.median(times))  # a one-off pause (collection, compilation) left out
    env.close()
    _, env_per_trial = memory_parts(scenario)
    declared = env_per_trial + agents.costs.memory_per_trial(agent)
    options = dataclasses.replace(VERSIONS["v1"].options(), **agent.needs.observation_options)
    estimate = estimate_seconds(
        scenario,
        options,
        {policy: agents.costs.seconds_per_trial_step(agent)},
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
    trials: Sequence[int] = TRIALS,
    steps: int = 5,
    progress: Any = print,
    layouts: tuple[tuple[int, ...], ...] = LAYOUTS,
) -> list[dict[str, Any]]:
    """Every policy on every layout of ``layouts`` ((M, N, Ms, Ns)) and target count, at each
    trial count of ``trials``."""
    rows = []
    for num_tx, num_rx, ms, ns in layouts:
        for k in TARGETS:
            scenario = random_scenario(num_tx, num_rx, k, ms, ns, horizon=steps + 3, seed=0)
            for policy in agents.available_agents():
                if policy in SKIPPED or (policy in ("fix1", "fix2") and (num_tx, num_rx) != (4, 6)):
                    continue
                for batch in trials:
                    where = f"{num_tx} x {num_rx} K={k} B={batch:<3} {policy:<22}"
                    try:
                        row = measure_policy(policy, scenario, batch, steps)
                    except ValueError as exc:  # a planner refuses a layout of too many super arms
                        progress(f"{where} refused: {exc}")
                        break
                    rows.append(
                        {"M": num_tx, "N": num_rx, "Ms": ms, "Ns": ns, "K": k, "trials": batch, **row}
                    )
                    measured, declared = row["measured_mib_per_trial"], row["declared_mib_per_trial"]
                    mib = f"{measured:7.2f} MiB (declared {declared:.2f})"
                    progress(
                        f"{where} {row['ms_per_trial_step']:8.3f} ms/trial-step "
                        f"(estimated {row['declared_ms_per_trial_step']:.3f}) {mib}"
                    )
    return rows


def record(rows: list[dict[str, Any]], trials: Sequence[int], steps: int, seconds: float) -> dict[str, Any]:
    """The JSON record of a measurement (``docs/results/perf/policy_cost.json``)."""
    from ..study import machine

    counts = ",".join(str(t) for t in trials)
    return {
        "command": f"python -m benchmarks.speed.policy_cost --trials {counts} --steps {steps}",
        "trials": list(trials),
        "steps": steps,
        "wall_s": round(seconds, 1),
        "machine": machine(),
        "rows": rows,
    }


def time_ratio(row: dict[str, Any]) -> float:
    """A row's measured / estimated time."""
    return row["ms_per_trial_step"] / row["declared_ms_per_trial_step"]


def ratios(rows: list[dict[str, Any]]) -> dict[str, float]:
    """The largest measured / declared memory and the range of measured / estimated time."""
    times = [time_ratio(r) for r in rows]
    return {
        "policy_memory_measured_over_declared_max": max(
            r["measured_mib_per_trial"] / r["declared_mib_per_trial"] for r in rows
        ),
        "policy_time_measured_over_estimated_min": min(times),
        "policy_time_measured_over_estimated_max": max(times),
    }


def _counts(text: str) -> tuple[int, ...]:
    try:
        counts = tuple(int(t) for t in text.split(","))
    except ValueError:
        counts = ()
    if not counts or min(counts) < 1:
        raise argparse.ArgumentTypeError(f"trial counts must be integers >= 1, comma-separated, got {text!r}")
    return counts


def main() -> None:
    parser = argparse.ArgumentParser(description="every policy's time and memory per trial-step")
    parser.add_argument(
        "--trials", type=_counts, default=TRIALS, help="trial counts, comma-separated (default 4,50)"
    )
    parser.add_argument("--steps", type=integer(1), default=5)
    parser.add_argument("--json", type=output_file, default=None, help="write the rows to this file")
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
        write_json(args.json, result, indent=1)


if __name__ == "__main__":
    main()
