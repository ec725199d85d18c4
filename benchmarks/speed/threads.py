"""Threads inside a task: a run of fewer tasks than cores, with one compute thread per worker
against the threads the harness chooses.

    python -m benchmarks.speed.threads --json docs/results/perf/threads.json

For each fusion it runs ``mimo-radar-bench run`` (MG-CRB-CL, its 500 trials in one task) as a
user does, twice, each into a fresh folder, with ``--workers`` all the cores: with
``--threads 1`` (one worker process of one thread runs the task; the other cores idle), and
without (the harness chooses the threads from the declared costs and says so). From the shards
it reads the task's compute seconds, and checks that both runs wrote the same numbers, bit for
bit. Beside the measured speed-up of the task it gives the one the harness predicted
(:func:`benchmarks.resources.choose_threads`).

It also gives the harness's choice, by the declared costs alone (nothing run), for the v1
claims study's scenario 1 (the strong-scaling study) at 2 to 16 cores, with the shards the
harness plans and with one shard of 500 trials per policy (``--shard-size 500``, or a run
resumed with them).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..outputs import output_file, write_json
from ..settings import integer
from ..study import machine

#: The run measured: one policy's trials in one task.
RUN = ("run", "--scenario", "paper-1-v1", "--policies", "mg-crb-cl", "--trials", "500", "--shard-size", "500")
FUSIONS = ("average", "centralized")


def run_command(arguments: tuple[str, ...], out: Path) -> tuple[float, str]:
    """Wall seconds of ``mimo-radar-bench ARGUMENTS --out OUT`` and what it said on stderr."""
    command = [sys.executable, "-m", "benchmarks", *arguments, "--quiet", "--no-figures", "--out", str(out)]
    start = time.time()
    done = subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    return time.time() - start, done.stderr


def shard_fields(out: Path) -> dict[str, np.ndarray]:
    """The run's one shard: its arrays."""
    (path,) = out.glob("shards/*/shard_*.npz")
    with np.load(path) as shard:
        return {key: shard[key] for key in shard.files}


def predicted(out: Path, workers: int) -> dict[str, float]:
    """The harness's choice for the run's tasks on ``workers`` cores: its threads and its
    predicted speed-up of the run over one thread per worker."""
    from ..harness import RunConfig
    from ..resources import choose_threads, longest_first

    config = RunConfig(**json.loads((out / "config.json").read_text()))
    todo = [(0, policy, shard) for policy, shard in longest_first(config, config.tasks())]
    threads, seconds, one_each = choose_threads([config], todo, workers)
    return {"threads": threads, "speedup": one_each / seconds}


def measure_fusion(fusion: str, workers: int, scratch: Path) -> dict[str, Any]:
    """Both runs of :data:`RUN` under ``fusion``: wall, task seconds, what the harness said."""
    runs: dict[str, dict[str, Any]] = {}
    fields = {}
    for name, extra in (("one thread", ("--threads", "1")), ("chosen", ())):
        out = scratch / f"{fusion}-{name.replace(' ', '-')}"
        arguments = (*RUN, "--fusion", fusion, "--workers", str(workers), *extra)
        wall, said = run_command(arguments, out)
        fields[name] = shard_fields(out)
        runs[name] = {
            "wall_s": wall,
            "task_s": float(fields[name]["wall_s"]),
            "said": [line for line in said.splitlines() if "by the declared costs" in line],
        }
        print(f"  {fusion}, {name}: {wall:.1f} s, the task {runs[name]['task_s']:.1f} s", flush=True)
    same = all(
        np.array_equal(
            fields["one thread"][key],
            fields["chosen"][key],
            equal_nan=fields["chosen"][key].dtype.kind == "f",
        )
        for key in fields["chosen"]
        if key not in ("wall_s", "checksum")  # the compute time, and the shard's checksum over it
    )
    return {
        "fusion": fusion,
        "runs": runs,
        "predicted": predicted(out, workers),
        "measured_task_speedup": runs["one thread"]["task_s"] / runs["chosen"]["task_s"],
        "same_numbers": same,
    }


def plans(cores: tuple[int, ...] = (2, 4, 8, 16)) -> list[dict[str, Any]]:
    """The harness's threads for the claims study's scenario 1 (the paper's six policies, 500
    trials of ``paper-1-v1``, the paper study's parameters) under each fusion on each of
    ``cores``, with its planned shards and with one shard per policy: the threads, the tasks'
    predicted seconds, and those of one thread per worker (the harness's estimates: this
    machine's speed where ``compile`` measured it; the threads chosen do not depend on it)."""
    from mimo_radar_env import VERSIONS

    from ..harness import PAPER_POLICIES, make_config
    from ..resources import choose_threads, longest_first
    from ..settings import paper_study_params

    rows = []
    for fusion in FUSIONS:
        for workers in cores:
            for shards, size in (("planned", None), ("one per policy", 500)):
                options = VERSIONS["v1"].options(fusion=fusion)
                config = make_config("paper-1-v1", PAPER_POLICIES, 500, 1000, shard_size=size,
                                     workers=workers, options=options, agent_params=paper_study_params("v1"),
                                     say=lambda message: None)  # fmt: skip
                todo = [(0, policy, shard) for policy, shard in longest_first(config, config.tasks())]
                threads, seconds, one_each = choose_threads([config], todo, workers)
                rows.append({"fusion": fusion, "workers": workers, "shards": shards,
                             "tasks": len(todo), "threads": threads, "seconds": seconds,
                             "one_thread_seconds": one_each})  # fmt: skip
    return rows


def measure(workers: int) -> dict[str, Any]:
    with tempfile.TemporaryDirectory(prefix="threads-") as scratch:
        rows = [measure_fusion(fusion, workers, Path(scratch)) for fusion in FUSIONS]
    return {
        "run": ["mimo-radar-bench", *RUN],
        "workers": workers,
        "machine": machine(),
        "fusions": rows,
        "plans": plans(),
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--workers", type=integer(1), default=os.cpu_count() or 1, help="cores (default: all)"
    )
    parser.add_argument("--json", type=output_file, default=None)
    args = parser.parse_args(argv)
    print(f"threads inside a task: mimo-radar-bench {' '.join(RUN)}, {args.workers} cores")
    result = measure(args.workers)
    for row in result["fusions"]:
        print(
            f"  {row['fusion']}: {row['predicted']['threads']} threads chosen, the task "
            f"{row['measured_task_speedup']:.2f}x faster (predicted {row['predicted']['speedup']:.2f}x), "
            f"same numbers: {row['same_numbers']}"
        )
    write_json(args.json, result)


if __name__ == "__main__":
    main()
