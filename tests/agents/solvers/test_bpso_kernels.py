"""BPSO's kernels: numba against numpy, serial against parallel, by table against by direct sum,
the stop at the optimum, the starting swarm, eq19's table and eq21's polynomial."""

import numpy as np
import pytest

from agents.solvers import BPSOSolver, ExactSolver, _bpso_kernels
from agents.solvers.bpso import TABLE_BITS
from mimo_radar_env.core.superarm import top_mask
from tests.agents.solvers.helpers import streams


def test_bpso_numba_and_numpy_kernels_give_the_same_numbers():
    if not _bpso_kernels.HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy kernel exists")
    index = np.random.default_rng(2).exponential(size=(40, 5, 7))
    fast = BPSOSolver(2, 3, iterations=30).solve(index, streams(index, 9))
    slow = BPSOSolver(2, 3, iterations=30, use_numba=False).solve(index, streams(index, 9))
    np.testing.assert_array_equal(fast[0], slow[0])
    np.testing.assert_array_equal(fast[1], slow[1])


@pytest.mark.parametrize("block", [1, 7, 30])
def test_bpso_numpy_kernel_draws_the_same_numbers_in_any_block_of_iterations(monkeypatch, block):
    """The numpy kernel hashes a block of iterations' draws at once: a block of one iteration, one
    that does not divide the iterations, and all of them select the same super arms."""
    index = np.random.default_rng(4).exponential(size=(9, 4, 6))
    solver = BPSOSolver(2, 3, iterations=30, use_numba=False)
    whole = solver.solve(index, streams(index, 3))
    population, stations = solver.population, 4 + 6
    monkeypatch.setitem(_bpso_kernels.DRAW_BLOCK_BYTES, "numpy", 8 * 9 * population * (2 + stations) * block)
    blocks = solver.solve(index, streams(index, 3))
    np.testing.assert_array_equal(blocks[0], whole[0])
    np.testing.assert_array_equal(blocks[1], whole[1])


@pytest.mark.parametrize("rule", ["xor", "set"])
def test_the_numpy_kernel_stops_each_trial_at_its_optimum_and_selects_what_every_iteration_selects(
    monkeypatch, rule
):
    """A trial whose global best holds its table's largest valid value leaves the swarm's arrays
    (as the compiled kernel stops it); the others run on: the same global bests, to the bit, as
    every trial running every iteration, and those that stopped hold the exact optimum."""
    index = np.random.default_rng(8).exponential(size=(40, 4, 6))
    solver = BPSOSolver(2, 3, iterations=60, rule=rule, use_numba=False)
    positions, keys = solver.initial_swarm(streams(index, 2), 4, 6)
    arguments = (index, 2, 3, positions, keys, *solver.swarm_arguments())
    left = []
    keep = _bpso_kernels._Fitness.keep
    monkeypatch.setattr(
        _bpso_kernels._Fitness, "keep", lambda self, rows: left.append(int(rows.sum())) or keep(self, rows)
    )
    stopping = _bpso_kernels.run_numpy(*arguments)
    every = _bpso_kernels.run_numpy(*arguments, stop_at_optimum=False)
    np.testing.assert_array_equal(stopping, every)
    assert left and left == sorted(left, reverse=True) and left[-1] < 40  # trials left, fewer each time
    values = np.einsum("bm,bn,bmn->b", every[:, :4].astype(float), every[:, 4:].astype(float), index)
    best = ExactSolver(2, 3).solve(index, streams(index))
    optimum = np.einsum("bm,bn,bmn->b", best[0].astype(float), best[1].astype(float), index)
    assert (values <= optimum + 1e-12).all() and np.isclose(values, optimum).sum() >= 40 - left[-1]


@pytest.mark.parametrize(("shape", "counts"), [((4, 6), (2, 3)), ((3, 3), (1, 1)), ((5, 2), (5, 1))])
def test_the_valid_patterns_are_every_bit_pattern_with_the_stations_counts(shape, counts):
    code = np.arange(1 << sum(shape))
    bits = (code[:, None] >> np.arange(sum(shape))) & 1
    valid = (bits[:, : shape[0]].sum(axis=1) == counts[0]) & (bits[:, shape[0] :].sum(axis=1) == counts[1])
    assert _bpso_kernels._valid_patterns(*shape, *counts) == tuple(code[valid].tolist())


