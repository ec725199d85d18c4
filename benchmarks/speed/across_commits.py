"""One benchmark figure at two commits, measured in the same run: how a kernel compares with an
earlier version of itself, without a copy of the old code in the tree.

Run, from a git checkout::

    python -m benchmarks.speed.across_commits 0b8e389 HEAD --key bpso_1thread_ms_xor \\
        -- python -m benchmarks.speed.solver_speed --json

Each commit is checked out into a temporary ``git worktree``; the command runs there
``--repeats`` times, the two commits interleaved (so that a change in the machine's load falls
on both), and must end its output with one JSON object; ``--key`` names the number taken from
it. ``--warmup N`` runs each commit's command N times first, not recorded (a new checkout's
first run compiles the numba kernels into its own cache). It prints each commit's median and
their ratio (the first commit's over the second's: for a time, the speed-up of the second),
and writes them as JSON with ``--json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..outputs import output_file, write_json
from ..settings import integer


def _checkout(repo: Path, commit: str, where: Path) -> None:
    subprocess.run(
        ["git", "-C", str(repo), "worktree", "add", "--detach", "--quiet", str(where), commit],
        check=True,
        capture_output=True,
        text=True,
    )


def _figure(command: Sequence[str], where: Path, key: str) -> float:
    """The number ``key`` of the JSON object that ends ``command``'s output, run in ``where`` with
    that checkout's packages first on the path."""
    environment = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(where), os.environ.get("PYTHONPATH", "")]),
    }
    result = subprocess.run(list(command), cwd=where, env=environment, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed in {where}: {result.stderr.strip()[-500:]}")
    lines = result.stdout.strip().splitlines()
    try:
        figures = json.loads(lines[-1])
        return float(figures[key])
    except (IndexError, json.JSONDecodeError, KeyError, TypeError, ValueError):
        raise RuntimeError(f"{' '.join(command)} did not end with a JSON object holding {key!r}") from None


def compare(
    repo: str | Path,
    commits: tuple[str, str],
    command: Sequence[str],
    key: str,
    repeats: int = 3,
    warmup: int = 0,
) -> dict[str, Any]:
    """Each commit's median of ``key`` over ``repeats`` interleaved runs of ``command``, and the
    ratio of the first commit's to the second's; after ``warmup`` runs of each, not recorded (a
    new checkout's first run compiles the numba kernels into its own cache)."""
    repo = Path(repo).resolve()
    values: dict[str, list[float]] = {commit: [] for commit in commits}
    with tempfile.TemporaryDirectory() as scratch:
        trees = {commit: Path(scratch) / f"tree{i}" for i, commit in enumerate(commits)}
        try:
            for commit, tree in trees.items():
                _checkout(repo, commit, tree)
            for run in range(warmup + repeats):
                for commit, tree in trees.items():
                    figure = _figure(command, tree, key)
                    if run >= warmup:
                        values[commit].append(figure)
        finally:
            for tree in trees.values():
                subprocess.run(
                    ["git", "-C", str(repo), "worktree", "remove", "--force", str(tree)], capture_output=True
                )
    medians = {commit: statistics.median(v) for commit, v in values.items()}
    first, second = commits
    return {
        "key": key,
        "command": list(command),
        "repeats": repeats,
        **({"warmup": warmup} if warmup else {}),
        "values": values,
        "medians": medians,
        "ratio": medians[first] / medians[second],
    }


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    argv = list(sys.argv[1:] if argv is None else argv)
    command = argv[argv.index("--") + 1 :] if "--" in argv else []
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.speed.across_commits",
        description="one benchmark figure at two commits, interleaved in one run",
    )
    parser.add_argument("first", help="the earlier commit")
    parser.add_argument("second", nargs="?", default="HEAD", help="the later commit (default HEAD)")
    parser.add_argument("--key", required=True, help="the number to take from the command's JSON line")
    parser.add_argument("--repeats", type=integer(1), default=3, help="runs per commit (default 3)")
    parser.add_argument(
        "--warmup", type=integer(0), default=0, help="runs per commit first, not recorded (default 0)"
    )
    parser.add_argument("--repo", default=".", help="the git checkout (default: here)")
    parser.add_argument("--json", type=output_file, default=None, help="also write the result to this file")
    args = parser.parse_args(argv[: argv.index("--")] if "--" in argv else argv)
    if not command:
        parser.error("give the benchmark command after '--'")
    result = compare(args.repo, (args.first, args.second), command, args.key, args.repeats, args.warmup)
    first, second = result["medians"]
    print(
        f"{args.key}: {first} {result['medians'][first]:.4g}, {second} {result['medians'][second]:.4g}; "
        f"{first} / {second} = {result['ratio']:.2f} (medians of {args.repeats}, interleaved)"
    )
    if args.json:
        write_json(args.json, result)
    return result


if __name__ == "__main__":
    main()
