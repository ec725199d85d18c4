"""The README's quickstart, first run against second: how much of a first run is compilation.

Run: ``python -m benchmarks.speed.first_run [--repeats 3] [--json PATH]``
(``docs/results/perf/first_run.json``, which docs/performance.md's sentence is generated from).

A fresh install has no numba cache. Each repeat times the quickstart (``mimo-radar-bench paper
--scenario 1 --trials 20``, figures included) in new interpreters, each into a new output
folder, along the two paths from an install:

- the README's: ``mimo-radar-bench compile`` into a new, empty cache folder
  (``NUMBA_CACHE_DIR``), then the quickstart's first run, which loads every kernel;
- without the compile step: into another empty cache folder, the first run compiles the kernels
  it calls and caches them, and a second run loads them.

The figures are each repeat's first run over that second run, on either path (the performance
issue's target: at most 1.5 along the README's), and the compile step's time.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from ..outputs import output_file, write_json
from ..settings import integer

#: The largest first-run / second-run ratio the performance issue accepts.
TARGET = 1.5
#: The README's quickstart, less ``--out``.
QUICKSTART = ("paper", "--scenario", "1", "--trials", "20", "--quiet")
#: The README's install step that compiles every numba kernel.
COMPILE = ("compile",)


def timed_run(out: Path | None, cache: Path, args: tuple[str, ...] = QUICKSTART) -> float:
    """Wall time (s) of one ``mimo-radar-bench`` command in a new interpreter with numba's cache
    in ``cache``, writing into ``out`` (``None``: a command without ``--out``)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "benchmarks", *args, *(("--out", str(out)) if out is not None else ())],
        env=env,
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    return time.perf_counter() - start


def measure(repeats: int = 3, args: tuple[str, ...] = QUICKSTART) -> dict[str, Any]:
    """Each repeat's compile step, first run after it, first run without it and second run (s),
    each path from an empty cache, and the first runs' ratios to the second."""
    pairs = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as folder:
            root = Path(folder)
            compiled = timed_run(None, root / "compiled", COMPILE)
            after = timed_run(root / "after", root / "compiled", args)
            first = timed_run(root / "first", root / "cache", args)
            second = timed_run(root / "second", root / "cache", args)
        pairs.append(
            {
                "compile_s": compiled,
                "first_after_compile_s": after,
                "first_s": first,
                "second_s": second,
                "ratio_after_compile": after / second,
                "ratio": first / second,
            }
        )
    after_compile = [p["ratio_after_compile"] for p in pairs]
    ratios = [p["ratio"] for p in pairs]
    return {
        "command": ["mimo-radar-bench", *args, "--out", "DIR"],
        "compile_command": ["mimo-radar-bench", *COMPILE],
        "repeats": pairs,
        "median_ratio_after_compile": statistics.median(after_compile),
        "max_ratio_after_compile": max(after_compile),
        "median_compile_s": statistics.median(p["compile_s"] for p in pairs),
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
    parser.add_argument(
        "--repeats", type=integer(1), default=3, help="pairs of runs, each from an empty cache"
    )
    parser.add_argument(
        "--json", type=output_file, default=None, help="also write the figures and the machine to this file"
    )
    args = parser.parse_args(argv)
    result = measure(args.repeats)
    for i, pair in enumerate(result["repeats"], start=1):
        print(
            f"repeat {i}: compile step {pair['compile_s']:.1f} s, then the first run "
            f"{pair['first_after_compile_s']:.1f} s; without it, first run {pair['first_s']:.1f} s, "
            f"second {pair['second_s']:.1f} s"
        )
    print(
        f"first / second, after the compile step: median {result['median_ratio_after_compile']:.2f}, "
        f"largest {result['max_ratio_after_compile']:.2f} (target <= {TARGET:g}); without it: median "
        f"{result['median_ratio']:.2f}, largest {result['max_ratio']:.2f}"
    )
    if args.json:
        write_json(args.json, result, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