def test_bpso_numpy_kernels_fitness_table_gives_the_direct_sums_bit_for_bit(monkeypatch):
    """eq19 looked up in the table of every bit pattern is each valid particle's direct sum, to
    the bit, and -inf for every invalid one; a batch whose table would not fit sums directly, and
    the solver selects the same super arms either way."""
    rng = np.random.default_rng(6)
    index = rng.normal(size=(5, 4, 6)) * 10.0 ** rng.integers(-3, 4, size=(5, 4, 6))
    positions = rng.integers(0, 2, size=(5, 40, 10)).astype(np.int8)
    direct = _bpso_kernels._fitness_np(index, positions, 4, 2, 3)
    lookup = _bpso_kernels._Fitness(index, 10, 4, 2, 3, 14)(positions)
    assert direct[1].any() and not direct[1].all()
    assert lookup.tobytes() == np.where(direct[1], direct[0], -np.inf).tobytes()
    solver = BPSOSolver(2, 3, iterations=30, use_numba=False)
    by_table = solver.solve(np.abs(index), streams(index, 5))
    monkeypatch.setattr(_bpso_kernels, "FITNESS_TABLE_BYTES", 0)
    by_sum = solver.solve(np.abs(index), streams(index, 5))
    np.testing.assert_array_equal(by_table[0], by_sum[0])
    np.testing.assert_array_equal(by_table[1], by_sum[1])


def test_bpso_serial_kernel_is_taken_with_one_thread_and_gives_the_same_numbers():
    if not _bpso_kernels.HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy kernel exists")
    import numba

    index = np.random.default_rng(5).exponential(size=(12, 4, 6))
    slow = BPSOSolver(2, 3, iterations=20, use_numba=False).solve(index, streams(index, 3))
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        assert _bpso_kernels.numba_kernel() is _bpso_kernels.run_numba_serial
        serial = BPSOSolver(2, 3, iterations=20).solve(index, streams(index, 3))
    finally:
        numba.set_num_threads(threads)
    if threads > 1:
        assert _bpso_kernels.numba_kernel() is _bpso_kernels.run_numba
    parallel = BPSOSolver(2, 3, iterations=20).solve(index, streams(index, 3))
    for got in (serial, parallel):
        np.testing.assert_array_equal(got[0], slow[0])
        np.testing.assert_array_equal(got[1], slow[1])
    # two dispatchers of one source, cached under two names
    assert _bpso_kernels.run_numba.py_func.__qualname__ != _bpso_kernels.run_numba_serial.py_func.__qualname__


@pytest.mark.parametrize(
    ("shape", "counts", "population"),
    [
        ((4, 6), (2, 3), 13),  # eq19 by table; particles padded from 13 to 16
        ((3, 3), (1, 1), 1),  # one particle
        ((8, 9), (3, 4), 50),  # 17 bits: eq19 summed directly
        ((12, 12), (2, 2), 9),
    ],
)
def test_bpso_kernels_agree_by_table_and_by_direct_sum(shape, counts, population):
    """The kernels look eq19 up in a table up to TABLE_BITS bits and sum it beyond;
    both, with any population, select what the numpy kernel selects, under both rules."""
    if not _bpso_kernels.HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy kernel exists")
    assert (sum(shape) <= TABLE_BITS) == (shape == (4, 6) or shape == (3, 3))
    index = np.random.default_rng(sum(shape)).exponential(size=(9, *shape))
    for rule in ("xor", "set"):
        solvers = [
            BPSOSolver(*counts, population=population, iterations=15, rule=rule, use_numba=use)
            for use in (True, False)
        ]
        fast, slow = (solver.solve(index, streams(index, 7)) for solver in solvers)
        np.testing.assert_array_equal(fast[0], slow[0])
        np.testing.assert_array_equal(fast[1], slow[1])


