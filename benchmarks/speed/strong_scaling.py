"""Strong scaling of a study on one machine: its wall time by worker count, where the time goes,
and a model of the measured parts that predicts other worker counts.

    python -m benchmarks.speed.strong_scaling --workers 1,2 --predict 4,8,16 \\
        --json docs/results/perf/strong-scaling.json

Each measurement runs ``mimo-radar-bench claims ... --workers W`` as a user does (a fresh
process, the default shards for W workers: sized by cost) into a fresh folder, and reads the shards it wrote
(``--repeats N`` measures every count N times, the counts' order reversed every other repeat,
and gives each figure as the mean of the repeats, the wall time and the efficiency with a 95 %
t interval, the efficiency paired by repeat; its output ends with the last count's figures as one
JSON line, for ``benchmarks.speed.across_commits --key``):
each task's compute seconds (``wall_s``), its trials, and when its file was written. The
``W x wall`` worker-seconds of a run split into

* **work in the tasks**: the tasks' compute seconds, of which **fixed per task** is the time to
  build the agent and the env and take the first step (probed: one trial, one step, per policy);
* **idle at the tail**: from the last task a worker finished to the run's last (the last ``W``
  shard files written, one per worker);
* **outside the tasks**: the rest: starting the command and its workers, loading the compiled
  kernels in each, writing the shards and the report.

The cost of **smaller batches** is the per-trial-step cost of a task at W's shard size against
the largest shard measured. The model predicts a worker count from one core's view, under two
schedules: ``"uniform"`` (every policy's trials in as many shards, the harness's default before
the cost-aware one) and ``"by cost"`` (the harness's shard sizes for W workers). Each policy's
task is probed at the schedule's shard size on one compute thread (as a worker of a
several-worker run has), the tasks are queued in the harness's order (the longest declared cost
first, run after run) on W workers (list scheduling), and the time outside the tasks is the one
measured at the most workers. It assumes a core as fast as this
machine's when all are busy (no memory-bandwidth contention): a larger machine checks that.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..outputs import output_file, write_json
from ..resources import makespan
from ..settings import integer
from ..study import machine
from . import t_interval

#: The study measured by default: the v1 claims study's scenario 1, whole episodes.
STUDY = ("claims", "--scenarios", "1", "--trials", "500")


@dataclass(frozen=True)
class Task:
    run: str
    policy: str
    shard: int
    trials: int
    steps: int
    seconds: float
    finished: float  # seconds after the command started


def run_study(
    study: tuple[str, ...], workers: int, out: Path, python: tuple[str, ...] = ("-m", "benchmarks")
) -> float:
    """Wall seconds of the study's command with ``workers`` workers into ``out`` (``python``: what
    the interpreter runs, the study's arguments after it)."""
    command = [sys.executable, *python, *study, "--quiet", "--no-figures"]
    start = time.time()
    subprocess.run([*command, "--workers", str(workers), "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL)  # fmt: skip
    return time.time() - start


def read_tasks(out: Path, started: float) -> list[Task]:
    """Every shard a study wrote under ``out``: its run, policy, trials, compute seconds and when
    it was written."""
    tasks = []
    for config_file in sorted(out.glob("*/config.json")):
        steps = json.loads(config_file.read_text())["steps"]
        for path in sorted(config_file.parent.glob("shards/*/shard_*.npz")):
            with np.load(path) as shard:
                trials, seconds = len(shard["trial_expected"]), float(shard["wall_s"])
            tasks.append(Task(config_file.parent.name, path.parent.name, int(path.stem.split("_")[1]),
                              trials, steps, seconds, path.stat().st_mtime - started))  # fmt: skip
    return tasks


def serial_parts(wall: float, tasks: list[Task]) -> dict[str, float]:
    """The wall seconds of a run before its first task started and after its last ended: the
    command's serial parts (imports, the run's checks and estimate, the workers' start; the
    report)."""
    return {
        "before_first_task_s": min(t.finished - t.seconds for t in tasks),
        "after_last_task_s": wall - max(t.finished for t in tasks),
    }


def breakdown(
    wall: float, workers: int, tasks: list[Task], fixed_per_task: dict[str, float]
) -> dict[str, float]:
    """The ``workers x wall`` worker-seconds of a run by where they went (module docstring)."""
    work = sum(t.seconds for t in tasks)
    fixed = sum(fixed_per_task.get(t.policy, 0.0) for t in tasks)
    finishes = sorted(t.finished for t in tasks)
    end = finishes[-1]
    tail = sum(end - f for f in finishes[-workers:])
    return {
        "worker_seconds": workers * wall,
        "task_steps_s": work - fixed,
        "task_fixed_s": fixed,
        "tail_idle_s": tail,
        "outside_tasks_s": workers * wall - work - tail,
    }


def _with_sizes(payload: dict[str, Any], sizes: int | dict[str, int] | None) -> dict[str, Any]:
    """A run's configuration with its shard sizes replaced: every policy's (an int), or each
    policy's (a mapping)."""
    if sizes is None:
        return payload
    if isinstance(sizes, int):
        return {**payload, "shard_size": sizes, "shard_sizes": {}}
    return {**payload, "shard_size": max(sizes.values()), "shard_sizes": dict(sizes)}


def queue_order(out: Path, sizes: int | dict[str, int] | None = None) -> list[tuple[str, str, int, int]]:
    """The harness's order of a study's tasks (run after run, the longest declared cost first),
    as (run, policy, shard, trials), with the runs' shard sizes replaced by ``sizes``."""
    from ..harness import RunConfig
    from ..resources import longest_first

    order = []
    for config_file in sorted(out.glob("*/config.json")):
        config = RunConfig(**_with_sizes(json.loads(config_file.read_text()), sizes))
        order += [
            (config_file.parent.name, p, s, len(config.shard_trials(p, s)))
            for p, s in longest_first(config, config.tasks())
        ]
    return order


def probe(out: Path, sizes: int | dict[str, int], steps: int | None = None) -> dict[str, dict[str, float]]:
    """Each policy's first task with the shard sizes ``sizes`` (``steps`` steps, default the
    run's) run alone on one core in this process, on one compute thread as in a worker of a
    several-worker run: its seconds by run and policy."""
    from mimo_radar_env.core.compiled import with_threads

    from ..harness import run_task

    seconds: dict[str, dict[str, float]] = {}
    for config_file in sorted(out.glob("*/config.json")):
        payload = _with_sizes(json.loads(config_file.read_text()), sizes)
        if steps is not None:
            payload["steps"] = steps
        run = config_file.parent.name
        with with_threads(1):
            seconds[run] = {p: float(run_task(payload, p, 0)["wall_s"]) for p in payload["policies"]}
    return seconds


def predict(
    out: Path, workers: int, trials: int, overhead: float, probes: dict[int, dict[str, dict[str, float]]]
) -> dict[str, Any]:
    """The model's wall time for ``workers`` workers (module docstring), under each schedule:
    ``"uniform"``, every policy's trials in the same number of shards (:func:`auto_shard_size`,
    the harness's default before the cost-aware one), and ``"by cost"``, the harness's shard
    sizes (:func:`benchmarks.resources.planned_shard_sizes`)."""
    from ..harness import RunConfig
    from ..resources import auto_shard_size, planned_shard_sizes

    payload = json.loads(next(out.glob("*/config.json")).read_text())
    policies = payload["policies"]
    schedules = {
        "uniform": dict.fromkeys(policies, auto_shard_size(trials, workers, len(policies))),
        "by cost": planned_shard_sizes(RunConfig(**payload), workers),
    }
    rows = []
    for schedule, sizes in schedules.items():
        key = tuple(sorted(sizes.items()))
        if key not in probes:
            probes[key] = probe(out, sizes)
        durations = [
            probes[key][run][policy] * n / sizes[policy] for run, policy, _, n in queue_order(out, sizes)
        ]
        span = makespan(durations, workers)
        rows.append({"workers": workers, "schedule": schedule, "shard_size": max(sizes.values()),
                     "shard_sizes": sizes, "tasks": len(durations), "task_seconds": sum(durations),
                     "makespan_s": span, "wall_s": overhead + span})  # fmt: skip
    return rows


def measure(
    study: tuple[str, ...],
    counts: list[int],
    predictions: list[int],
    model_from: int | None = None,
    measured_only: Callable[[dict[str, Any]], None] | None = None,
    repeats: int = 1,
    model: bool = True,
) -> dict[str, Any]:
    """The measured runs at ``counts`` workers (``repeats`` times each, alternately) and the
    model's predictions at ``predictions``, from the runs at ``model_from`` workers (default the
    most measured): their time outside the tasks. ``measured_only`` is given the result without
    the model as soon as the runs are measured (the model's probes take minutes: a run stopped
    then keeps its measurements); without ``model`` that is the result."""
    with tempfile.TemporaryDirectory(prefix="strong-scaling-") as scratch:
        return _measure(study, counts, predictions, model_from, Path(scratch), measured_only, repeats, model)


def _measure(
    study: tuple[str, ...],
    counts: list[int],
    predictions: list[int],
    model_from: int | None,
    scratch: Path,
    measured_only: Callable[[dict[str, Any]], None] | None = None,
    repeats: int = 1,
    model: bool = True,
) -> dict[str, Any]:
    trials = int(study[study.index("--trials") + 1])
    runs: dict[int, list[dict[str, Any]]] = {w: [] for w in counts}
    folders = {}
    for repeat in range(repeats):
        for workers in counts if repeat % 2 == 0 else counts[::-1]:
            out = scratch / f"w{workers}-{repeat}"
            started = time.time()
            wall = run_study(study, workers, out)
            tasks = read_tasks(out, started)
            runs[workers].append({"wall_s": wall, "tasks": tasks})
            folders[workers] = out
            print(f"  {workers:>3} workers: {wall:7.1f} s, {len(tasks)} tasks", flush=True)
    reference = folders[counts[0]]
    probe(reference, 1, steps=1)  # warm-up: the compiled kernels load in this process
    fixed = {p: s for run in probe(reference, 1, steps=1).values() for p, s in run.items()}
    probes: dict[tuple, dict[str, dict[str, float]]] = {}
    base = counts[0]
    rows = [
        _row(workers, runs[workers], [base * r["wall_s"] for r in runs[base]], fixed) for workers in counts
    ]
    result = {
        "study": ["mimo-radar-bench", *study],
        "machine": machine(),
        "repeats": repeats,
        "measured": rows,
        "fixed_per_task_s": fixed,
    }
    if measured_only is not None:
        measured_only({**result, "model": []})
    if not model:
        return {**result, "model": []}
    source = model_from or max(counts)
    order = queue_order(folders[source])
    overheads = []
    for run in runs[source]:
        by_task = {(t.run, t.policy, t.shard): t.seconds for t in run["tasks"]}
        overheads.append(run["wall_s"] - makespan([by_task[r, p, s] for r, p, s, _ in order], source))
    overhead = float(np.mean(overheads))
    model = [
        row
        for w in sorted({source, *predictions})
        for row in predict(folders[source], w, trials, overhead, probes)
    ]
    return result | {"model_from_workers": source, "outside_tasks_s": overhead, "model": model}


def _row(
    workers: int, runs: list[dict[str, Any]], base_seconds: list[float], fixed: dict[str, float]
) -> dict[str, Any]:
    """One worker count's measured row: each figure the mean over its runs, and with two runs or
    more each run's wall time and 95 % t intervals of the mean wall time and of the efficiency
    against the base count's runs (``base_seconds``: workers x wall), paired by repeat."""
    walls = np.array([r["wall_s"] for r in runs])
    efficiencies = np.array(base_seconds) / (workers * walls)
    tasks = [t for r in runs for t in r["tasks"]]
    per_step = sum(t.seconds - fixed[t.policy] for t in tasks) / sum(t.trials * t.steps for t in tasks)
    parts = [breakdown(r["wall_s"], workers, r["tasks"], fixed) for r in runs]
    serial = [serial_parts(r["wall_s"], r["tasks"]) for r in runs]
    before = [s["before_first_task_s"] for s in serial]
    after = [s["after_last_task_s"] for s in serial]
    row = {
        "workers": workers, "schedule": "by cost", "wall_s": float(walls.mean()),
        "tasks": len(runs[0]["tasks"]), "shard_trials": max(t.trials for t in tasks),
        "speedup": float(np.mean(np.array(base_seconds) / walls)),
        "efficiency": float(efficiencies.mean()),
        "us_per_trial_step_in_tasks": 1e6 * per_step,
        "breakdown": {k: float(np.mean([p[k] for p in parts])) for k in parts[0]},
        "before_first_task_s": float(np.mean(before)), "after_last_task_s": float(np.mean(after)),
    }  # fmt: skip
    if len(runs) > 1:
        row |= {
            "wall_s_each": walls.tolist(),
            "wall_s_ci": list(t_interval(walls)),
            "efficiency_ci": list(t_interval(efficiencies)),
            "after_last_task_s_each": after,
        }
    return row


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", default="1,2", help="worker counts measured, comma-separated")
    parser.add_argument("--predict", default="4,8,16", help="worker counts the model predicts")
    parser.add_argument(
        "--model-from", type=integer(1), help="count the model starts from (default: the most)"
    )
    parser.add_argument(
        "--study", default=" ".join(STUDY), help="the study's arguments (default %(default)r)"
    )
    parser.add_argument(
        "--repeats", type=integer(1), default=1, help="runs of each worker count, alternately (default 1)"
    )
    parser.add_argument(
        "--no-model", action="store_true", help="measure only (the model's probes take minutes)"
    )
    parser.add_argument("--json", type=output_file, default=None)
    args = parser.parse_args(argv)
    counts = [int(w) for w in args.workers.split(",")]
    predictions = [int(w) for w in args.predict.split(",") if w]
    study = tuple(args.study.split())
    if "--trials" not in study:
        parser.error("--study must give --trials")
    print(f"strong scaling of mimo-radar-bench {' '.join(study)}, {os.cpu_count()} cores")
    if args.model_from is not None and args.model_from not in counts:
        parser.error(f"--model-from must be one of the measured counts {counts}")
    result = measure(
        study,
        counts,
        predictions,
        args.model_from,
        lambda partial: write_json(args.json, partial),
        args.repeats,
        model=not args.no_model,
    )
    for row in result["measured"]:
        wall, efficiency = row["wall_s"], row["efficiency"]
        print(f"  measured {row['workers']:>3} workers: {wall:7.1f} s, efficiency {efficiency:.2f}")
    for row in result["model"]:
        print(f"  model    {row['workers']:>3} workers: {row['wall_s']:7.1f} s")
    write_json(args.json, result)
    # the last count measured, as one JSON line (for benchmarks.speed.across_commits --key)
    last = result["measured"][-1]
    keys = ("workers", "wall_s", "before_first_task_s", "after_last_task_s", "efficiency")
    print(json.dumps({key: last[key] for key in keys}))


if __name__ == "__main__":
    main()
