"""Where the BPSO kernel's time goes: the agents' kernel with one part knocked out at a time.

Run: ``python -m benchmarks.speed.bpso_parts [--trials 500] [--repeats 3] [--json PATH]``
(``docs/results/perf/bpso_parts.json``, which docs/performance.md's table is generated from).

The kernel stops a trial once its global best holds the optimum, so how long it runs depends on
the swarm's path, which a knocked-out part changes. The breakdown is therefore of the whole
swarm: every variant is the agents' numba kernel (:mod:`agents.solvers._bpso_kernels`)
compiled from its own source without that stop (every trial runs all ``q_max`` iterations,
the "whole swarm"), and, but for the first, with one part replaced by something of negligible
cost: the eq21 exp polynomial (``e = 1 - v``), the flip draws' hashes, the ``r1``/``r2``
hashes, or the whole velocity and position update. A variant's numbers are wrong; only its
time is read. The part's cost is the whole swarm's time minus the variant's; what the stop
saves is the whole swarm's time minus the kernel's. All run in one thread, interleaved, at the
paper's size (Npop = 50, q_max = 100, Ms = 2, Ns = 3 of 4 x 6), beside the kernel the agents'
replaced (:mod:`benchmarks.speed.bpso_reference`). A replacement that no longer matches the
kernel's source is an error naming the part, so the breakdown cannot silently measure
something else.
"""

from __future__ import annotations

import argparse
import inspect
import json
import textwrap
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents.random_streams import TrialRandom
from agents.solvers import BPSOSolver, _bpso_kernels
from mimo_radar_env.core.compiled import numba

from ..studies.settings import integer
from . import bpso_reference, solver_speed

_POLYNOMIAL = """y = v * (-1.0 / 32.0)
e = 1.0 + y * (1.0 + y * (0.5 + y * (_C3 + y * (_C4 + y * (_C5 + y * _C6)))))
e = e * e
e = e * e
e = e * e
e = e * e
e = e * e"""
#: The kernel's stop at the optimum, which every variant leaves out (the whole swarm).
WHOLE_SWARM: list[tuple[str, str]] = [("if global_fit >= optimum:\nbreak", "pass")]
#: part -> replacements (old, new) of the kernel's source, each matched after stripping indents.
PARTS: dict[str, list[tuple[str, str]]] = {
    "the exp polynomial of eq21": [(_POLYNOMIAL, "e = 1.0 - v")],
    "the flip draws' hashes": [
        (
            "bits = element_bits_nb(base_flip, p * lanes + lane)",
            "bits = np.uint64(p * 2654435761 + lane * 977 + it * 131)",
        )
    ],
    "the r1, r2 hashes": [
        ("a1[p] = c1 * to_unit_nb(element_bits_nb(base_r1, p))", "a1[p] = c1 * 0.37"),
        ("a2[p] = c2 * to_unit_nb(element_bits_nb(base_r2, p))", "a2[p] = c2 * 0.61"),
    ],
    "the whole velocity and position update": [
        (
            "for j in range(length):\nbest_bit = global_best[j]",
            "for j in range(0):\nbest_bit = global_best[j]",
        )
    ],
}


def variant(part: str | None = None) -> Any:
    """The agents' kernel without its stop at the optimum and with ``part`` knocked out (``None``:
    the whole swarm alone), compiled (one thread)."""
    source = textwrap.dedent(inspect.getsource(_bpso_kernels._run_numba))
    lines = source.splitlines()
    replacements = [("the stop at the optimum", pair) for pair in WHOLE_SWARM]
    replacements += [(part, pair) for pair in (PARTS[part] if part is not None else [])]
    for what, (old, new) in replacements:
        stripped = [line.strip() for line in lines]
        want = old.splitlines()
        starts = [i for i in range(len(stripped)) if stripped[i : i + len(want)] == want]
        if len(starts) != 1:
            raise RuntimeError(f"the kernel's source no longer holds {what!r} as this benchmark knows it")
        i = starts[0]
        replaced = new.splitlines()
        # a line-for-line replacement keeps each line's indent; a shorter one takes the first's
        indents = [lines[i + k][: len(lines[i + k]) - len(lines[i + k].lstrip())] for k in range(len(want))]
        if len(replaced) != len(want):
            indents = [indents[0]] * len(replaced)
        lines[i : i + len(want)] = [indent + line for indent, line in zip(indents, replaced, strict=True)]
    name = "knocked_out"
    namespace = dict(vars(_bpso_kernels))
    exec(
        compile("\n".join(lines).replace("def _run_numba(", f"def {name}(", 1), "<bpso_parts>", "exec"),
        namespace,
    )
    return numba.njit(namespace[name])


def kernel_arguments(trials: int, rule: str, seed: int = 0) -> tuple:
    """The kernels' arguments for the paper-size problem: exponential indices (B, 4, 6), Ms = 2,
    Ns = 3, the starting swarm and the paper's swarm parameters (the solver's defaults)."""
    index = solver_speed.paper_index(trials)
    solver = BPSOSolver(2, 3, rule=rule)
    positions, keys = solver.initial_swarm(TrialRandom.for_batch(seed, trials), 4, 6)
    return (index, 2, 3, positions, keys, *solver.swarm_arguments())


def measure(trials: int = 500, repeats: int = 3, rule: str = "set") -> dict[str, Any]:
    """Best-of-``repeats`` milliseconds of the kernel, of the whole swarm (the kernel without its
    stop), of each knocked-out variant of the whole swarm and of the reference kernel, one thread,
    interleaved; each part's cost and share of the whole swarm's time."""
    args = kernel_arguments(trials, rule)
    kernels = {
        "kernel": _bpso_kernels.run_numba_serial,
        "whole swarm": variant(),
        "reference": bpso_reference.run_reference,
        **{part: variant(part) for part in PARTS},
    }
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        for kernel in kernels.values():
            kernel(*args)  # compilation
        best = {name: np.inf for name in kernels}
        for _ in range(repeats):
            for name, kernel in kernels.items():
                start = time.perf_counter()
                kernel(*args)
                best[name] = min(best[name], time.perf_counter() - start)
    finally:
        numba.set_num_threads(threads)
    ms = {name: 1e3 * seconds for name, seconds in best.items()}
    return {
        "trials": trials,
        "rule": rule,
        "kernel_ms": ms["kernel"],
        "whole_swarm_ms": ms["whole swarm"],
        "reference_ms": ms["reference"],
        "parts": [
            {
                "part": part,
                "without_ms": ms[part],
                "cost_ms": ms["whole swarm"] - ms[part],
                "share": (ms["whole swarm"] - ms[part]) / ms["whole swarm"],
            }
            for part in PARTS
        ],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=integer(1), default=500)
    parser.add_argument("--repeats", type=integer(1), default=3)
    parser.add_argument("--json", default=None, help="also write the figures to this file")
    args = parser.parse_args(argv)
    result = measure(args.trials, args.repeats)
    print(
        f"BPSO kernel, one thread, {args.trials} trials, rule {result['rule']}: "
        f"{result['kernel_ms']:.1f} ms; without its stop at the optimum (the whole swarm) "
        f"{result['whole_swarm_ms']:.1f} ms; "
        f"the kernel it replaced {result['reference_ms']:.1f} ms"
    )
    for row in result["parts"]:
        print(
            f"  without {row['part']:<40} {row['without_ms']:6.1f} ms: "
            f"the part costs {row['cost_ms']:5.1f} ms ({100 * row['share']:.0f} %)"
        )
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