@pytest.mark.parametrize("rule", ["xor", "set"])
def test_bpso_kernel_stopping_at_the_optimum_selects_what_the_whole_swarm_selects(rule):
    """The compiled kernel stops a trial once its global best holds the table's best value (no
    particle can then replace it). The paper's whole swarm (Npop = 50, q_max = 100, which the numpy
    kernel always runs) selects the same super arms, on ties too: indices drawn from {0, 1, 2}
    give several optimal super arms, of which the first one found must be kept."""
    if not _bpso_kernels.HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy kernel exists")
    rng = np.random.default_rng(23)
    ties = rng.integers(0, 3, size=(40, 4, 6)).astype(float)
    index = np.concatenate([rng.exponential(size=(40, 4, 6)), ties])
    solvers = [BPSOSolver(2, 3, rule=rule, use_numba=use) for use in (True, False)]
    fast, slow = (solver.solve(index, streams(index, 4)) for solver in solvers)
    np.testing.assert_array_equal(fast[0], slow[0])
    np.testing.assert_array_equal(fast[1], slow[1])
    etx, erx = ExactSolver(2, 3).solve(index, streams(index))
    values = np.einsum("bm,bmn,bn->b", fast[0], index, fast[1])
    best = np.einsum("bm,bmn,bn->b", etx, index, erx)
    assert (values == best).mean() > 0.4  # many trials reach the optimum, where the stop applies


@pytest.mark.parametrize(
    ("shape", "counts", "population"), [((4, 6), (2, 3), 50), ((8, 9), (3, 4), 13), ((3, 3), (1, 1), 1)]
)
def test_bpso_compiled_initial_swarm_is_the_numpy_one(shape, counts, population):
    """The compiled starting swarm hashes the draws the numpy one draws and keeps the same top
    stations: the same particles, and the streams left in the same state."""
    if not _bpso_kernels.HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy kernel exists")
    index = np.zeros((17, *shape))
    randoms = [streams(index, 8), streams(index, 8)]
    swarms = [
        BPSOSolver(*counts, population=population, use_numba=use).initial_swarm(random, *shape)
        for use, random in zip((True, False), randoms, strict=True)
    ]
    np.testing.assert_array_equal(swarms[0][0], swarms[1][0])
    np.testing.assert_array_equal(swarms[0][1], swarms[1][1])
    assert swarms[0][0].dtype == np.int8
    assert randoms[0].calls == randoms[1].calls


def test_bpso_compiled_top_stations_break_ties_as_top_mask():
    """Ties go to the lowest index, as top_mask's stable sort has them."""
    if not _bpso_kernels.HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy kernel exists")
    rng = np.random.default_rng(3)
    values = rng.integers(0, 3, size=(200, 6)).astype(float)  # many ties
    for count in range(7):
        out = np.empty((1, 200, 6), dtype=np.int8)
        _bpso_kernels._top_counts(values.ravel(), 6, count, out, 0, 0)
        np.testing.assert_array_equal(out[0].astype(bool), top_mask(values, count))


def test_bpso_fitness_table_is_eq19_of_every_pattern():
    """Every valid bit pattern's table entry is the index sum of its channels (brute force)
    where it selects Ms transmitters and Ns receivers; the others are left as they were (the
    kernel sets them to -inf once per chunk of trials); the largest entry is returned."""
    if not _bpso_kernels.HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy kernel exists")
    index = np.random.default_rng(1).normal(size=(4, 6))
    untouched = -np.inf
    table = np.full(1 << 10, untouched)
    k = _bpso_kernels
    tx_codes, rx_codes = k._valid_codes(2, 4), k._valid_codes(3, 6)
    stations = k._selected(tx_codes, 2), k._selected(rx_codes, 3)
    best = k._valid_entries(index, tx_codes, rx_codes, *stations, table)
    assert best == table.max()  # the optimum the kernel stops at
    sentinel = np.full(1 << 10, 7.5)  # invalid patterns are never written, whatever they hold
    k._valid_entries(index, tx_codes, rx_codes, *stations, sentinel)
    valid = sentinel != 7.5
    np.testing.assert_array_equal(sentinel[valid], table[valid])
    for pattern in range(1 << 10):
        bits = (pattern >> np.arange(10)) & 1
        tx, rx = bits[:4], bits[4:]
        if tx.sum() == 2 and rx.sum() == 3:
            assert table[pattern] == pytest.approx(tx @ index @ rx, rel=1e-12)
        else:
            assert table[pattern] == untouched and not valid[pattern]


def test_bpso_exp_polynomial_is_accurate():
    v = np.linspace(-6, 6, 10001)
    np.testing.assert_allclose(_bpso_kernels.exp_negative(v), np.exp(-v), rtol=1e-7)
