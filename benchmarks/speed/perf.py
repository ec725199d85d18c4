"""``mimo-radar-bench perf``: the performance figures, each measured against its reference in one run.

Figures (``perf.json``):

* ``tracker_speedup_vs_filterpy``: batched IMM-UKF vs filterpy filters looped in Python,
  same inputs, 500 trials, 6 channels, 3 models (``benchmarks/speed/tracker_speed.py``);
* ``exact_vs_bpso_speedup``, ``bpso_optimality_rate``: the solvers at the paper's size, 500
  trials (``benchmarks/speed/solver_speed.py``);
* ``env_trial_steps_per_s``: vector env with tracker, 500 trials, ``paper-1``, random valid
  actions (``benchmarks/speed/env_throughput.py``);
* ``repro_wall_s_exact``: all three paper scenarios, six policies, 500 trials, T = 1000,
  every index policy with the exact solver, through the harness;
* ``repro_wall_s_paper``: the same with MG-CRB-CL using BPSO, as in the paper;
* ``flat_vector_trial_steps_per_s``, ``flat_sync_trial_steps_per_s``,
  ``flat_vector_vs_sync_speedup``: ``MimoRadarSelectFlat-v1`` (paper-1-v1, random Discrete
  actions) through its native vector entry point (``trials`` trials) against Gymnasium's sync
  vector env of single Flat envs (``5 x reference_trials`` of them), in trial-steps per second;
* ``ppo_training_steps_per_s_native``, ``ppo_training_steps_per_s_sync``,
  ``ppo_training_native_vs_sync_speedup``: SB3 PPO training (the shipped hyperparameters, 8
  envs, one thread) through ``NativeVecEnv`` against SB3's ``DummyVecEnv`` of single Flat envs,
  in environment steps per second (8,192 steps each; ``--quick``: 2,048);
* ``policy_*``: every policy's time per trial-step and peak memory per trial at 4 x 6, 16 x 16
  and 64 x 64 stations, K = 1 and 5, against what it declares (``policy_cost.json`` beside
  ``perf.json``; ``benchmarks/speed/policy_cost.py``; ``--quick``: 4 x 6 only).

``--quick`` measures the same things at small sizes (under a minute), for CI smoke tests.
"""

from __future__ import annotations

import json
import os
import platform
import tempfile
import time
from pathlib import Path
from typing import Any

from ..harness import PAPER_POLICIES, make_config, run
from ..studies.settings import default_workers
from . import env_throughput, policy_cost, solver_speed, tracker_speed

FULL = {
    "trials": 500,
    "tracker_steps": 20,
    "reference_trials": 10,
    "env_steps": 200,
    "repro_trials": 500,
    "repro_steps": None,
    "solver_repeats": 5,
}
QUICK = {
    "trials": 100,
    "tracker_steps": 5,
    "reference_trials": 2,
    "env_steps": 30,
    "repro_trials": 20,
    "repro_steps": 50,
    "solver_repeats": 2,
}
TARGETS = {
    "tracker_speedup_vs_filterpy": (">=", 300.0),
    "repro_wall_s_exact": ("<=", 120.0),
    "repro_wall_s_paper": ("<=", 600.0),
}


def repro_wall_s(solver: str, trials: int, steps: int | None, workers: int, shard_size: int) -> float:
    """Wall seconds of the paper's study (3 scenarios x 6 policies) through the harness."""
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for scenario in ("paper-1", "paper-2", "paper-3"):
            params = {"mg-crb-cl": {"solver": solver}}
            config = make_config(
                scenario, list(PAPER_POLICIES), trials, steps, shard_size=shard_size, agent_params=params
            )
            run(config, Path(tmp) / scenario, workers=workers, progress=False)
    return time.perf_counter() - start


