"""Where a command's own wall time goes: its main thread, sampled as it runs.

    python -m benchmarks.speed.timeline --json OUT.json -- claims --scenarios 1 --trials 500 \\
        --workers 16 --quiet --no-figures --out DIR

runs ``mimo-radar-bench ARGS`` in this process while a thread samples the main thread's stack
every ``--interval`` seconds. A sample is placed at the innermost frame of the project's
packages (``path:function``; the innermost frame of all where none is the project's), with the
innermost function beside it (``wait``: the command idle while the tasks run; ``read``: waiting
for a process). Consecutive samples at one place make a span. It prints a study's wall time in
parts (:func:`parts`), each place's total and the spans of at least ``--min-span`` seconds, and
writes them as JSON.

The workers' tasks are timed by their shards (:mod:`.strong_scaling`); this is the command's part
of the wall time: its set-up before the first task, what it computes while the tasks run, and
its end. Sampling holds the interpreter's lock for a moment every interval: a command with a
busy main thread runs a little slower under it.
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from types import FrameType
from typing import Any

from ..outputs import output_file, write_json

#: The folders whose frames are the project's.
PROJECT = tuple(
    Path(__file__).resolve().parents[2] / package for package in ("mimo_radar_env", "agents", "benchmarks")
)


@dataclass(frozen=True)
class Span:
    """Consecutive samples at one place: from the first (s after the start) to the next sample
    elsewhere (or the end)."""

    start: float
    end: float
    where: str
    leaf: str

    @property
    def seconds(self) -> float:
        return self.end - self.start


def place(frame: FrameType, roots: Sequence[Path] = PROJECT) -> tuple[str, str]:
    """``(where, leaf)`` of a stack whose innermost frame is ``frame``: the innermost frame under
    ``roots`` (its path from their parent folder, and its function), or the innermost of all
    (its file's name), and the innermost frame's function."""
    leaf = frame.f_code.co_name
    folders = [str(root) for root in roots]
    current: FrameType | None = frame
    while current is not None:
        filename = current.f_code.co_filename
        for folder in folders:
            if filename.startswith(folder):
                relative = Path(filename).relative_to(Path(folder).parent)
                return f"{relative}:{current.f_code.co_name}", leaf
        current = current.f_back
    return f"{Path(frame.f_code.co_filename).name}:{leaf}", leaf


def sample(
    function: Callable[[], Any], interval: float = 0.01, roots: Sequence[Path] = PROJECT
) -> tuple[Any, list[Span], float]:
    """Run ``function`` in this thread, sampled every ``interval`` seconds: its result, the spans
    and the wall seconds. An exception of ``function`` is raised after the sampling stops."""
    main, samples = threading.get_ident(), []
    stop = threading.Event()
    start = time.perf_counter()

    def sampler() -> None:
        while not stop.wait(interval):
            frame = sys._current_frames().get(main)
            if frame is not None:
                samples.append((time.perf_counter() - start, *place(frame, roots)))

    thread = threading.Thread(target=sampler, daemon=True)
    thread.start()
    try:
        result = function()
    finally:
        stop.set()
        thread.join()
        wall = time.perf_counter() - start
    return result, spans(samples, wall), wall


def spans(samples: Sequence[tuple[float, str, str]], wall: float) -> list[Span]:
    """Samples ``(seconds, where, leaf)`` in time order merged into spans."""
    merged: list[Span] = []
    for index, (at, where, leaf) in enumerate(samples):
        end = samples[index + 1][0] if index + 1 < len(samples) else wall
        if merged and (merged[-1].where, merged[-1].leaf) == (where, leaf):
            merged[-1] = Span(merged[-1].start, end, where, leaf)
        else:
            merged.append(Span(at, end, where, leaf))
    return merged


def totals(of: Sequence[Span]) -> dict[str, float]:
    """Each place's seconds over all its spans, the most first."""
    seconds: dict[str, float] = {}
    for span in of:
        key = f"{span.where} | {span.leaf}"
        seconds[key] = seconds.get(key, 0.0) + span.seconds
    return dict(sorted(seconds.items(), key=lambda item: -item[1]))


#: The places where a study's command waits for its tasks (local workers or Ray), and where it
#: computes intervals.
WAITING = ("benchmarks/backends.py:run_processes", "benchmarks/backends.py:run_ray")
STATISTICS = ("benchmarks/metrics.py:", "benchmarks/uncertainty.py:")
#: :func:`parts`' keys, in time order, and what each holds.
PARTS = {
    "before": "until it first waits for its tasks",
    "waiting": "waiting for its tasks",
    "statistics": "computing intervals, between its waits",
    "other": "other work between its waits",
    "after": "after its last wait",
}


def parts(of: Sequence[Span], wall: float) -> dict[str, float]:
    """A study's command's wall seconds in :data:`PARTS`: until it first waits for its tasks (its
    imports, checks and plan, starting the workers, and what it does once the tasks are
    submitted and before it waits: the first tasks may start within this part), then, up to the
    end of its last wait, the waits, the intervals it computed (as policies finished) and its
    other work (saving shards, joining them), and after its last wait (the last intervals, the
    report). Empty where it never waited (a run in its own process)."""
    waits = [span for span in of if span.where in WAITING]
    if not waits:
        return {}
    first, last = waits[0].start, waits[-1].end
    between = [span for span in of if first <= span.start and span.end <= last]
    waited = sum(span.seconds for span in waits)
    statistics = sum(span.seconds for span in between if span.where.startswith(STATISTICS))
    return dict(
        zip(PARTS, (first, waited, statistics, last - first - waited - statistics, wall - last), strict=True)
    )


def _run_command(argv: list[str]) -> int:
    from benchmarks import cli

    try:
        return int(cli.main(argv) or 0)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else 1


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    argv = list(sys.argv[1:] if argv is None else argv)
    if "--" not in argv:
        raise SystemExit("give the command's arguments after '--' (e.g. -- claims --trials 20)")
    split = argv.index("--")
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.speed.timeline", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--interval", type=float, default=0.01, help="seconds between samples (default 0.01)")
    parser.add_argument("--min-span", type=float, default=0.1, help="shortest span printed (s, default 0.1)")
    parser.add_argument("--json", type=output_file, default=None, help="also write the timeline here")
    args = parser.parse_args(argv[:split])
    if not args.interval > 0:
        parser.error(f"--interval must be above 0, got {args.interval}")
    command = argv[split + 1 :]
    code, timeline, wall = sample(lambda: _run_command(command), args.interval)
    record = {
        "command": ["mimo-radar-bench", *command],
        "exit_code": code,
        "interval_s": args.interval,
        "wall_s": wall,
        "parts_s": parts(timeline, wall),
        "totals_s": totals(timeline),
        "spans": [asdict(span) for span in timeline],
    }
    print(f"{' '.join(record['command'])}: {wall:.2f} s (exit code {code})")
    for name, seconds in record["parts_s"].items():
        print(f"  {seconds:7.2f} s  {PARTS[name]}")
    print("the main thread's time by place:")
    for key, seconds in record["totals_s"].items():
        if seconds >= args.min_span:
            print(f"  {seconds:7.2f} s  {key}")
    print(f"spans of at least {args.min_span} s:")
    for span in timeline:
        if span.seconds >= args.min_span:
            print(f"  {span.start:7.2f} - {span.end:7.2f} s  {span.where} | {span.leaf}")
    write_json(args.json, record)
    return record


if __name__ == "__main__":
    main()
