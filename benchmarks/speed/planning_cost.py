"""What looking ahead costs: the planners' time per step against best-tracking's, side by side.

Run: ``python -m benchmarks.speed.planning_cost [--trials 500] [--steps 5] [--json PATH]``
(``docs/results/perf/planning_cost.json``, which docs/performance.md's table is generated from).

On ``paper-1-v1`` (120 super arms) with ``--trials`` trials in one vector env (the tracker on,
the v1 defaults), it times ``act`` per step of best-tracking and of ``plan-tracking`` at H = 10
with each search, after a warm-up step, and prints each planner's time as a multiple of
best-tracking's (the planning issue's target: at most 10 at H = 10).
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

import agents
from mimo_radar_env import VERSIONS

from ..outputs import output_file, write_json
from ..settings import integer

#: (policy, parameters) measured against best-tracking.
PLANNERS = (
    ("plan-tracking", {"horizon": 10, "search": "beam"}),
    ("plan-tracking", {"horizon": 10, "search": "rollout"}),
    ("plan-tracking", {"horizon": 10, "search": "mcts"}),
)


def act_seconds(
    policy: str, params: dict[str, Any], trials: int, steps: int, scenario: str = "paper-1-v1"
) -> float:
    """The median time of one ``act`` of ``policy`` on ``trials`` trials (s)."""
    agent = agents.make_agent(policy, scenario, seed=0, **params)
    episode = agents.Rollout(agent, agents.make_env(agent, trials, VERSIONS["v1"].options()), seed=0)
    episode.step()  # the first step warms up
    return float(np.median([step.act_seconds for step in episode.run(steps)]))


def measure(trials: int = 500, steps: int = 5) -> dict[str, float]:
    """Each planner's act time per step (ms) and as a multiple of best-tracking's, measured in the
    same run."""
    reference = act_seconds("best-tracking", {}, trials, steps)
    ratios = {"best-tracking_ms_per_step": 1e3 * reference}
    for policy, params in PLANNERS:
        seconds = act_seconds(policy, params, trials, steps)
        name = f"{policy}:{params['horizon']}-{params['search']}"
        ratios[f"{name}_ms_per_step"] = 1e3 * seconds
        ratios[f"{name}_over_best_tracking"] = seconds / reference
    return ratios


#: The planning issue's target: planning at H = 10 costs at most this many times best-tracking.
TARGET_RATIO = 10.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=integer(1), default=500)
    parser.add_argument("--steps", type=integer(1), default=5)
    parser.add_argument(
        "--json", type=output_file, default=None, help="also write the figures and the machine to this file"
    )
    args = parser.parse_args()
    from ..study import machine

    before = machine()
    ratios = measure(args.trials, args.steps)
    for key, value in ratios.items():
        print(f"{key:<50} {value:10.2f}")
    if args.json:
        record = {
            "command": (
                f"python -m benchmarks.speed.planning_cost --trials {args.trials} --steps {args.steps}"
            ),
            "machine": before,
            "load_average_1min_after": machine()["load_average_1min"],
            "scenario": "paper-1-v1",
            "trials": args.trials,
            "steps": args.steps,
            "target_ratio": TARGET_RATIO,
            "figures": ratios,
        }
        write_json(args.json, record, indent=1)


if __name__ == "__main__":
    main()