def measure(quick: bool = False, workers: int | None = None) -> dict[str, Any]:
    sizes = QUICK if quick else FULL
    workers = workers or default_workers()
    trials = sizes["repro_trials"]
    shard_size = max(1, -(-trials // workers))  # one shard per worker and policy: the largest batches
    results: dict[str, Any] = {
        "quick": quick,
        "workers": workers,
        "machine": platform.machine(),
        "cores": os.cpu_count(),
        "load_average_1min_before": round(os.getloadavg()[0], 2),
    }
    tracker = tracker_speed.measure(sizes["trials"], sizes["tracker_steps"], sizes["reference_trials"])
    results.update(tracker)
    solvers = solver_speed.measure(sizes["trials"], sizes["solver_repeats"])
    results.update(
        {k: solvers[k] for k in ("exact_ms", "bpso_ms", "exact_vs_bpso_speedup", "bpso_optimality_rate")}
    )
    results["env_trial_steps_per_s"] = env_throughput.measure(
        "paper-1", sizes["trials"], sizes["env_steps"], tracking=True
    )
    results["env_trial_steps_per_s_no_tracker"] = env_throughput.measure(
        "paper-1", sizes["trials"], sizes["env_steps"], tracking=False
    )
    flat_steps = min(sizes["env_steps"], 20)
    results["flat_vector_trial_steps_per_s"] = env_throughput.flat_measure(
        "paper-1-v1", sizes["trials"], flat_steps, "vector_entry_point"
    )
    results["flat_sync_trial_steps_per_s"] = env_throughput.flat_measure(
        "paper-1-v1", sizes["reference_trials"] * 5, flat_steps, "sync"
    )
    results["flat_vector_vs_sync_speedup"] = (
        results["flat_vector_trial_steps_per_s"] / results["flat_sync_trial_steps_per_s"]
    )
    training_steps = 2048 if quick else 8192
    results["ppo_training_steps_per_s_native"] = env_throughput.ppo_training_rate(
        "paper-1-v1", training_steps, native=True
    )
    results["ppo_training_steps_per_s_sync"] = env_throughput.ppo_training_rate(
        "paper-1-v1", training_steps, native=False
    )
    results["ppo_training_native_vs_sync_speedup"] = (
        results["ppo_training_steps_per_s_native"] / results["ppo_training_steps_per_s_sync"]
    )
    results["repro_wall_s_exact"] = repro_wall_s("exact", trials, sizes["repro_steps"], workers, shard_size)
    results["repro_wall_s_paper"] = repro_wall_s("bpso", trials, sizes["repro_steps"], workers, shard_size)
    start = time.perf_counter()
    layouts = policy_cost.LAYOUTS[:1] if quick else policy_cost.LAYOUTS
    rows = policy_cost.measure(4, 7, progress=lambda line: None, layouts=layouts)
    results["policy_cost"] = policy_cost.record(rows, 4, 7, time.perf_counter() - start)
    results.update(policy_cost.ratios(rows))
    results["load_average_1min_after"] = round(os.getloadavg()[0], 2)
    return results


#: The figures of the table: key, unit, what it measures.
FIGURES = (
    ("tracker_speedup_vs_filterpy", "x", "batched IMM-UKF / filterpy loop"),
    ("batched_channel_cycles_per_s", "/s", "IMM-UKF channel-cycles, batched"),
    ("filterpy_channel_cycles_per_s", "/s", "IMM-UKF channel-cycles, filterpy"),
    ("exact_ms", "ms", "exact solver per batched selection"),
    ("bpso_ms", "ms", "BPSO per batched selection"),
    ("exact_vs_bpso_speedup", "x", "exact / BPSO"),
    ("bpso_optimality_rate", "", "BPSO optimal fraction"),
    ("env_trial_steps_per_s", "/s", "vector env with tracker"),
    ("env_trial_steps_per_s_no_tracker", "/s", "vector env, tracking=False"),
    ("repro_wall_s_exact", "s", "paper study, exact solvers"),
    ("repro_wall_s_paper", "s", "paper study, MG-CRB-CL with BPSO"),
)
#: Figures measured since the committed perf.json (shown by ``perf``; in the docs' table once
#: perf.json is re-measured).
NEW_FIGURES = (
    ("flat_vector_trial_steps_per_s", "/s", "Flat-v1, native vector entry point"),
    ("flat_sync_trial_steps_per_s", "/s", "Flat-v1, sync vector env of single envs"),
    ("flat_vector_vs_sync_speedup", "x", "Flat-v1 native vector / sync"),
    ("ppo_training_steps_per_s_native", "/s", "PPO training env steps, native vector env"),
    ("ppo_training_steps_per_s_sync", "/s", "PPO training env steps, SB3 DummyVecEnv"),
    ("ppo_training_native_vs_sync_speedup", "x", "PPO training, native / DummyVecEnv"),
)
#: The policies' costs against their declarations (their table in the docs is generated from
#: ``policy_cost.json``).
POLICY_FIGURES = (
    ("policy_memory_measured_over_declared_max", "", "policies: largest measured / declared memory"),
    ("policy_time_measured_over_estimated_min", "", "policies: least measured / estimated time"),
    ("policy_time_measured_over_estimated_max", "", "policies: largest measured / estimated time"),
)


def format_value(value: float) -> str:
    """Three decimals below 10, whole numbers with thousands separators above."""
    return f"{value:,.3f}" if value < 10 else f"{value:,.0f}"


def target_met(key: str, value: float) -> bool | None:
    """Whether ``value`` meets the figure's target (None: the figure has none)."""
    if key not in TARGETS:
        return None
    op, bound = TARGETS[key]
    return value >= bound if op == ">=" else value <= bound


def format_table(results: dict[str, Any]) -> str:
    rows = FIGURES + tuple(f for f in NEW_FIGURES + POLICY_FIGURES if f[0] in results)
    lines = [f"{'figure':<44}{'value':>14}  {'target':<10}what", "-" * 100]
    for key, unit, what in rows:
        value = results[key]
        text = format_value(value)
        target = ""
        if key in TARGETS and not results.get("quick"):
            op, bound = TARGETS[key]
            target = f"{op}{bound:g} {'ok' if target_met(key, value) else 'MISSED'}"
        lines.append(f"{key:<44}{text + ' ' + unit:>14}  {target:<10}{what}")
    return "\n".join(lines)


def main(out: str | Path, quick: bool = False, workers: int | None = None) -> dict[str, Any]:
    results = measure(quick, workers)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "policy_cost.json").write_text(json.dumps(results.pop("policy_cost"), indent=1) + "\n")
    (out / "perf.json").write_text(json.dumps(results, indent=2))
    print(format_table(results))
    return results
