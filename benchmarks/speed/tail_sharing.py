"""The tail shared and not: a study's wall time with and without its last tasks on idle cores.

When the last tasks take up the cores of the workers that ended
(``benchmarks.backends.share_idle_cores``), against the same study without.

    python -m benchmarks.speed.tail_sharing --json docs/results/perf/tail-sharing.json

It compiles every kernel first (``mimo-radar-bench compile``: the harness shares the tail only
where the kernels over threads are compiled already), then runs the study (default: the
strong-scaling study, the v1 claims study's scenario 1) with ``--workers W`` alternately as
shipped and with the sharing switched off (the same command, ``share_idle_cores`` replaced by a
function that does nothing), ``--repeats`` times each, the order reversed every other repeat,
every run a fresh command into a fresh folder. It gives each run's wall time and checks that every
run wrote the numbers of the first, bit for bit.
"""

from __future__ import annotations

import subprocess
import sys

from ..outputs import write_json
from ..study import machine
from .ray_cluster import CLI, Variant, alternate, alternating_arguments


def without_sharing(argv: list[str]) -> int:
    """The command line ``argv`` with the tail's sharing switched off, and nothing else changed."""
    from .. import backends
    from ..cli import main

    shipped = backends.share_idle_cores
    backends.share_idle_cores = lambda *arguments: None
    try:
        return main(argv)
    finally:
        backends.share_idle_cores = shipped


NOT_SHARED = (
    "import sys; from benchmarks.speed.tail_sharing import without_sharing; "
    "sys.exit(without_sharing(sys.argv[1:]))"
)
VARIANTS: dict[str, Variant] = {"shared": (CLI, ()), "not shared": (("-c", NOT_SHARED), ())}


def main(argv: list[str] | None = None) -> None:
    args = alternating_arguments(__doc__, 6, argv)
    subprocess.run([sys.executable, "-m", "benchmarks", "compile"], check=True, stdout=subprocess.DEVNULL)
    print(f"the tail shared and not: mimo-radar-bench {args.study}, {args.workers} workers")
    study = tuple(args.study.split())
    runs = alternate(study, args.workers, args.repeats, VARIANTS, "tail")
    write_json(
        args.json,
        {"study": ["mimo-radar-bench", *study], "workers": args.workers, "machine": machine(), "runs": runs},
    )


if __name__ == "__main__":
    main()
