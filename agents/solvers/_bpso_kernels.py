"""BPSO iteration kernels: a numba one and a pure-numpy one that give the same numbers.

Both draw their random numbers from the same counter-based SplitMix64 hash of
(trial key, stream, iteration, element) and evaluate the sigmoid of eq21 with
the same sequence of +, * and / (no libm call), so nothing is computed
differently by the two paths. numba is optional (``pip install numba``);
without it the numpy kernel runs.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env.core.arrays import namespace
from mimo_radar_env.core.compiled import CHUNK, HAVE_NUMBA, numba, twins
from mimo_radar_env.core.counter_hash import Stream, element_bits, stream_bases, to_unit
from mimo_radar_env.core.superarm import all_super_arms

if HAVE_NUMBA:  # pragma: no branch
    from mimo_radar_env.core._counter_hash_kernels import element_bits_nb, stream_base_nb, to_unit_nb

# numba reads module globals as compile-time constants
_R1, _R2, _FLIP = int(Stream.BPSO_R1), int(Stream.BPSO_R2), int(Stream.BPSO_FLIP)
_C3, _C4, _C5, _C6 = 1.0 / 6.0, 1.0 / 24.0, 1.0 / 120.0, 1.0 / 720.0


def exp_negative(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``exp(-v)`` from + and * only: the Taylor polynomial of ``exp(-v/32)`` squared five times
    (relative error below 1e-7 for ``|v| <= 6``), so that numpy and numba, whose ``exp`` differ
    in the last bit, compute identical numbers."""
    y = v * (-1.0 / 32.0)
    e = 1.0 + y * (1.0 + y * (0.5 + y * (_C3 + y * (_C4 + y * (_C5 + y * _C6)))))
    for _ in range(5):
        e = e * e
    return e


def _flip_uniform_np(
    base: NDArray[np.uint64], element: NDArray[np.uint64], shift: NDArray[np.uint64]
) -> NDArray[np.float64]:
    """16-bit uniforms, four per hash: ``(lane + 0.5) / 65536``."""
    xp = namespace(base)
    # the lane's 16 bits are below the shift's top (at most 48): an arithmetic shift of torch's
    # int64 words keeps them as numpy's logical one does
    lane = (element_bits(base, element) >> shift) & xp.word(0xFFFF)
    return (xp.astype(lane, np.float64) + 0.5) * (1.0 / 65536.0)


#: The most memory the draws of a block of iterations take (r1, r2 and the flips): on torch where
#: every trial runs every iteration (a CUDA graph) a block's draws are a few kernels, so the fewer
#: blocks the fewer launches; elsewhere, arrays that stay in the caches are the faster (measured:
#: 128 MiB blocks slowed the 500-trial kernel), and draws made far ahead are wasted on the trials
#: that stop at their optimum.
DRAW_BLOCK_BYTES = {"torch": 128 * 2**20, "numpy": 4 * 2**20}


