"""The Ray backend against the local one: a study's wall time at the same number of workers, on
a Ray cluster started beforehand on this machine.

    python -m benchmarks.speed.ray_cluster --json docs/results/perf/ray.json

It starts a Ray cluster on this machine (``ray start --head --num-cpus W``), runs the study
(default: the strong-scaling study, the v1 claims study's scenario 1) with ``--workers W``
alternately on the local backend and on the cluster (``--backend ray --address auto``),
``--repeats`` times each, every run a fresh command into a fresh folder, then stops the
cluster. It gives each run's wall time and checks that every run wrote the same numbers as the
first: every shard's arrays, bit for bit (the compute time and the checksum over it aside).
"""

from __future__ import annotations

import argparse
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
from .strong_scaling import STUDY, read_tasks, run_study, serial_parts

BACKENDS = {"local": (), "ray": ("--backend", "ray", "--address", "auto")}


def shard_arrays(out: Path) -> dict[str, np.ndarray]:
    """Every shard array a study wrote under ``out`` by ``run/policy/shard/field``, less its compute
    time and the checksum over it."""
    arrays = {}
    for path in sorted(out.glob("*/shards/*/shard_*.npz")):
        with np.load(path) as shard:
            for key in shard.files:
                if key not in ("wall_s", "checksum"):
                    arrays[f"{path.relative_to(out)}/{key}"] = shard[key]
    return arrays


def same(one: dict[str, np.ndarray], two: dict[str, np.ndarray]) -> bool:
    return one.keys() == two.keys() and all(
        np.array_equal(one[k], two[k], equal_nan=one[k].dtype.kind == "f") for k in one
    )


def ray(*arguments: str, check: bool = True) -> None:
    """``ray ARGUMENTS`` (the cluster's start and stop), its output dropped."""
    command = [sys.executable, "-m", "ray.scripts.scripts", *arguments]
    subprocess.run(command, check=check, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


#: A variant of a study's command: the interpreter's arguments before the study's, and extra ones.
Variant = tuple[tuple[str, ...], tuple[str, ...]]
CLI: tuple[str, ...] = ("-m", "benchmarks")


def alternate(
    study: tuple[str, ...], workers: int, repeats: int, variants: dict[str, Variant], key: str
) -> list[dict[str, Any]]:
    """The study run ``repeats`` times in each of ``variants`` (a name: the interpreter's
    arguments before the study's and the study's extra arguments), alternately, the order
    reversed every other repeat (so that a drift of the machine's speed falls on both), every run
    a fresh command into a fresh folder: per run, its variant (under ``key``), repeat, wall
    seconds, whether it wrote the numbers of the first run, and the wall seconds before its
    first task started and after its last ended (from its shards, as
    :mod:`.strong_scaling` reads them: the command's serial parts)."""
    runs: list[dict[str, Any]] = []
    reference: dict[str, np.ndarray] | None = None
    with tempfile.TemporaryDirectory(prefix="alternate-") as scratch:
        for repeat in range(repeats):
            order = list(variants.items())
            for name, (python, extra) in order if repeat % 2 == 0 else order[::-1]:
                out = Path(scratch) / f"{name.replace(' ', '-')}-{repeat}"
                started = time.time()
                wall = run_study((*study, *extra), workers, out, python)
                arrays = shard_arrays(out)
                reference = arrays if reference is None else reference
                run = {key: name, "repeat": repeat, "wall_s": wall, "same_numbers": same(reference, arrays)}
                tasks = read_tasks(out, started)
                if tasks:
                    run |= serial_parts(wall, tasks)
                runs.append(run)
                print(f"  {name:>10}, repeat {repeat}: {wall:.1f} s", flush=True)
    return runs


def measure(study: tuple[str, ...], workers: int, repeats: int) -> dict[str, Any]:
    ray("start", "--head", f"--num-cpus={workers}", "--include-dashboard=false")
    try:
        variants = {backend: (CLI, extra) for backend, extra in BACKENDS.items()}
        runs = alternate(study, workers, repeats, variants, "backend")
    finally:
        ray("stop", check=False)
    return {
        "study": ["mimo-radar-bench", *study],
        "workers": workers,
        "machine": machine(),
        "runs": runs,
    }


def alternating_arguments(doc: str, repeats: int, argv: list[str] | None) -> argparse.Namespace:
    """The command line of a benchmark of alternating runs (:func:`alternate`): ``--workers``,
    ``--repeats`` (default ``repeats``), ``--study`` and ``--json``."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument(
        "--workers", type=integer(1), default=os.cpu_count() or 1, help="workers (default: cores)"
    )
    parser.add_argument(
        "--repeats", type=integer(1), default=repeats, help="runs of each variant, alternating"
    )
    parser.add_argument(
        "--study", default=" ".join(STUDY), help="the study's arguments (default %(default)r)"
    )
    parser.add_argument("--json", type=output_file, default=None)
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    args = alternating_arguments(__doc__, 2, argv)
    print(f"local against Ray: mimo-radar-bench {args.study}, {args.workers} workers")
    result = measure(tuple(args.study.split()), args.workers, args.repeats)
    for backend in BACKENDS:
        walls = [r["wall_s"] for r in result["runs"] if r["backend"] == backend]
        print(f"  {backend}: {', '.join(f'{w:.1f}' for w in walls)} s")
    print(f"  same numbers in every run: {all(r['same_numbers'] for r in result['runs'])}")
    write_json(args.json, result)


if __name__ == "__main__":
    main()
