"""Super-arm solvers at the paper's size: time per batched selection and optimality.

Run: ``python -m benchmarks.speed.solver_speed [--trials 500] [--repeats 5] [--write FILE]``.
Index matrices are i.i.d. Exponential(1) (SINR-like), (B, 4, 6), Ms = 2, Ns = 3.
Prints the time per batched selection of ``exact``, ``bpso`` (numba kernel and,
once, the numpy kernel) and ``alternating``, their ratios, BPSO's optimality rate
against ``exact``, and the alternating solver's gap on a 10 x 12 layout. With numba, it also
times the agents' BPSO selection in one thread under both position rules; under both, it times
BPSO's iterations where numba is not used (:func:`without_numba`). Earlier versions of
the kernel are compared across commits (:mod:`benchmarks.speed.across_commits`), not with copies
kept in the tree.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import time
from pathlib import Path

import numpy as np

from agents.solvers import AlternatingSolver, BPSOSolver, ExactSolver
from agents.solvers.bpso import BPSO_RULES
from mimo_radar_env.core.arrays import NUMPY
from mimo_radar_env.core.compiled import HAVE_NUMBA, numba
from mimo_radar_env.core.streams import TrialRandom

from ..outputs import write_json
from ..precompile import paper_index
from ..settings import integer
from ..study import machine


def _time(solver, index, repeats: int) -> tuple[float, tuple]:
    solver.solve(index, TrialRandom.for_batch(0, len(index)))  # warm-up (numba compilation)
    best, result = np.inf, None
    for r in range(repeats):
        start = time.perf_counter()
        result = solver.solve(index, TrialRandom.for_batch(r, len(index)))
        best = min(best, time.perf_counter() - start)
    return best, result


def optimality(index, tx, rx, etx, erx) -> tuple[float, float]:
    same = (tx == etx).all(axis=1) & (rx == erx).all(axis=1)
    value = np.einsum("bm,bmn,bn->b", tx, index, rx)
    best = np.einsum("bm,bmn,bn->b", etx, index, erx)
    return float(same.mean()), float(np.mean(1 - value / best))


def one_thread(index, repeats: int, rule: str = "xor") -> dict[str, float]:
    """The agents' BPSO selection in one thread, the paper's swarm, under position rule ``rule``:
    its best time of ``repeats`` (``bpso_1thread_ms_RULE``) and its optimality rate against
    ``exact`` (``bpso_optimality_rate_RULE``)."""
    solver = BPSOSolver(2, 3, rule=rule)  # the paper's swarm: the solver's defaults
    etx, erx = ExactSolver(2, 3).solve(index, TrialRandom.for_batch(0, len(index)))
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        solver.solve(index, TrialRandom.for_batch(0, len(index)))  # compilation
        seconds, rates = [], []
        for r in range(repeats):
            start = time.perf_counter()
            tx, rx = solver.solve(index, TrialRandom.for_batch(r, len(index)))
            seconds.append(time.perf_counter() - start)
            rates.append(float(((tx == etx).all(axis=1) & (rx == erx).all(axis=1)).mean()))
    finally:
        numba.set_num_threads(threads)
    return {
        f"bpso_1thread_ms_{rule}": min(seconds) * 1e3,
        f"bpso_optimality_rate_{rule}": float(np.mean(rates)),
    }


def without_numba(index, repeats: int, rule: str) -> dict[str, float]:
    """BPSO's iterations where numba is not used, the paper's swarm under rule ``rule``, best of
    ``repeats``: the numpy kernel (``bpso_numpy_iterations_ms_RULE``), each trial stopping at its
    optimum, against the same kernel running every iteration of every trial
    (``..._every_iteration_ms_RULE``, the same selections, checked); with torch installed the
    same on torch's CPU (``bpso_torch_cpu_...``; every iteration is what a CUDA graph replays)."""
    from agents.solvers import _bpso_kernels

    solver = BPSOSolver(2, 3, rule=rule)
    out: dict[str, float] = {}
    namespaces = [("numpy", NUMPY)]
    if importlib.util.find_spec("torch") is not None:
        from mimo_radar_env.core.arrays import device_namespace

        namespaces.append(("torch_cpu", device_namespace("cpu")))
    for name, xp in namespaces:
        positions, keys = solver.initial_swarm(TrialRandom.for_batch(0, len(index), xp), 4, 6)
        given = xp.asarray(index)
        arguments = (given, 2, 3, positions, keys, *solver.swarm_arguments())
        chosen = {}
        for stop, key in (
            (True, f"bpso_{name}_iterations_ms_{rule}"),
            (False, f"bpso_{name}_every_iteration_ms_{rule}"),
        ):
            seconds = []
            for _ in range(repeats):
                start = time.perf_counter()
                chosen[stop] = np.asarray(_bpso_kernels.run_numpy(*arguments, stop_at_optimum=stop))
                seconds.append(time.perf_counter() - start)
            out[key] = min(seconds) * 1e3
        if not np.array_equal(chosen[True], chosen[False]):  # pragma: no cover - a bug
            raise AssertionError(f"BPSO's {name} kernel selected differently when its trials stop")
    return out


