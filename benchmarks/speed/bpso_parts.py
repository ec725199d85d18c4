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

The breakdown runs under both position rules, each with how many iterations the kernel's trials
run before their stop (:func:`counting_variant`: the kernel with its stop, recording the iteration
each trial stops at). From these it estimates the time of a kernel with today's numbers whose
eq21 decision cost nothing: the whole swarm without the exp polynomial, scaled by the share of
the ``q_max`` iterations the trials run (the same scaling of the whole swarm is printed beside the
kernel's measured time, as a check of the estimate).

It also times, under both rules, the agents' kernel transcribed to float32 with its stop
(:func:`float32_variant`: the swarm's state, the draws and eq20-eq21 in float32, particles
padded to 16, the float32 vector width; eq19's table stays float64), the layout the performance
issue proposed, beside the kernel and the kernel it replaced. Its selections are a different
random stream's: how often they are the optimum is counted against the exact solver's.
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
from agents.solvers.bpso import BPSO_RULES
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
    return _compiled("\n".join(lines), "knocked-out variant")


def _compiled(source: str, what: str, constants: dict[str, Any] | None = None) -> Any:
    """``source``, an edited copy of the agents' kernel, compiled (one thread) in the kernels'
    module namespace with ``constants`` added."""
    namespace = {**vars(_bpso_kernels), **(constants or {})}
    exec(
        compile(source.replace("def _run_numba(", "def edited_kernel(", 1), f"<bpso_parts {what}>", "exec"),
        namespace,
    )
    return numba.njit(namespace["edited_kernel"])


#: The float32 transcription: (old, new) substrings of the kernel's source, each found once.
FLOAT32: list[tuple[str, str]] = [
    ("width = (population + LANES - 1) // LANES * LANES", "width = (population + 15) // 16 * 16"),
    *[
        (f"{name} = np.empty({shape})", f"{name} = np.empty({shape}, dtype=np.float32)")
        for name, shape in [
            ("position", "(length, width)"),
            ("velocity", "(length, width)"),
            ("personal_best", "(length, width)"),
            ("uniform", "(length, width)"),
            ("a1", "width"),
            ("a2", "width"),
            ("global_best", "length"),
        ]
    ],
    (
        "d = np.float64(positions[b, p, j]) if p < population else 0.0",
        "d = np.float32(positions[b, p, j]) if p < population else _F0",
    ),
    ("velocity[j, p] = 0.0", "velocity[j, p] = _F0"),
    ("global_best[j] = 0.0", "global_best[j] = _F0"),
    (
        "inertia = inertia_start - (inertia_start - inertia_end) * it / steps",
        "inertia = np.float32(inertia_start - (inertia_start - inertia_end) * it / steps)",
    ),
    (
        "a1[p] = c1 * to_unit_nb(element_bits_nb(base_r1, p))",
        "a1[p] = np.float32(c1 * to_unit_nb(element_bits_nb(base_r1, p)))",
    ),
    (
        "a2[p] = c2 * to_unit_nb(element_bits_nb(base_r2, p))",
        "a2[p] = np.float32(c2 * to_unit_nb(element_bits_nb(base_r2, p)))",
    ),
    ("u = (np.float64(lane_bits) + 0.5) * (1.0 / 65536.0)", "u = (np.float32(lane_bits) + _HALF) * _UNIT16"),
    (
        "v = min(max(v, -velocity_clamp), velocity_clamp)",
        "v = min(max(v, -np.float32(velocity_clamp)), np.float32(velocity_clamp))",
    ),
    ("y = v * (-1.0 / 32.0)", "y = v * _SCALE"),
    (
        "e = 1.0 + y * (1.0 + y * (0.5 + y * (_C3 + y * (_C4 + y * (_C5 + y * _C6)))))",
        "e = _F1 + y * (_F1 + y * (_HALF + y * (_G3 + y * (_G4 + y * (_G5 + y * _G6)))))",
    ),
    ("hit = uniform[j, p] * (1.0 + e) < 1.0", "hit = uniform[j, p] * (_F1 + e) < _F1"),
    ("position[j, p] = 1.0 if hit else 0.0", "position[j, p] = _F1 if hit else _F0"),
    ("position[j, p] = (1.0 - d) if hit else d", "position[j, p] = (_F1 - d) if hit else d"),
    ("code[p] += position[j, p] * w", "code[p] += np.float64(position[j, p]) * w"),
]
_F32 = np.float32
#: The float32 constants the transcription reads (numba takes module globals as constants).
FLOAT32_CONSTANTS = {
    "_F0": _F32(0.0),
    "_F1": _F32(1.0),
    "_HALF": _F32(0.5),
    "_UNIT16": _F32(1.0 / 65536.0),
    "_SCALE": _F32(-1.0 / 32.0),
    "_G3": _F32(1.0 / 6.0),
    "_G4": _F32(1.0 / 24.0),
    "_G5": _F32(1.0 / 120.0),
    "_G6": _F32(1.0 / 720.0),
}


def _transcribed(
    replacements: list[tuple[str, str]], what: str, constants: dict[str, Any] | None = None
) -> Any:
    """The agents' kernel with each (old, new) substring of its source replaced, compiled (one
    thread). A replacement that no longer matches the kernel's source exactly once is an error
    naming it and ``what`` the transcription is."""
    source = textwrap.dedent(inspect.getsource(_bpso_kernels._run_numba))
    for old, new in replacements:
        if source.count(old) != 1:
            raise RuntimeError(f"the kernel's source no longer holds {old!r} once, as the {what} knows it")
        source = source.replace(old, new)
    return _compiled(source, what, constants)


def float32_variant() -> Any:
    """The agents' kernel, stop included, transcribed to float32 by :data:`FLOAT32`, compiled
    (one thread)."""
    return _transcribed(FLOAT32, "float32 transcription", FLOAT32_CONSTANTS)


#: The kernel with its stop, recording in an extra column the last iteration each trial runs (the
#: iteration loop's ``q`` after the loop: where it stopped, or ``q_max``).
COUNTING: list[tuple[str, str]] = [
    (
        "result = np.empty((batch, length), dtype=np.int8)",
        "result = np.zeros((batch, length + 1), dtype=np.int64)",
    ),
    (
        "result[b, j] = np.int8(global_best[j])",
        "result[b, j] = np.int8(global_best[j]); result[b, length] = q",
    ),
]


def counting_variant() -> Any:
    """The agents' kernel, stop included, returning (B, M + N + 1): its selections and, last, the
    number of iterations each trial ran (``q_max`` for a trial that never held the optimum)."""
    return _transcribed(COUNTING, "iteration count")


def iterations_run(trials: int = 500, rule: str = "set") -> dict[str, float]:
    """How many of the ``q_max`` iterations the kernel's trials run before their stop: the mean,
    and the share of trials that run them all."""
    args = kernel_arguments(trials, rule)
    counted = counting_variant()(*args)
    iterations = args[5]
    run = counted[:, -1]
    return {
        "q_max": iterations,
        "mean_iterations": float(run.mean()),
        "share_all_iterations": float(np.mean(run == iterations)),
    }


def float32_comparison(trials: int = 500, repeats: int = 3) -> dict[str, Any]:
    """Per rule, best-of-``repeats`` milliseconds of the kernel, of its float32 transcription and
    of the kernel it replaced (one thread, interleaved), and how often each selects the exact
    solver's super arm (its fitness's largest value)."""
    from agents.solvers import ExactSolver

    float32 = float32_variant()
    kernels = {
        "kernel": _bpso_kernels.run_numba_serial,
        "float32": float32,
        "reference": bpso_reference.run_reference,
    }
    rules = {}
    for rule in BPSO_RULES:
        args = kernel_arguments(trials, rule)
        index = args[0]
        exact_tx, exact_rx = ExactSolver(2, 3).solve(index, None)
        optimum = np.einsum("bm,bn,bmn->b", exact_tx, exact_rx, index)
        selected, best = _interleaved(kernels, args, repeats)
        rate = {
            name: float(np.mean(np.einsum("bm,bn,bmn->b", s[:, :4], s[:, 4:], index) == optimum))
            for name, s in selected.items()
        }
        rules[rule] = {
            **{f"{name}_ms": 1e3 * seconds for name, seconds in best.items()},
            **{f"{name}_optimality_rate": value for name, value in rate.items()},
        }
    return {"trials": trials, "rules": rules}


def _interleaved(
    kernels: dict[str, Any], args: tuple, repeats: int
) -> tuple[dict[str, Any], dict[str, float]]:
    """Each kernel's result (of its first call, which compiles it) and its best-of-``repeats``
    seconds, in one numba thread, the kernels interleaved."""
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        results = {name: kernel(*args) for name, kernel in kernels.items()}
        best = {name: np.inf for name in kernels}
        for _ in range(repeats):
            for name, kernel in kernels.items():
                start = time.perf_counter()
                kernel(*args)
                best[name] = min(best[name], time.perf_counter() - start)
    finally:
        numba.set_num_threads(threads)
    return results, best


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
    _, best = _interleaved(kernels, args, repeats)
    ms = {name: 1e3 * seconds for name, seconds in best.items()}
    return {
        "trials": trials,
        "rule": rule,
        **iterations_run(trials, rule),
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
    result: dict[str, Any] = {
        "trials": args.trials,
        "breakdowns": [measure(args.trials, args.repeats, rule) for rule in BPSO_RULES],
        "float32": float32_comparison(args.trials, args.repeats),
    }
    for breakdown in result["breakdowns"]:
        print(
            f"BPSO kernel, one thread, {args.trials} trials, rule {breakdown['rule']}: "
            f"{breakdown['kernel_ms']:.1f} ms, its trials running {breakdown['mean_iterations']:.1f} of "
            f"{breakdown['q_max']} iterations on average ({breakdown['share_all_iterations']:.1%} all); "
            f"without its stop at the optimum (the whole swarm) {breakdown['whole_swarm_ms']:.1f} ms; "
            f"the kernel it replaced {breakdown['reference_ms']:.1f} ms"
        )
        for row in breakdown["parts"]:
            print(
                f"  without {row['part']:<40} {row['without_ms']:6.1f} ms: "
                f"the part costs {row['cost_ms']:5.1f} ms ({100 * row['share']:.0f} %)"
            )
    for rule, row in result["float32"]["rules"].items():
        print(
            f"rule {rule}: the kernel {row['kernel_ms']:.1f} ms, in float32 {row['float32_ms']:.1f} ms, the "
            f"kernel it replaced {row['reference_ms']:.1f} ms (optimal selections: "
            f"{row['kernel_optimality_rate']:.1%}, {row['float32_optimality_rate']:.1%}, "
            f"{row['reference_optimality_rate']:.1%})"
        )
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