def run_numpy(
    index: NDArray[np.float64],
    tx_count: int,
    rx_count: int,
    positions: NDArray[np.int8],
    keys: NDArray[np.uint64],
    iterations: int,
    c1: float,
    c2: float,
    inertia_start: float,
    inertia_end: float,
    velocity_clamp: float,
    set_rule: bool,
    table_bits: int,
    stop_at_optimum: bool = True,
    iterate: Callable[..., tuple[Any, ...]] | None = None,
) -> NDArray[np.int8]:
    """The iterations, vectorised over trials and particles. Returns the global bests (B, L).

    With ``stop_at_optimum`` and eq19's table (:class:`_Fitness`: particles of at most
    ``table_bits`` bits, where it fits in memory), a trial leaves the
    swarm's arrays once its global best holds the largest value any valid super arm has, as the
    compiled kernel stops it: a best is replaced only by a strictly larger fitness, so no later
    iteration could change it, and each trial's draws are its own, so the others go on as they
    would have. Without it every trial runs every iteration, with no shape that depends on the
    data: what a CUDA graph captures. ``iterate`` runs an iteration in place of
    :func:`swarm_iteration`, with its arguments (its compiled twin:
    :class:`~mimo_radar_env.envs.device_forms.CompiledFunction`)."""
    xp = namespace(index)
    batch, population, length = positions.shape
    fitness_of = _Fitness(index, length, index.shape[1], tx_count, rx_count, table_bits)
    swarm = _Swarm(positions, fitness_of)
    draws = _Draws(keys, population, length, iterations, xp.is_torch and not stop_at_optimum, c1, c2)
    # omega of each iteration, linear from the first to the last (a 0-d array each: one compiled
    # iteration serves them all); the same operations as on Python floats, so the same numbers
    steps = xp.arange(iterations, dtype=np.float64)
    inertias = list(inertia_start - (inertia_start - inertia_end) * steps / max(iterations - 1, 1))
    iterate = iterate or swarm_iteration
    constants = {"clamp": velocity_clamp, "set_rule": set_rule, "counts": fitness_of.counts}
    optimum = fitness_of.optimum if stop_at_optimum else None
    result, alive = None, None  # the bests of the trials that stopped; the rows still iterating
    for q in range(iterations):
        arrays = (*swarm.state, swarm.rows, *draws.at(q), inertias[q], *fitness_of.arrays)
        swarm.state = iterate(*arrays, **constants)
        if optimum is None or q == iterations - 1:
            continue
        final = swarm.global_fit >= optimum
        if not bool(final.any()):
            continue
        if result is None:
            result, alive = xp.copy(swarm.global_best), xp.arange(batch)
        result[alive[final]] = swarm.global_best[final]
        keep = ~final
        if not bool(keep.any()):
            return result
        alive, optimum = alive[keep], optimum[keep]
        for part in (swarm, draws, fitness_of):
            part.keep(keep)
    if result is None:
        return swarm.global_best
    result[alive] = swarm.global_best
    return result


class _Swarm:
    """The particles of every trial still iterating, their rows 0..B-1, and their ``state`` in
    :func:`swarm_iteration`'s order: positions and velocities (B, P, L), personal bests (B, P, L)
    and their fitness (B, P), the global best (B, L) and its fitness (B,)."""

    def __init__(self, positions: NDArray[np.int8], fitness_of: _Fitness) -> None:
        xp = self.xp = namespace(positions)
        personal_fit = fitness_of(positions)
        self.rows = xp.arange(positions.shape[0])
        first = xp.argmax(personal_fit, axis=1)
        self.state: tuple[Any, ...] = (
            xp.copy(positions),
            xp.zeros(positions.shape),
            xp.copy(positions),
            personal_fit,
            xp.copy(positions[self.rows, first]),
            xp.copy(personal_fit[self.rows, first]),
        )

    @property
    def global_best(self) -> Any:
        return self.state[4]

    @property
    def global_fit(self) -> Any:
        return self.state[5]

    def keep(self, rows: Any) -> None:
        self.state = tuple(part[rows] for part in self.state)
        self.rows = self.xp.arange(self.state[0].shape[0])


def swarm_iteration(
    positions: Any,
    velocities: Any,
    personal_best: Any,
    personal_fit: Any,
    global_best: Any,
    global_fit: Any,
    rows: Any,
    c1_r1: Any,
    c2_r2: Any,
    u: Any,
    inertia: Any,
    *fitness_arrays: Any,
    clamp: float,
    set_rule: bool,
    counts: tuple[int, int, int],
) -> tuple[Any, ...]:
    """One iteration, a function of arrays: eq20's velocities (``c1 r1`` and ``c2 r2`` as drawn,
    :class:`_Draws`; ``inertia`` a 0-d array), eq21's positions, then the bests. Returns the new
    state, its first six arguments; ``rows`` is 0..B-1, ``fitness_arrays`` and ``counts`` eq19's
    (:func:`fitness`)."""
    xp = namespace(positions)
    velocities = (
        inertia * velocities
        + c1_r1[..., None] * (personal_best - positions)
        + c2_r2[..., None] * (global_best[:, None, :] - positions)
    )  # eq20
    velocities = xp.clip(velocities, -clamp, clamp)
    draw = u * (1.0 + exp_negative(velocities)) < 1.0  # u < sigmoid(V)
    if set_rule:  # Kennedy-Eberhart: the bit is 1 with probability sigmoid(V)
        positions = xp.astype(draw, np.int8)
    else:  # eq21 as written: the bit flips with probability sigmoid(V)
        positions = xp.astype(xp.where(draw, 1 - positions, positions), np.int8)
    # an invalid position's fitness is -inf, so it improves on nothing; and a best is replaced
    # only by a larger fitness, so each best's fitness is the larger of the two (never NaN:
    # the index is finite)
    value = fitness(positions, *fitness_arrays, counts=counts)
    improved = value > personal_fit
    personal_best = xp.where(improved[..., None], positions, personal_best)
    personal_fit = xp.maximum(value, personal_fit)
    candidate = xp.argmax(personal_fit, axis=1)
    candidate_fit = personal_fit[rows, candidate]
    better = candidate_fit > global_fit
    global_best = xp.where(better[:, None], personal_best[rows, candidate], global_best)
    global_fit = xp.maximum(candidate_fit, global_fit)
    return positions, velocities, personal_best, personal_fit, global_best, global_fit


