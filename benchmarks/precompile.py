"""Every numba kernel a run can call, compiled once into numba's on-disk cache.

A fresh install has no cache, so a run compiles the kernels it calls on their first call (about
4 s of the README's quickstart on two cores). ``mimo-radar-bench compile`` does it up front:
each :data:`WORKLOADS` entry runs, at a tiny size, the code path a run takes (a harness task for
the env and the tracking search, the solver's own calls for BPSO), so the kernels are compiled
for exactly the argument types a run passes; the workloads are spread over worker processes.
Afterwards every kernel of :func:`all_kernels` must be cached, or the command fails naming it.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from concurrent.futures import as_completed
from typing import Any

import numpy as np

from mimo_radar_env import VERSIONS
from mimo_radar_env.core.compiled import CHUNK, HAVE_NUMBA, uncached, with_threads
from mimo_radar_env.tracking.fusion import FUSIONS, compiled_kernels
from mimo_radar_env.tracking.selection import compiled_kernels as selection_kernels

from .errors import BenchError

#: The scenario the workloads run (any scenario calls the kernels with the same argument types).
SCENARIO = "paper-1-v1"


def paper_index(trials: int) -> np.ndarray:
    """Index matrices at the paper's size: i.i.d. Exponential(1), (B, 4, 6)."""
    return np.random.default_rng(7).exponential(size=(trials, 4, 6))


def _env_and_tracking_search(fusion: str, threads: int = 1) -> None:
    """Two-step harness tasks of best-tracking under ``fusion``, of two trials and of one: the
    fusion's update, the bound and the tracking search's posteriors (whose super-arm masks, a
    broadcast view, are typed differently for one trial); with ``threads``, one task of more
    than one chunk of trials on that many threads (their twins over threads)."""

    from . import harness

    options = VERSIONS["v1"].options(fusion=fusion)
    for trials in (2, 1) if threads == 1 else (CHUNK + 1,):
        config = harness.make_config(
            SCENARIO, ["best-tracking"], trials, 2, options=options, say=lambda _: None
        )
        with with_threads(threads):
            harness.run_task(config.to_json(), "best-tracking", 0)


def _threads() -> int:
    """Threads for the twins over threads: two where numba has them (one core has one, and a
    run there never takes those twins)."""
    from mimo_radar_env.core.compiled import numba

    return min(2, numba.config.NUMBA_NUM_THREADS)


def _bpso(threads: int) -> None:
    """One paper-size BPSO selection (2 of 4 TX, 3 of 6 RX) with the kernel for ``threads``
    numba threads: a harness worker's one-thread kernel, or a one-process run's parallel one."""
    from agents.solvers import BPSOSolver, _bpso_kernels
    from mimo_radar_env.core.streams import TrialRandom

    solver = BPSOSolver(2, 3)
    index = solver.check(paper_index(2))
    positions, keys = solver.initial_swarm(TrialRandom.for_batch(0, 2), 4, 6)
    _bpso_kernels.numba_kernel(threads)(index, 2, 3, positions, keys, *solver.swarm_arguments())


#: name -> (workload, its compilation time in seconds on the developers' machine, for ordering).
WORKLOADS: dict[str, tuple[Callable[[], None], float]] = {
    "BPSO, all threads (a one-process run)": (lambda: _bpso(2), 5.3),
    **{
        f"env, {fusion} fusion, and the tracking search": (
            lambda fusion=fusion: _env_and_tracking_search(fusion),
            4.0,
        )
        for fusion in FUSIONS
    },
    "BPSO, one thread (a harness worker)": (lambda: _bpso(1), 2.8),
    # both fusions in one worker, in turn: the second loads the threaded bound and tracking search
    # the first compiled, rather than compiling them again beside it
    "env over threads, each fusion, and the tracking search": (
        lambda: [_env_and_tracking_search(fusion, _threads()) for fusion in FUSIONS],
        13.0,
    ),
}


def all_kernels(threaded: bool = True) -> list[Any]:
    """Every numba kernel a run can call: each fusion's update and the bound, the tracking
    search's, and their twins over threads where numba has more than one; BPSO's starting swarm
    and its one-thread and parallel kernels. Without ``threaded``, those a worker of one thread
    calls (no twin over threads)."""
    from agents.solvers import _bpso_kernels
    from agents.solvers import compiled_kernels as solver_kernels

    kernels: list[Any] = []
    for twin in (False, True) if threaded and _threads() > 1 else (False,):
        for fusion in FUSIONS:
            kernels += compiled_kernels(fusion, twin)
        kernels += selection_kernels(twin)
    kernels += solver_kernels("bpso", threads=1) + ([_bpso_kernels.run_numba] if threaded else [])
    return list(dict.fromkeys(kernels))  # the bound is every fusion's: listed once


def _run(name: str) -> float:
    start = time.perf_counter()
    WORKLOADS[name][0]()
    return time.perf_counter() - start


def precompile(workers: int = 2) -> Iterator[tuple[str, float]]:
    """Run :data:`WORKLOADS` (the longest first) in ``workers`` worker processes; yields each
    workload's name and seconds as it finishes. Raises :class:`BenchError` if a kernel of
    :func:`all_kernels` is still uncached afterwards (a workload no longer calls it as a run does)."""
    from .backends import worker_pool

    if not HAVE_NUMBA:
        raise BenchError("numba is not installed (pip install -e '.[fast]'): there is nothing to compile")
    names = sorted(WORKLOADS, key=lambda name: -WORKLOADS[name][1])
    with worker_pool(workers) as pool:
        # with two workers, one runs both env workloads in turn: the second loads the bound the
        # first compiled, rather than compiling it again beside it
        futures = {pool.submit(_run, name): name for name in names}
        pool.close()
        for future in as_completed(futures):
            yield futures[future], future.result()
    left = uncached(all_kernels())
    if left:
        raise BenchError(f"after compiling, these kernels are still not cached: {', '.join(left)}")
