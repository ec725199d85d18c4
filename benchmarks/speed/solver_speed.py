"""Super-arm solvers at the paper's size: time per batched selection and optimality.

Run: ``python -m benchmarks.speed.solver_speed [--trials 500] [--repeats 5]``.
Index matrices are i.i.d. Exponential(1) (SINR-like), (B, 4, 6), Ms = 2, Ns = 3.
Prints the time per batched selection of ``exact``, ``bpso`` (numba kernel and,
once, the numpy kernel) and ``alternating``, their ratios, BPSO's optimality rate
against ``exact``, and the alternating solver's gap on a 10 x 12 layout. With numba, it also
times, in one thread and side by side for both position rules, the agents' BPSO selection, the
selection it replaced (the numpy starting swarm and ``benchmarks.speed.bpso_reference``'s kernel,
the speed reference) and the candidate SIMD kernel (``benchmarks.speed.bpso_simd``).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from agents.random_streams import TrialRandom
from agents.solvers import AlternatingSolver, BPSOSolver, ExactSolver
from agents.solvers.bpso import BPSO_RULES
from mimo_radar_env.core.compiled import HAVE_NUMBA, numba
from mimo_radar_env.core.counter_hash import Stream

from . import bpso_reference, bpso_simd


def paper_index(trials: int) -> np.ndarray:
    """The benchmark's index matrices at the paper's size: i.i.d. Exponential(1), (B, 4, 6)."""
    return np.random.default_rng(7).exponential(size=(trials, 4, 6))


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
    """One thread, the paper's swarm, the same index: the pre-rework selection kept as the
    reference (the numpy starting swarm and :mod:`benchmarks.speed.bpso_reference`'s kernel), the
    agents' selection and the SIMD candidate; each
    one's best time of ``repeats`` and its optimality rate against ``exact``, and the agents'
    and the candidate's speed-ups over the reference, all measured in this run."""
    solver = BPSOSolver(2, 3, rule=rule)  # the paper's swarm: the solver's defaults
    # the selection as it was before the rework: the numpy starting swarm, the reference kernel
    before = BPSOSolver(2, 3, rule=rule, use_numba=False)
    etx, erx = ExactSolver(2, 3).solve(index, TrialRandom.for_batch(0, len(index)))

    def reference(random: TrialRandom) -> tuple:
        positions, keys = before.initial_swarm(random, 4, 6)
        best = bpso_reference.run_reference(index, 2, 3, positions, keys, *solver.swarm_arguments())
        return best[:, :4].astype(bool), best[:, 4:].astype(bool)

    def candidate(random: TrialRandom) -> tuple:
        keys = random.keys_for(Stream.BPSO_KEYS)
        best = bpso_simd.run_numba(index, 2, 3, keys, solver.population, *solver.swarm_arguments())
        return best[:, :4].astype(bool), best[:, 4:].astype(bool)

    kernels = {"reference": reference, "agents": lambda r: solver.solve(index, r), "candidate": candidate}
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        out: dict[str, float] = {}
        seconds: dict[str, list[float]] = {name: [] for name in kernels}
        rates: dict[str, list[float]] = {name: [] for name in kernels}
        for run in kernels.values():
            run(TrialRandom.for_batch(0, len(index)))  # compilation
        for r in range(repeats):  # interleaved, so that a change of the machine's load hits all three
            for name, run in kernels.items():
                random = TrialRandom.for_batch(r, len(index))
                start = time.perf_counter()
                tx, rx = run(random)
                seconds[name].append(time.perf_counter() - start)
                rates[name].append(float(((tx == etx).all(axis=1) & (rx == erx).all(axis=1)).mean()))
        for name in kernels:
            key = "bpso" if name == "agents" else f"bpso_{name}"
            out[f"{key}_1thread_ms_{rule}"] = min(seconds[name]) * 1e3
            out[f"{key}_optimality_rate_{rule}"] = float(np.mean(rates[name]))
    finally:
        numba.set_num_threads(threads)
    reference_ms = out[f"bpso_reference_1thread_ms_{rule}"]
    out[f"bpso_speedup_vs_reference_{rule}"] = reference_ms / out[f"bpso_1thread_ms_{rule}"]
    out[f"bpso_candidate_speedup_vs_reference_{rule}"] = (
        reference_ms / out[f"bpso_candidate_1thread_ms_{rule}"]
    )
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


def main() -> None:
    parser = argparse.ArgumentParser(description="super-arm solver speed and optimality")
    parser.add_argument("--trials", type=int, default=500)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    r = measure(args.trials, args.repeats)
    if HAVE_NUMBA:
        index = paper_index(args.trials)
        for rule in BPSO_RULES:
            r.update(one_thread(index, args.repeats, rule))
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
                f"    rule {rule}: pre-rework kernel {r[f'bpso_reference_1thread_ms_{rule}']:.1f} ms"
                f" ({100 * r[f'bpso_reference_optimality_rate_{rule}']:.1f} %), agents' kernel"
                f" {r[f'bpso_1thread_ms_{rule}']:.1f} ms ({100 * r[f'bpso_optimality_rate_{rule}']:.1f} %):"
                f" {r[f'bpso_speedup_vs_reference_{rule}']:.2f}x; SIMD candidate"
                f" {r[f'bpso_candidate_1thread_ms_{rule}']:.1f} ms"
                f" ({100 * r[f'bpso_candidate_optimality_rate_{rule}']:.1f} %):"
                f" {r[f'bpso_candidate_speedup_vs_reference_{rule}']:.2f}x"
            )


if __name__ == "__main__":
    main()