class _Draws:
    """The iterations' random numbers, which depend on no state: r1, r2 per particle and the
    16-bit flip uniforms per bit, hashed for a block of iterations at once (a few operations a
    block instead of a few dozen an iteration), blocks sized to DRAW_BLOCK_BYTES (``whole_blocks``:
    the torch budget, where every trial runs every iteration)."""

    def __init__(
        self,
        keys: Any,
        population: int,
        length: int,
        iterations: int,
        whole_blocks: bool,
        c1: float,
        c2: float,
    ) -> None:
        xp = self.xp = namespace(keys)
        self.c1, self.c2 = c1, c2
        batch = keys.shape[0]
        self.iterations = iterations
        # row q is iteration q's stream_base: r1's and r2's stacked (2, q_max, B), hashed together;
        # iteration-major, so that each iteration's draws are contiguous, laid out alike in any block
        r_streams = (Stream.BPSO_R1, Stream.BPSO_R2)
        self.r_bases = xp.stack([stream_bases(keys, s, iterations).T for s in r_streams])
        self.flip_bases = xp.ascontiguousarray(stream_bases(keys, Stream.BPSO_FLIP, iterations).T)
        self.particle = xp.arange(population, dtype=np.int64)[None, :]
        lanes = (length + 3) // 4
        bit = xp.arange(length, dtype=np.int64)
        self.hash_element = (xp.arange(population, dtype=np.int64)[:, None] * lanes + bit // 4)[
            None
        ]  # (1, P, L)
        self.lane_shift = xp.words(16 * (bit % 4)) if not xp.is_torch else 16 * (bit % 4)
        budget = DRAW_BLOCK_BYTES["torch" if whole_blocks else "numpy"]
        self.block = int(np.clip(budget // (8 * batch * population * (2 + length)), 1, iterations))
        self.drawn_for: Any = None  # the block's rows of the trials left, where some stopped since

    def at(self, q: int) -> tuple[Any, Any, Any]:
        """Iteration ``q``'s ``c1 r1`` and ``c2 r2`` (B, P), each product as eq20 forms it (made
        for a block at once), and its flip uniforms (B, P, L)."""
        block = self.block
        if q % block == 0:
            drawn = slice(q, min(q + block, self.iterations))
            r1, r2 = to_unit(element_bits(self.r_bases[:, drawn, :, None], self.particle))  # (Q, B, P)
            self.r_block = (self.c1 * r1, self.c2 * r2)
            self.u_block = _flip_uniform_np(
                self.flip_bases[drawn, :, None, None], self.hash_element, self.lane_shift
            )
            self.drawn_for = None
        c1_r1, c2_r2 = self.r_block
        if self.drawn_for is None:
            return c1_r1[q % block], c2_r2[q % block], self.u_block[q % block]
        rows = self.drawn_for
        return c1_r1[q % block][rows], c2_r2[q % block][rows], self.u_block[q % block][rows]

    def keep(self, rows: Any) -> None:
        self.r_bases, self.flip_bases = self.r_bases[:, :, rows], self.flip_bases[:, rows]
        # the block's draws stay as drawn, read through the rows of the trials left (not copied)
        self.drawn_for = (
            self.xp.arange(rows.shape[0])[rows] if self.drawn_for is None else self.drawn_for[rows]
        )


class _Fitness:
    """eq19 of a swarm's positions (B, P, L), -inf where a position is not a valid super arm (a
    call), as the compiled kernel's table holds it: looked up in a
    table of every bit pattern's value per trial (:func:`_fitness_np` of each valid pattern, so
    the same numbers) for particles of at most ``table_bits`` bits where it fits
    FITNESS_TABLE_BYTES, a few operations an iteration instead of one a channel; else summed
    directly. With the table, ``optimum`` is each trial's largest value of a valid pattern (else
    None), and :meth:`keep` keeps the rows of the trials still iterating."""

    def __init__(
        self,
        index: NDArray[np.float64],
        length: int,
        num_tx: int,
        tx_count: int,
        rx_count: int,
        table_bits: int,
    ) -> None:
        xp = namespace(index)
        self.index, self.counts = index, (num_tx, tx_count, rx_count)
        self.table: Any = None
        self.optimum: Any = None
        batch, channels = index.shape[0], index.shape[1] * index.shape[2]
        table_bytes = 8 * batch << length
        if length > table_bits or table_bytes > FITNESS_TABLE_BYTES:
            return
        # only the valid patterns are summed (a tenth of them at the paper's 4 x 6): the others are 0
        valid_codes = _valid_patterns(num_tx, index.shape[2], tx_count, rx_count)
        if table_bytes + 8 * batch * len(valid_codes) * channels > FITNESS_TABLE_BYTES:
            return
        bit = xp.arange(length, dtype=np.int64)
        codes = xp.constant(valid_codes)
        values, _ = _fitness_np(index, xp.astype((codes[:, None] >> bit) & 1, np.int8)[None], *self.counts)
        self.table = xp.full((batch, 1 << length), -np.inf, dtype=values.dtype)  # (B, C)
        self.table[:, codes] = values
        self.optimum = xp.max(values, axis=1)
        self.weights = 1 << bit  # bit j of a pattern is station j

    @property
    def arrays(self) -> tuple[Any, ...]:
        """:func:`fitness`'s arrays: the table and its weights, or the index."""
        return (self.index,) if self.table is None else (self.table, self.weights)

    def __call__(self, positions: NDArray[np.int8]) -> NDArray[np.float64]:
        return fitness(positions, *self.arrays, counts=self.counts)

    def keep(self, rows: Any) -> None:
        self.index = self.index[rows]
        if self.table is not None:
            self.table, self.optimum = self.table[rows], self.optimum[rows]


def fitness(positions: Any, *arrays: Any, counts: tuple[int, int, int]) -> Any:
    """eq19 of positions (B, P, L), -inf where one is not a valid super arm: looked up in the
    table of every bit pattern's value (``arrays``: the table (B, 2^L) and the weights 2^j of the
    bits), or summed from the index (``arrays``: the index (B, M, N); ``counts``: M, Ms, Ns)."""
    xp = namespace(positions)
    if len(arrays) == 1:
        value, valid = _fitness_np(arrays[0], positions, *counts)
        return xp.where(valid, value, -np.inf)
    table, weights = arrays
    code = (positions * weights).sum(axis=-1)  # (B, P), int64 as the weights
    return xp.take_along_axis(table, code, axis=1)


@functools.cache
def _valid_patterns(num_tx: int, num_rx: int, tx_count: int, rx_count: int) -> tuple[int, ...]:
    """The bit patterns (bit j: station j, transmitters first) of every super arm, ascending."""
    tx, rx = all_super_arms(num_tx, num_rx, tx_count, rx_count)
    bits = np.concatenate([tx, rx], axis=1).astype(np.int64) << np.arange(num_tx + num_rx)
    return tuple(sorted(bits.sum(axis=1).tolist()))


#: The most memory eq19's table may take: a value per bit pattern and trial, and the terms it is
#: summed from (one a channel, valid pattern and trial); a larger batch sums each particle's
#: channels directly.
FITNESS_TABLE_BYTES = 256 * 2**20


def _fitness_np(
    index: NDArray[np.float64], positions: NDArray[np.int8], num_tx: int, tx_count: int, rx_count: int
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """eq19: index sum over the selected channels (summed TX-major, as the numba kernel), 0 if
    invalid; ``positions`` (B, P, L), or (1, P, L) for the same patterns in every trial."""
    xp = namespace(index)
    tx = xp.astype(positions[..., :num_tx], np.float64)
    rx = xp.astype(positions[..., num_tx:], np.float64)
    tx_ok = positions[..., :num_tx].sum(axis=-1) == tx_count
    valid = tx_ok & (positions[..., num_tx:].sum(axis=-1) == rx_count)
    terms = tx[..., :, None] * rx[..., None, :] * index[:, None]  # (B, P, M, N): tx_m rx_n I_mn
    value = xp.zeros(terms.shape[:2])
    # a loop over the channels (not trials or particles), m-major, fixes the summation order
    for term in xp.moveaxis(terms.reshape(*terms.shape[:2], -1), -1, 0):
        value += term
    return xp.where(valid, value, 0.0), valid


#: Particles are padded to a multiple of this (the vector width of float64 on AVX-512), so that
#: the inner loops have no scalar remainder; padded particles never enter a best.
LANES = 8


if HAVE_NUMBA:  # pragma: no branch

    @numba.njit(cache=True)
    def _valid_codes(count, stations):
        """The bit patterns of ``stations`` bits with exactly ``count`` bits set, ascending."""
        codes = np.empty(1 << stations, dtype=np.int64)
        found = 0
        for code in range(1 << stations):
            ones = 0
            for bit in range(stations):
                ones += (code >> bit) & 1
            if ones == count:
                codes[found] = code
                found += 1
        return codes[:found]

    @numba.njit(cache=True)
    def _selected(codes, count):
        """The stations (ascending) of each bit pattern of ``codes``, (len(codes), count)."""
        stations = np.empty((codes.shape[0], count), dtype=np.int64)
        for i in range(codes.shape[0]):
            found = 0
            bit = 0
            while found < count:
                if (codes[i] >> bit) & 1:
                    stations[i, found] = bit
                    found += 1
                bit += 1
        return stations

    @numba.njit(cache=True)
    def _valid_entries(index, tx_codes, rx_codes, tx_selected, rx_selected, table):
        """Writes eq19 of every valid bit pattern of one trial into ``table`` (bit j of a pattern
        is station j, transmitters first; ``*_selected``: :func:`_selected` of the codes) and
        returns the largest. A valid pattern's sum runs over its selected channels TX-major, the
        order in which the direct sum adds them (the other terms it adds are zeros), so both give
        the same number."""
        num_tx = index.shape[0]
        best = -np.inf
        for a in range(tx_codes.shape[0]):
            for c in range(rx_codes.shape[0]):
                total = 0.0
                for m in tx_selected[a]:
                    for n in rx_selected[c]:
                        total += index[m, n]
                table[tx_codes[a] | (rx_codes[c] << num_tx)] = total
                if total > best:
                    best = total
        return best

    @numba.njit(cache=True)
    def _top_counts(values, stations, count, out, b, offset):
        """``out[b, p, offset + i] = 1`` where ``values[p * stations + i]`` is among the ``count``
        largest of particle ``p``'s ``stations`` values (ties: the lowest index first, as
        ``top_mask``'s stable sort), 0 elsewhere."""
        for p in range(out.shape[1]):
            row = p * stations
            for i in range(stations):
                vi = values[row + i]
                above = 0
                for j in range(stations):
                    vj = values[row + j]
                    above += (vj > vi) | ((j < i) & (vj == vi))  # branch-free: the draws are random
                out[b, p, offset + i] = 1 if above < count else 0

    @numba.njit(cache=True)
    def initial_positions(tx_bases, rx_bases, population, num_tx, num_rx, tx_count, rx_count):
        """The starting swarm (B, population, M + N) int8 that ``BPSOSolver.initial_swarm``
        builds with numpy: particle ``p``'s transmitters are the ``tx_count`` largest of the
        uniforms at flat indices ``p * M .. p * M + M - 1`` of the transmitters' draw (bases
        ``tx_bases``), its receivers likewise; the same hashes, so the same particles."""
        batch = tx_bases.shape[0]
        positions = np.empty((batch, population, num_tx + num_rx), dtype=np.int8)
        tx_values = np.empty(population * num_tx)
        rx_values = np.empty(population * num_rx)
        for b in range(batch):
            for i in range(population * num_tx):
                tx_values[i] = to_unit_nb(element_bits_nb(tx_bases[b], i))
            for i in range(population * num_rx):
                rx_values[i] = to_unit_nb(element_bits_nb(rx_bases[b], i))
            _top_counts(tx_values, num_tx, tx_count, positions, b, 0)
            _top_counts(rx_values, num_rx, rx_count, positions, b, num_tx)
        return positions

    def _run_numba(
        index,
        tx_count,
        rx_count,
        positions,
        keys,
        iterations,
        c1,
        c2,
        inertia_start,
        inertia_end,
        velocity_clamp,
        set_rule,
        table_bits,
    ):
        """Same numbers as :func:`run_numpy`. Per trial, the swarm is laid out (bit, particle) in
        float64 (positions are 0 or 1, exact), particles padded to :data:`LANES`, so that every
        inner loop runs over particles with one type and vectorises; eq19 is a table lookup
        (:func:`_valid_entries`) for particles of at most ``table_bits`` bits. With the table,
        a trial stops once its global best holds the table's largest value: a best is replaced
        only by a strictly larger fitness, so no later iteration could change it (the numpy
        kernel stops its trials likewise and selects the same)."""
        batch, population, length = positions.shape
        num_tx = index.shape[1]
        num_rx = index.shape[2]
        lanes = (length + 3) // 4
        width = (population + LANES - 1) // LANES * LANES
        steps = max(iterations - 1, 1)
        by_table = length <= table_bits
        tx_codes = _valid_codes(tx_count, num_tx if by_table else 0)
        rx_codes = _valid_codes(rx_count, num_rx if by_table else 0)
        tx_selected = _selected(tx_codes, tx_count)
        rx_selected = _selected(rx_codes, rx_count)
        weight = np.empty(length)
        for j in range(length):
            weight[j] = 2.0**j
        result = np.empty((batch, length), dtype=np.int8)
        chunks = (batch + CHUNK - 1) // CHUNK
        for chunk in numba.prange(chunks):
            # scratch space shared by the chunk's trials; the table's invalid patterns stay -inf
            table = np.full(1 << length if by_table else 0, -np.inf)
            position = np.empty((length, width))
            velocity = np.empty((length, width))
            personal_best = np.empty((length, width))
            uniform = np.empty((length, width))
            a1 = np.empty(width)
            a2 = np.empty(width)
            code = np.empty(width)
            fitness = np.empty(population)
            personal_fit = np.empty(population)
            global_best = np.empty(length)
            for b in range(chunk * CHUNK, min(batch, (chunk + 1) * CHUNK)):
                # the trial's swarm: its particles, zero velocity; its table's valid entries
                optimum = np.inf  # no table: only an infinite fitness is final
                if by_table:
                    # the best value a valid particle can have: once the global best holds it, no
                    # particle can be strictly better, so the global best is final and the trial stops
                    optimum = _valid_entries(index[b], tx_codes, rx_codes, tx_selected, rx_selected, table)
                for j in range(length):
                    for p in range(width):
                        d = np.float64(positions[b, p, j]) if p < population else 0.0
                        position[j, p] = d
                        personal_best[j, p] = d
                        velocity[j, p] = 0.0
                    global_best[j] = 0.0
                global_fit = -np.inf
                key = keys[b]
                for q in range(iterations + 1):
                    if q > 0:
                        it = q - 1
                        inertia = inertia_start - (inertia_start - inertia_end) * it / steps
                        base_r1 = stream_base_nb(key, _R1, it)
                        base_r2 = stream_base_nb(key, _R2, it)
                        base_flip = stream_base_nb(key, _FLIP, it)
                        for p in range(width):
                            a1[p] = c1 * to_unit_nb(element_bits_nb(base_r1, p))
                            a2[p] = c2 * to_unit_nb(element_bits_nb(base_r2, p))
                        # the eq21 draws: four 16-bit uniforms per hash, bit j in lane j // 4
                        for lane in range(lanes):
                            for p in range(width):
                                bits = element_bits_nb(base_flip, p * lanes + lane)
                                for s in range(4):  # a constant trip count: the loop over p vectorises
                                    if 4 * lane + s < length:
                                        lane_bits = (bits >> np.uint64(16 * s)) & np.uint64(0xFFFF)
                                        u = (np.float64(lane_bits) + 0.5) * (1.0 / 65536.0)
                                        uniform[4 * lane + s, p] = u
                        for j in range(length):
                            best_bit = global_best[j]
                            for p in range(width):
                                d = position[j, p]
                                v = inertia * velocity[j, p] + a1[p] * (personal_best[j, p] - d)
                                v = v + a2[p] * (best_bit - d)  # eq20
                                v = min(max(v, -velocity_clamp), velocity_clamp)
                                velocity[j, p] = v
                                y = v * (-1.0 / 32.0)
                                e = 1.0 + y * (1.0 + y * (0.5 + y * (_C3 + y * (_C4 + y * (_C5 + y * _C6)))))
                                e = e * e
                                e = e * e
                                e = e * e
                                e = e * e
                                e = e * e
                                hit = uniform[j, p] * (1.0 + e) < 1.0  # u < sigmoid(V), eq21
                                if set_rule:
                                    position[j, p] = 1.0 if hit else 0.0
                                else:
                                    position[j, p] = (1.0 - d) if hit else d
                    if by_table:
                        for p in range(width):
                            code[p] = 0.0
                        for j in range(length):
                            w = weight[j]
                            for p in range(width):
                                code[p] += position[j, p] * w
                        for p in range(population):
                            fitness[p] = table[np.int64(code[p])]
                    else:  # eq19 summed as _fitness_np sums it, -inf where the cardinality is broken
                        for p in range(population):
                            fitness[p] = 0.0
                        for m in range(num_tx):
                            for n in range(num_rx):
                                w = index[b, m, n]
                                for p in range(population):
                                    fitness[p] += position[m, p] * position[num_tx + n, p] * w
                        for p in range(population):
                            ct = 0.0
                            for m in range(num_tx):
                                ct += position[m, p]
                            cr = 0.0
                            for n in range(num_rx):
                                cr += position[num_tx + n, p]
                            if ct != tx_count or cr != rx_count:
                                fitness[p] = -np.inf
                    if q == 0:
                        for p in range(population):
                            personal_fit[p] = fitness[p]
                    else:
                        for p in range(population):
                            if fitness[p] > personal_fit[p]:
                                personal_fit[p] = fitness[p]
                                for j in range(length):
                                    personal_best[j, p] = position[j, p]
                    best = 0
                    for p in range(1, population):
                        if personal_fit[p] > personal_fit[best]:
                            best = p
                    if q == 0 or personal_fit[best] > global_fit:
                        global_fit = personal_fit[best]
                        for j in range(length):
                            global_best[j] = personal_best[j, best]
                    if global_fit >= optimum:
                        break
                for j in range(length):
                    result[b, j] = np.int8(global_best[j])
        return result

    #: Trials spread over numba's threads (``prange``), and the same kernel for one thread (a
    #: harness worker): ``prange`` is ``range`` there, the numbers are the same, and it compiles
    #: in about half the time of the parallel one.
    run_numba_serial, run_numba = twins(_run_numba, ("run_numba_serial", "run_numba"))


def numba_kernel(threads: int | None = None) -> Any:
    """The compiled kernel for ``threads`` numba threads (default: the current count): the serial
    one with one thread, so that a worker process compiles only what it runs."""
    return run_numba_serial if (threads or numba.get_num_threads()) == 1 else run_numba
