"""Cost per step against array size (M*N), targets (K) and trials (B), with memory peaks.

Run: ``python -m benchmarks.speed.scaling [--steps 10]``. Each row runs the vector env under v1's
options (its in-loop tracker and the tracker's position bound) and a UCB1 agent on a random
layout in 100 km x 100 km (the exact solver
where ``min(C(M,Ms), C(N,Ns)) <= 20,000``, alternating maximisation beyond, as the env's
oracle does), and reports
milliseconds per step, microseconds per trial-step, and the peak of numpy allocations
(tracemalloc) during the steps. Growth exponents are fitted on log-log scales.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc
from typing import Any

import numpy as np

import agents
from mimo_radar_env import VERSIONS, random_scenario
from mimo_radar_env.core.superarm import AUTO_EXACT_SUBSETS, is_exact_affordable

from ..outputs import output_file, write_json
from ..settings import integer


def measure(
    num_tx: int, num_rx: int, num_targets: int, tx_count: int, rx_count: int, trials: int, steps: int
) -> dict[str, float]:
    scenario = random_scenario(num_tx, num_rx, num_targets, tx_count, rx_count)
    solver = (
        "exact"
        if is_exact_affordable(num_tx, num_rx, tx_count, rx_count, AUTO_EXACT_SUBSETS)
        else "alternating"
    )
    agent = agents.make_agent("ucb1", scenario, seed=0, solver=solver)
    episode = agents.Rollout(agent, agents.make_env(agent, trials, VERSIONS["v1"].options()), seed=0)
    episode.step()  # warm-up
    tracemalloc.start()
    start = time.perf_counter()
    for _ in episode.run(steps):
        pass
    elapsed = time.perf_counter() - start
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    per_step = elapsed / steps
    return {
        "M": num_tx,
        "N": num_rx,
        "Ms": tx_count,
        "Ns": rx_count,
        "K": num_targets,
        "B": trials,
        "solver": solver,
        "ms_per_step": 1e3 * per_step,
        "us_per_trial_step": 1e6 * per_step / trials,
        "peak_mib": peak / 2**20,
    }


GRID = {
    "trials (paper size, K=1)": [(4, 6, 1, 2, 3, b) for b in (50, 100, 200, 500, 1000)],
    "targets (16x16, Ms=Ns=4, B=50)": [(16, 16, k, 4, 4, 50) for k in (1, 2, 5, 10, 20)],
    "array size (K=5, Ms=Ns=4, B=20)": [(m, m, 5, 4, 4, 20) for m in (8, 16, 32, 64)],
    "the issue's large runs": [(32, 32, 10, 4, 4, 20), (64, 64, 20, 8, 8, 10)],
}


def growth(xs: list[float], ys: list[float]) -> float:
    return float(np.polyfit(np.log(xs), np.log(ys), 1)[0])


def fitted_growth(rows: dict[str, list[dict[str, Any]]]) -> dict[str, float]:
    """The log-log slope of ms/step against trials B, targets K and stations M*N."""
    t = rows["trials (paper size, K=1)"]
    k = rows["targets (16x16, Ms=Ns=4, B=50)"]
    a = rows["array size (K=5, Ms=Ns=4, B=20)"]
    return {
        "trials B": growth([r["B"] for r in t], [r["ms_per_step"] for r in t]),
        "targets K": growth([r["K"] for r in k], [r["ms_per_step"] for r in k]),
        "stations M*N": growth([r["M"] * r["N"] for r in a], [r["ms_per_step"] for r in a]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description="cost per step against M*N, K and trials")
    parser.add_argument("--steps", type=integer(1), default=10)
    parser.add_argument(
        "--json", type=output_file, default=None, help="also write the rows to this JSON file"
    )
    args = parser.parse_args()
    rows = {}
    for title, grid in GRID.items():
        print(f"\n{title}")
        head = f"{'M x N':>9}{'Ms,Ns':>7}{'K':>4}{'B':>6}  {'solver':<12}{'ms/step':>10}"
        print(f"{head}{'us/trial-step':>15}{'peak MiB':>10}")
        rows[title] = [measure(*config, steps=args.steps) for config in grid]
        for r in rows[title]:
            print(
                f"{r['M']:>4} x {r['N']:<3}{r['Ms']:>3},{r['Ns']:<3}{r['K']:>4}{r['B']:>6}  {r['solver']:<12}"
                f"{r['ms_per_step']:>10.1f}{r['us_per_trial_step']:>15.1f}{r['peak_mib']:>10.1f}"
            )
    print("\nfitted growth of ms/step (log-log slope):")
    for name, slope in fitted_growth(rows).items():
        print(f"  {name}: {slope:.2f}")
    if args.json:
        write_json(args.json, rows, end="")


if __name__ == "__main__":
    main()
