"""The README's quickstart, first run against second: how much of a first run is compilation.

Run: ``python -m benchmarks.speed.first_run [--repeats 3] [--json PATH]``
(``docs/results/perf/first_run.json``, which docs/performance.md's sentence is generated from).

A fresh install has no numba cache. Each repeat points numba at a new, empty cache folder
(``NUMBA_CACHE_DIR``), then runs the quickstart (``mimo-radar-bench paper --scenario 1 --trials
20``, figures included) twice in new interpreters, each into a new output folder: the first run
compiles the kernels it calls and caches them, the second loads them. The figure is each
repeat's first-run time over its second's (the performance issue's target: at most 1.5).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

#: The largest first-run / second-run ratio the performance issue accepts.
TARGET = 1.5
#: The README's quickstart, less ``--out``.
QUICKSTART = ("paper", "--scenario", "1", "--trials", "20", "--quiet")


def timed_run(out: Path, cache: Path, args: tuple[str, ...] = QUICKSTART) -> float:
    """Wall time (s) of one ``mimo-radar-bench`` run in a new interpreter with numba's cache in
    ``cache``."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "benchmarks", *args, "--out", str(out)],
        env=env,
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    return time.perf_counter() - start


def measure(repeats: int = 3, args: tuple[str, ...] = QUICKSTART) -> dict[str, Any]:
    """Each repeat's first and second run (s) from an empty cache, and their ratios."""
    pairs = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as folder:
            root = Path(folder)
            first = timed_run(root / "first", root / "cache", args)
            second = timed_run(root / "second", root / "cache", args)
        pairs.append({"first_s": first, "second_s": second, "ratio": first / second})
    ratios = [p["ratio"] for p in pairs]
    return {
        "command": ["mimo-radar-bench", *args, "--out", "DIR"],
        "repeats": pairs,
        "median_ratio": statistics.median(ratios),
        "max_ratio": max(ratios),
        "machine": {
            "platform": platform.platform(),
            "cores": os.cpu_count(),
            "python": platform.python_version(),
            "load_average_1min": round(os.getloadavg()[0], 2),
        },
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="pairs of runs, each from an empty cache")
    parser.add_argument("--json", default=None, help="also write the figures and the machine to this file")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error(f"--repeats must be at least 1, got {args.repeats}")
    result = measure(args.repeats)
    for i, pair in enumerate(result["repeats"], start=1):
        print(
            f"repeat {i}: first run {pair['first_s']:.1f} s, second {pair['second_s']:.1f} s, "
            f"ratio {pair['ratio']:.2f}"
        )
    print(
        f"first / second: median {result['median_ratio']:.2f}, largest {result['max_ratio']:.2f} "
        f"(target <= {TARGET:g})"
    )
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
