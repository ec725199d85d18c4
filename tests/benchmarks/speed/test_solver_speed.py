"""The solver benchmark: its optimality and gap are the brute-force ones, its speed-up the quotient
of the two times it measured."""

import itertools

import numpy as np
import pytest

from agents.solvers import ExactSolver
from benchmarks.precompile import paper_index
from benchmarks.speed import solver_speed
from mimo_radar_env.core.streams import TrialRandom


def _brute_force_best(index, ms, ns):
    trials, m, n = index.shape
    best = np.full(trials, -np.inf)
    for tx in itertools.combinations(range(m), ms):
        for rx in itertools.combinations(range(n), ns):
            best = np.maximum(best, index[:, list(tx)][:, :, list(rx)].sum(axis=(1, 2)))
    return best


def test_optimality_and_gap_are_against_the_brute_force_optimum():
    index = paper_index(40)
    etx, erx = ExactSolver(2, 3).solve(index, TrialRandom.for_batch(0, 40))
    best = _brute_force_best(index, 2, 3)
    np.testing.assert_allclose(np.einsum("bm,bmn,bn->b", etx, index, erx), best, rtol=1e-12)
    # a selection that is optimal in the first half of the trials and a fixed one elsewhere
    tx, rx = etx.copy(), erx.copy()
    tx[20:], rx[20:] = [1, 1, 0, 0], [1, 1, 1, 0, 0, 0]
    value = np.einsum("bm,bmn,bn->b", tx, index, rx)
    same = (tx == etx).all(1) & (rx == erx).all(1)
    rate, gap = solver_speed.optimality(index, tx, rx, etx, erx)
    assert rate == pytest.approx(same.mean()) and 0.5 <= rate < 1
    assert gap == pytest.approx(np.mean(1 - value / best)) and gap > 0


def test_the_measured_figures_mean_what_they_say():
    r = solver_speed.measure(trials=30, repeats=1)
    assert r["exact_vs_bpso_speedup"] == pytest.approx(r["bpso_ms"] / r["exact_ms"], rel=1e-12)
    for solver in ("bpso", "alternating"):
        suffix = "" if solver == "bpso" else "_10x12"
        assert 0 <= r[f"{solver}_optimality_rate{suffix}"] <= 1
        assert r[f"{solver}_mean_gap{suffix}"] >= 0  # never better than the exact optimum


def test_bpso_without_numba_is_timed_stopping_and_running_every_iteration(monkeypatch):
    """Both kernels of each namespace run (every iteration asked of the numpy kernel once a
    namespace), and the figures are the kernel's own times, named by namespace and rule."""
    from agents.solvers import _bpso_kernels

    calls = []
    run = _bpso_kernels.run_numpy
    monkeypatch.setattr(
        _bpso_kernels,
        "run_numpy",
        lambda *a, stop_at_optimum: calls.append(stop_at_optimum) or run(*a, stop_at_optimum=stop_at_optimum),
    )
    r = solver_speed.without_numba(np.random.default_rng(0).exponential(size=(20, 4, 6)), 2, "set")
    names = ["numpy", "torch_cpu"] if "bpso_torch_cpu_iterations_ms_set" in r else ["numpy"]
    assert calls == [True, True, False, False] * len(names)
    assert sorted(r) == sorted(
        f"bpso_{n}_{k}_ms_set" for n in names for k in ("iterations", "every_iteration")
    )
    assert all(value > 0 for value in r.values())
