"""``mimo-radar-bench perf``: the performance figures, each measured against its reference in one run.

Figures (``perf.json``), on v1's paper scenarios, the tracker's position bound included:

* ``tracker_speedup_vs_filterpy``: batched IMM-UKF vs filterpy filters looped in Python,
  same inputs, 500 trials, 6 channels, 3 models (``benchmarks/speed/tracker_speed.py``);
* ``exact_vs_bpso_speedup``, ``bpso_optimality_rate``: the solvers at the paper's size, 500
  trials (``benchmarks/speed/solver_speed.py``);
* ``bpso_1thread_ms_{xor,set}``, ``bpso_optimality_rate_{xor,set}``: the agents' BPSO selection
  in one thread, the paper's swarm, 500 trials, under each position rule, and its optimal
  fraction against ``exact``. The kernel is compared with its earlier versions across commits
  (``python -m benchmarks.speed.across_commits``); ``bpso_speedup_vs_reference_*`` and
  ``bpso_candidate_speedup_vs_reference_*``, in perf.json files measured before commit 0b8e389
  left them (the committed one at 0d8834b), came from copies of the replaced kernel and of a
  float32 candidate then kept in the tree;
* ``env_trial_steps_per_s_{average,centralized}``: the v1 vector env with the tracker and the
  bound, 500 trials, ``paper-1-v1``, random valid actions, and
  ``env_compiled_speedup_{average,centralized}`` over the same env on the numpy twins of its
  numba kernels (``env_numpy_trial_steps_per_s_*``); ``env_trial_steps_per_s_no_tracker``
  (``benchmarks/speed/env_throughput.py``);
* ``claims_v1_average_wall_s``, ``claims_v1_centralized_wall_s``,
  ``claims_v1_both_fusions_wall_s``: the v1 claims study (``mimo-radar-bench claims``, three
  paper scenarios, six policies, MG-CRB-CL with the paper's BPSO, 500 trials) timed whole with
  ``--workers`` processes, under each fusion, and their sum; ``claims_v1_average_exact_solver_wall_s``
  the same study (average fusion) with MG-CRB-CL's exact solver in place of the paper's BPSO:
  BPSO's share removed, the floor for any BPSO kernel; ``tracking_study_wall_s``: the
  tracking study (``mimo-radar-bench tracking``, 200 trials, both fusions) timed whole;
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

``--quick`` measures the same things at small sizes (a few minutes), for CI smoke tests; its
study timings are of a few trials and steps and mark no target.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from pathlib import Path
from typing import Any

from agents.solvers.bpso import BPSO_RULES

from ..cli import Command
from ..harness import output_folder
from ..outputs import folder
from ..precompile import paper_index
from ..settings import default_workers, integer
from . import env_throughput, policy_cost, solver_speed, tracker_speed

SCENARIO = "paper-1-v1"
FULL = {
    "trials": 500,
    "tracker_steps": 20,
    "reference_trials": 10,
    "env_steps": 200,
    "solver_repeats": 5,
    "claims_trials": 500,
    "tracking_trials": 200,
    "study_steps": None,
}
QUICK = {
    "trials": 100,
    "tracker_steps": 5,
    "reference_trials": 2,
    "env_steps": 30,
    "solver_repeats": 2,
    "claims_trials": 6,
    "tracking_trials": 6,
    "study_steps": 20,
}
TARGETS = {
    "tracker_speedup_vs_filterpy": (">=", 300.0),
    # in perf.json files measured while the replaced kernel's copy was in the tree (up to 0b8e389)
    "bpso_speedup_vs_reference_xor": (">=", 5.0),
    "bpso_speedup_vs_reference_set": (">=", 5.0),
    "claims_v1_average_wall_s": ("<=", 120.0),
    "claims_v1_both_fusions_wall_s": ("<=", 240.0),
    "tracking_study_wall_s": ("<=", 300.0),
}


#: MG-CRB-CL with the exact solver instead of the paper's BPSO (cheaper per selection by
#: ``exact_vs_bpso_speedup``): the claims study's time with BPSO's share removed, the floor for any
#: BPSO kernel (up to the variation between two timings of one study).
EXACT_SOLVER = ["--agent-param", "mg-crb-cl.solver=exact", "--agent-param", "mg-crb-cl.solver_params={}"]


def study_wall_s(argv: list[str], trials: int, steps: int | None, workers: int) -> float:
    """Wall seconds of one ``mimo-radar-bench`` study run whole (``argv``: its name and options),
    into a fresh folder, without figures."""
    from ..cli import main as cli_main

    size = ["--trials", str(trials), *([] if steps is None else ["--steps", str(steps)])]
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        code = cli_main([*argv, *size, "--workers", str(workers), "--quiet", "--no-figures", "--out", tmp])
        seconds = time.perf_counter() - start
    if code != 0:
        raise RuntimeError(f"mimo-radar-bench {' '.join(argv)} exited with {code}")
    return seconds


def measure(quick: bool = False, workers: int | None = None) -> dict[str, Any]:
    sizes = QUICK if quick else FULL
    workers = workers or default_workers()
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
    if solver_speed.HAVE_NUMBA:
        index = paper_index(sizes["trials"])
        for rule in BPSO_RULES:
            results.update(solver_speed.one_thread(index, sizes["solver_repeats"], rule))
    steps = sizes["env_steps"]
    for fusion in ("average", "centralized"):
        rate = env_throughput.measure(SCENARIO, sizes["trials"], steps, True, fusion)
        numpy = env_throughput.measure(SCENARIO, sizes["trials"], steps, True, fusion, compiled=False)
        results[f"env_trial_steps_per_s_{fusion}"] = rate
        results[f"env_numpy_trial_steps_per_s_{fusion}"] = numpy
        results[f"env_compiled_speedup_{fusion}"] = rate / numpy
    results["env_trial_steps_per_s_no_tracker"] = env_throughput.measure(
        SCENARIO, sizes["trials"], steps, False
    )
    flat_steps = min(sizes["env_steps"], 20)
    results["flat_vector_trial_steps_per_s"] = env_throughput.flat_measure(
        SCENARIO, sizes["trials"], flat_steps, "vector_entry_point"
    )
    results["flat_sync_trial_steps_per_s"] = env_throughput.flat_measure(
        SCENARIO, sizes["reference_trials"] * 5, flat_steps, "sync"
    )
    results["flat_vector_vs_sync_speedup"] = (
        results["flat_vector_trial_steps_per_s"] / results["flat_sync_trial_steps_per_s"]
    )
    training_steps = 2048 if quick else 8192
    results["ppo_training_steps_per_s_native"] = env_throughput.ppo_training_rate(
        SCENARIO, training_steps, native=True
    )
    results["ppo_training_steps_per_s_sync"] = env_throughput.ppo_training_rate(
        SCENARIO, training_steps, native=False
    )
    results["ppo_training_native_vs_sync_speedup"] = (
        results["ppo_training_steps_per_s_native"] / results["ppo_training_steps_per_s_sync"]
    )
    study_steps = sizes["study_steps"]
    for fusion in ("average", "centralized"):
        results[f"claims_v1_{fusion}_wall_s"] = study_wall_s(
            ["claims", "--fusion", fusion], sizes["claims_trials"], study_steps, workers
        )
    results["claims_v1_both_fusions_wall_s"] = (
        results["claims_v1_average_wall_s"] + results["claims_v1_centralized_wall_s"]
    )
    results["claims_v1_average_exact_solver_wall_s"] = study_wall_s(
        ["claims", *EXACT_SOLVER], sizes["claims_trials"], study_steps, workers
    )
    results["tracking_study_wall_s"] = study_wall_s(
        ["tracking"], sizes["tracking_trials"], study_steps, workers
    )
    start = time.perf_counter()
    layouts = policy_cost.LAYOUTS[:1] if quick else policy_cost.LAYOUTS
    rows = policy_cost.measure((4,), 7, progress=lambda line: None, layouts=layouts)
    results["policy_cost"] = policy_cost.record(rows, (4,), 7, time.perf_counter() - start)
    results.update(policy_cost.ratios(rows))
    results["load_average_1min_after"] = round(os.getloadavg()[0], 2)
    return results


#: The figures of the table: key, unit, what it measures.
FIGURES = (
    ("tracker_speedup_vs_filterpy", "x", "batched IMM-UKF / filterpy loop"),
    ("batched_channel_cycles_per_s", "/s", "IMM-UKF channel-cycles, batched"),
    ("filterpy_channel_cycles_per_s", "/s", "IMM-UKF channel-cycles, filterpy"),
    ("exact_ms", "ms", "exact solver per batched selection (500 trials)"),
    ("bpso_ms", "ms", "BPSO per batched selection (500 trials, all threads)"),
    ("exact_vs_bpso_speedup", "x", "exact / BPSO"),
    ("bpso_optimality_rate", "", "BPSO optimal fraction (rule xor)"),
    ("bpso_1thread_ms_xor", "ms", "BPSO, one thread, rule xor"),
    ("bpso_reference_1thread_ms_xor", "ms", "the selection it replaced, one thread, rule xor"),
    ("bpso_speedup_vs_reference_xor", "x", "BPSO / the selection it replaced, rule xor"),
    ("bpso_1thread_ms_set", "ms", "BPSO, one thread, rule set (v1's)"),
    ("bpso_reference_1thread_ms_set", "ms", "the selection it replaced, one thread, rule set"),
    ("bpso_speedup_vs_reference_set", "x", "BPSO / the selection it replaced, rule set"),
    ("bpso_candidate_speedup_vs_reference_xor", "x", "float32 SIMD candidate / the selection replaced, xor"),
    ("bpso_candidate_speedup_vs_reference_set", "x", "float32 SIMD candidate / the selection replaced, set"),
    ("env_trial_steps_per_s_average", "/s", "v1 env, tracker and bound, average fusion"),
    ("env_numpy_trial_steps_per_s_average", "/s", "the same on the numpy paths"),
    ("env_compiled_speedup_average", "x", "compiled / numpy paths, average fusion"),
    ("env_trial_steps_per_s_centralized", "/s", "v1 env, tracker and bound, centralised fusion"),
    ("env_numpy_trial_steps_per_s_centralized", "/s", "the same on the numpy paths"),
    ("env_compiled_speedup_centralized", "x", "compiled / numpy paths, centralised fusion"),
    ("env_trial_steps_per_s_no_tracker", "/s", "v1 env, tracking=False"),
    ("claims_v1_average_wall_s", "s", "v1 claims study, 500 trials, average fusion, whole"),
    ("claims_v1_centralized_wall_s", "s", "v1 claims study, 500 trials, centralised fusion, whole"),
    ("claims_v1_both_fusions_wall_s", "s", "v1 claims study, both fusions"),
    (
        "claims_v1_average_exact_solver_wall_s",
        "s",
        "the same, average fusion, MG-CRB-CL with the exact solver",
    ),
    ("tracking_study_wall_s", "s", "tracking study, 200 trials, both fusions, whole"),
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
    rows = tuple(f for f in FIGURES + POLICY_FIGURES if f[0] in results)
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
    out = output_folder(out)
    results = measure(quick, workers)
    (out / "policy_cost.json").write_text(json.dumps(results.pop("policy_cost"), indent=1) + "\n")
    (out / "perf.json").write_text(json.dumps(results, indent=2))
    print(format_table(results))
    return results


class Perf(Command):
    name = "perf"
    description = (
        "Measure the tracker against filterpy, BPSO against the kernel it replaced, the v1 vector env "
        "against its numpy paths, and the v1 claims and tracking studies timed whole; write "
        "DIR/perf.json and print a table."
    )

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("--out", required=True, type=folder, help="output directory for perf.json")
        parser.add_argument("--quick", action="store_true", help="small sizes, a few minutes (CI smoke test)")
        parser.add_argument(
            "--workers",
            type=integer(1),
            default=None,
            help="worker processes for the studies (default: cores)",
        )

    def main(self) -> int:
        main(self.args.out, quick=self.args.quick, workers=self.args.workers)
        return 0