def measure(trials: int = 500, repeats: int = 5) -> dict[str, float]:
    index = paper_index(trials)
    exact_s, (etx, erx) = _time(ExactSolver(2, 3), index, repeats)
    bpso_s, (btx, brx) = _time(BPSOSolver(2, 3), index, repeats)
    numpy_s, _ = _time(BPSOSolver(2, 3, use_numba=False), index, 1)
    rate, gap = optimality(index, btx, brx, etx, erx)
    big = np.random.default_rng(8).exponential(size=(trials, 10, 12))
    alt_s, (atx, arx) = _time(AlternatingSolver(3, 4), big, repeats)
    _, (xtx, xrx) = _time(ExactSolver(3, 4), big, 1)
    alt_rate, alt_gap = optimality(big, atx, arx, xtx, xrx)
    return {
        "exact_ms": exact_s * 1e3,
        "bpso_ms": bpso_s * 1e3,
        "bpso_numpy_ms": numpy_s * 1e3,
        "exact_vs_bpso_speedup": bpso_s / exact_s,
        "bpso_optimality_rate": rate,
        "bpso_mean_gap": gap,
        "alternating_ms_10x12": alt_s * 1e3,
        "alternating_optimality_rate_10x12": alt_rate,
        "alternating_mean_gap_10x12": alt_gap,
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="super-arm solver speed and optimality")
    parser.add_argument("--trials", type=integer(1), default=500)
    parser.add_argument("--repeats", type=integer(1), default=5)
    parser.add_argument("--json", action="store_true", help="end with the figures as one JSON line")
    parser.add_argument(
        "--write", type=Path, default=None, help="also write the figures and the machine here"
    )
    args = parser.parse_args(argv)
    r = measure(args.trials, args.repeats)
    index = paper_index(args.trials)
    for rule in BPSO_RULES:
        if HAVE_NUMBA:
            r.update(one_thread(index, args.repeats, rule))
        r.update(without_numba(index, args.repeats, rule))
    print(
        f"super-arm solvers, M=4 N=6 Ms=2 Ns=3, {args.trials} trials per batched selection"
        f" (numba {'on' if HAVE_NUMBA else 'not installed'})"
    )
    print(f"  exact                    {r['exact_ms']:10.2f} ms")
    rate, gap = 100 * r["bpso_optimality_rate"], 100 * r["bpso_mean_gap"]
    print(f"  bpso (Npop=50, q=100)    {r['bpso_ms']:10.2f} ms   optimal in {rate:.1f} %, gap {gap:.2f} %")
    print(f"  bpso, numpy kernel       {r['bpso_numpy_ms']:10.2f} ms")
    print(f"  exact is {r['exact_vs_bpso_speedup']:.0f}x faster than bpso")
    rate, gap = 100 * r["alternating_optimality_rate_10x12"], 100 * r["alternating_mean_gap_10x12"]
    print(
        f"  alternating, 10x12, Ms=3 Ns=4: {r['alternating_ms_10x12']:.2f} ms, optimal in {rate:.1f} %,"
        f" mean gap {gap:.3f} %"
    )
    if HAVE_NUMBA:
        print("  one thread, the paper's swarm (best of the repeats; optimal fraction against exact):")
        for rule in BPSO_RULES:
            print(
                f"    rule {rule}: {r[f'bpso_1thread_ms_{rule}']:.1f} ms"
                f" ({100 * r[f'bpso_optimality_rate_{rule}']:.1f} %)"
            )
    print("  BPSO's iterations without numba (best of the repeats), each trial stopping at its optimum,")
    print("  against every iteration of every trial:")
    for name in ("numpy", "torch_cpu"):
        for rule in BPSO_RULES:
            if f"bpso_{name}_iterations_ms_{rule}" in r:
                stopping = r[f"bpso_{name}_iterations_ms_{rule}"]
                every = r[f"bpso_{name}_every_iteration_ms_{rule}"]
                ratio = every / stopping
                print(f"    {name:9s} rule {rule}: {stopping:8.1f} ms against {every:8.1f} ms ({ratio:.1f}x)")
    if args.write is not None:
        write_json(args.write, {"trials": args.trials, "repeats": args.repeats, "machine": machine(), **r})
    if args.json:
        print(json.dumps(r))


if __name__ == "__main__":
    main()
