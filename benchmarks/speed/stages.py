"""Where a step's time goes: each stage of a v1 env step and of MG-CRB-CL's selection.

Run: ``python -m benchmarks.speed.stages [--trials 500] [--steps 40] [--json FILE]``.

On ``paper-1-v1`` with ``--trials`` trials in one vector env (the v1 defaults, the tracker and
the bound on), for each fusion, it times every stage of ``env.step`` by wrapping the engine's
methods (the simulation's draws and truth, the IMM-UKF update, the bound, the oracle's search
of the optimal super arm; the rest is the observation and ``info``), and MG-CRB-CL's ``act``
with the paper's BPSO and with the exact solver. Beside each stage's time it gives the
arithmetic the stage declares per trial-step (``core.model``'s and the agents' declarations)
and the rate that makes, which says whether a stage is bound by arithmetic (a rate near the
machine's) or by the overhead of many small calls (a low rate): docs/performance.md reads the
accelerator estimates from it.
"""

from __future__ import annotations

import argparse
import contextlib
import time
from typing import Any

import numpy as np

import agents
from mimo_radar_env import VERSIONS, MimoRadarSelectVectorEnv, load_scenario
from mimo_radar_env.core.superarm import random_super_arms, search_operations
from mimo_radar_env.envs import engine as engine_module
from mimo_radar_env.envs.cost import operations_per_trial_step

from ..outputs import output_file, write_json
from ..settings import integer

SCENARIO = "paper-1-v1"
#: An assumed sustained float64 rate of an accelerator (operations per second: a data-centre
#: GPU's order of magnitude, not measured here): the time the declared arithmetic alone would
#: take on it, a floor that ignores kernel launches and transfers.
ASSUMED_ACCELERATOR_OPS = 1e12


@contextlib.contextmanager
def timed(target: Any, attribute: str, spent: dict[str, float], stage: str):
    """Adds the time of every call of ``target.attribute`` to ``spent[stage]``."""
    original = getattr(target, attribute)

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            spent[stage] += time.perf_counter() - start

    setattr(target, attribute, wrapper)
    try:
        yield
    finally:
        setattr(target, attribute, original)


def env_stages(fusion: str, trials: int, steps: int, scenario: str = SCENARIO) -> dict[str, float]:
    """Seconds per step of each stage of the env's step (v1 defaults, random valid actions)."""
    options = VERSIONS["v1"].options(fusion=fusion).to_dict()
    env = MimoRadarSelectVectorEnv(num_envs=trials, scenario=scenario, **options)
    env.reset(seed=0)
    sc = env.scenario
    actions = random_super_arms(
        np.random.default_rng(0), trials, sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step
    )
    env.step(actions)  # warm-up: compilation, first allocations
    engine = env.engine
    spent = dict.fromkeys(("simulation", "tracker", "bound", "oracle search"), 0.0)
    with contextlib.ExitStack() as stack:
        for attribute in ("advance", "observe", "mean_sinr"):
            stack.enter_context(timed(engine.simulation, attribute, spent, "simulation"))
        stack.enter_context(timed(engine, "_track", spent, "tracker"))
        stack.enter_context(timed(engine, "_advance_bound", spent, "bound"))
        stack.enter_context(timed(engine_module, "position_bound", spent, "bound"))
        stack.enter_context(timed(engine_module, "best_super_arm", spent, "oracle search"))
        start = time.perf_counter()
        for _ in range(steps):
            env.step(actions)
        total = time.perf_counter() - start
    stages = {stage: seconds / steps for stage, seconds in spent.items()}
    stages["observation and info"] = total / steps - sum(stages.values())
    return stages


def act_seconds(solver: dict[str, Any], trials: int, steps: int) -> float:
    """MG-CRB-CL's ``act`` per step with ``solver`` (the first step warms up)."""
    agent = agents.make_agent("mg-crb-cl", SCENARIO, seed=0, **solver)
    episode = agents.Rollout(agent, agents.make_env(agent, trials, VERSIONS["v1"].options()), seed=0)
    episode.step()
    return sum(step.act_seconds for step in episode.run(steps)) / steps


def measure(trials: int = 500, steps: int = 40) -> dict[str, Any]:
    scenario = load_scenario(SCENARIO)
    sc = scenario
    rows = []
    for fusion in ("average", "centralized"):
        env_ops = operations_per_trial_step(scenario, True, fusion)
        oracle_ops = search_operations(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        for stage, seconds in env_stages(fusion, trials, steps).items():
            declared = {
                "oracle search": oracle_ops,
                "tracker": env_ops - oracle_ops - 60.0 * sc.num_tx * sc.num_rx,
            }
            rows.append(
                {
                    "fusion": fusion,
                    "stage": stage,
                    "ms_per_step": 1e3 * seconds,
                    **_rate(declared.get(stage), seconds, trials),
                }
            )
    for label, solver in (
        ("MG-CRB-CL act, BPSO (paper, rule set)", {"solver": "bpso", "solver_params": {"rule": "set"}}),
        ("MG-CRB-CL act, exact solver", {"solver": "exact"}),
    ):
        agent = agents.make_agent("mg-crb-cl", SCENARIO, seed=0, **solver)
        seconds = act_seconds(solver, trials, steps)
        rows.append(
            {
                "fusion": "-",
                "stage": label,
                "ms_per_step": 1e3 * seconds,
                **_rate(agents.costs.operations_per_trial_step(agent), seconds, trials),
            }
        )
    return {"scenario": SCENARIO, "trials": trials, "steps": steps, "rows": rows}


def _rate(operations: float | None, seconds: float, trials: int) -> dict[str, float]:
    if operations is None:
        return {}
    return {
        "declared_operations_per_trial": operations,
        "achieved_operations_per_s": operations * trials / seconds,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=integer(1), default=500)
    parser.add_argument("--steps", type=integer(1), default=40)
    parser.add_argument("--json", type=output_file, default=None)
    args = parser.parse_args()
    from ..study import machine

    record = {
        "command": f"python -m benchmarks.speed.stages --trials {args.trials} --steps {args.steps}",
        "machine": machine(),
        **measure(args.trials, args.steps),
    }
    for row in record["rows"]:
        rate = row.get("achieved_operations_per_s")
        print(
            f"{row['fusion']:<12} {row['stage']:<40} {row['ms_per_step']:8.2f} ms"
            + (f"  {rate:.2e} ops/s" if rate else "")
        )
    if args.json:
        write_json(args.json, record, indent=1)


if __name__ == "__main__":
    main()
