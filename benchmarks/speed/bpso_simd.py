"""A candidate BPSO kernel laid out for SIMD (not yet the agents' kernel): a numba one and a
pure-numpy one that give the same numbers.

``python -m benchmarks.speed.solver_speed`` times it beside the agents' kernel
(``agents.solvers._bpso_kernels``). It draws different random numbers (float32 and a different
element layout), so adopting it re-records every number that depends on BPSO; it is kept here,
measured and tested, until it meets its speed target.

Trials are the innermost (vector) axis: a compiled chunk of :data:`CHUNK` trials holds
positions, velocities and personal bests as float32 arrays ``(bit, particle, trial)``, so every
loop of an iteration (the random draws, eq20, eq21, the cardinality checks, eq19 and the best
updates) runs branch-free over contiguous trials. Positions, velocities and the draws are
float32 (they are 0/1, bounded by the clamp and uniforms); eq19's index sums stay float64, so
two super arms whose indices differ in the eighth digit are still told apart.

Random numbers come from the counter-based SplitMix64 hash of (per-call trial key, stream,
iteration, element), which vectorises over trials: ``r1``, ``r2`` one 24-bit uniform per
particle and iteration, the eq21 draws four 16-bit uniforms per hash, the initial particles one
64-bit score per bit (the ``Ms``/``Ns`` largest are selected). The sigmoid of eq21 is evaluated
with the same sequence of float32 ``+`` and ``*`` in both kernels (no libm call), so nothing is
computed differently by the two paths. numba is optional (``pip install numba``); without it
the numpy kernel runs.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env.core.compiled import HAVE_NUMBA, numba
from mimo_radar_env.core.counter_hash import Stream, element_bits, stream_base

if HAVE_NUMBA:  # pragma: no branch
    from mimo_radar_env.core.counter_hash import element_bits_nb, stream_base_nb

#: Trials per compiled chunk (the vector axis); chunks run in parallel.
CHUNK = 64

# numba reads module globals as compile-time constants
_R1, _R2, _FLIP, _INIT = (
    int(Stream.BPSO_R1),
    int(Stream.BPSO_R2),
    int(Stream.BPSO_FLIP),
    int(Stream.BPSO_INIT),
)
_F32 = np.float32
_C2, _C3, _C4, _C5, _C6 = _F32(0.5), _F32(1.0 / 6.0), _F32(1.0 / 24.0), _F32(1.0 / 120.0), _F32(1.0 / 720.0)
_ONE, _ZERO, _SCALE = _F32(1.0), _F32(0.0), _F32(-1.0 / 32.0)
_HALF, _UNIT16, _UNIT24 = _F32(0.5), _F32(2.0**-16), _F32(2.0**-24)
_MASK16 = np.uint64(0xFFFF)
_SHIFT24 = np.uint64(40)


def exp_negative(v: NDArray[np.float32]) -> NDArray[np.float32]:
    """``exp(-v)`` in float32 from + and * only: the Taylor polynomial of ``exp(-v/32)`` squared
    five times (relative error below 1e-5 for ``|v| <= 6``), so that numpy and numba compute
    identical numbers."""
    y = v.astype(np.float32) * _SCALE
    e = _ONE + y * (_ONE + y * (_C2 + y * (_C3 + y * (_C4 + y * (_C5 + y * _C6)))))
    for _ in range(5):
        e = e * e
    return e


def _inertia(q: int, iterations: int, start: float, end: float) -> np.float32:
    """omega at iteration ``q``: linear from ``start`` to ``end`` (computed in float64)."""
    return _F32(start - (start - end) * q / max(iterations - 1, 1))


def _uniform24(bits: NDArray[np.uint64]) -> NDArray[np.float32]:
    return (bits >> _SHIFT24).astype(np.float32) * _UNIT24


def _initial_positions(
    keys: NDArray[np.uint64], population: int, num_tx: int, num_rx: int, tx_count: int, rx_count: int
) -> NDArray[np.float32]:
    """(B, L, P) valid super arms: the ``Ms`` (``Ns``) largest scores of each particle's TX (RX)
    bits, ties to the lower index."""
    length = num_tx + num_rx
    element = (np.arange(population)[None, :] * length + np.arange(length)[:, None]).astype(np.uint64)
    score = element_bits(stream_base(keys, _INIT, 0)[:, None, None], element)  # (B, L, P)
    position = np.zeros(score.shape, dtype=np.float32)
    for low, high, count in ((0, num_tx, tx_count), (num_tx, length, rx_count)):
        order = np.argsort(~score[:, low:high], axis=1, kind="stable")[:, :count]  # descending
        np.put_along_axis(position[:, low:high], order, _ONE, axis=1)
    return position


def run_numpy(
    index: NDArray[np.float64],
    tx_count: int,
    rx_count: int,
    keys: NDArray[np.uint64],
    population: int,
    iterations: int,
    c1: float,
    c2: float,
    inertia_start: float,
    inertia_end: float,
    velocity_clamp: float,
    set_rule: bool = False,
) -> NDArray[np.int8]:
    """All iterations, vectorised over trials and particles. Returns the global bests (B, L)."""
    batch, num_tx, num_rx = index.shape
    length = num_tx + num_rx
    quads = (length + 3) // 4
    rows = np.arange(batch)
    particle = np.arange(population, dtype=np.uint64)
    quad_element = particle[None, :] * quads + np.arange(quads, dtype=np.uint64)[:, None]  # (Q, P)
    lane_shift = (16 * np.arange(4)).astype(np.uint64)
    clamp = _F32(velocity_clamp)
    position = _initial_positions(keys, population, num_tx, num_rx, tx_count, rx_count)
    velocity = np.zeros_like(position)
    personal_best = position.copy()
    personal_fit = np.full((batch, population), -np.inf)
    global_best = np.zeros((batch, length), dtype=np.float32)
    global_fit = np.full(batch, -np.inf)
    for q in range(iterations + 1):
        if q > 0:
            it = q - 1
            inertia = _inertia(it, iterations, inertia_start, inertia_end)
            a1 = _F32(c1) * _uniform24(element_bits(stream_base(keys, _R1, it)[:, None], particle))[:, None]
            a2 = _F32(c2) * _uniform24(element_bits(stream_base(keys, _R2, it)[:, None], particle))[:, None]
            bits = element_bits(stream_base(keys, _FLIP, it)[:, None, None], quad_element)  # (B, Q, P)
            lanes = (bits[:, :, None, :] >> lane_shift[None, None, :, None]) & _MASK16  # (B, Q, 4, P)
            u = (lanes.astype(np.float32) + _HALF) * _UNIT16
            u = u.reshape(batch, 4 * quads, population)[:, :length]
            v = inertia * velocity + a1 * (personal_best - position)
            v = v + a2 * (global_best[:, :, None] - position)  # eq20
            velocity = np.minimum(np.maximum(v, -clamp), clamp)
            hit = u * (_ONE + exp_negative(velocity)) < _ONE  # u < sigmoid(V)
            if set_rule:  # Kennedy-Eberhart: the bit is 1 with probability sigmoid(V)
                position = np.where(hit, _ONE, _ZERO)
            else:  # eq21 as written: the bit flips with probability sigmoid(V)
                position = np.where(hit, _ONE - position, position)
        tx_ok = position[:, :num_tx].sum(axis=1) == tx_count  # sums of 0/1: exact in any order
        valid = tx_ok & (position[:, num_tx:].sum(axis=1) == rx_count)
        bit = position.astype(np.float64)
        fit = np.zeros((batch, population))
        for m in range(num_tx):  # eq19 as sum_m x_m (sum_n y_n w_mn), in the compiled kernel's order
            row = np.zeros((batch, population))
            for n in range(num_rx):
                row = row + bit[:, num_tx + n] * index[:, m, n, None]
            fit = fit + bit[:, m] * row
        improved = valid & (fit > personal_fit)
        personal_fit = np.where(improved, fit, personal_fit)
        personal_best = np.where(improved[:, None, :], position, personal_best)
        candidate = np.argmax(personal_fit, axis=1)
        better = personal_fit[rows, candidate] > global_fit
        global_best = np.where(better[:, None], personal_best[rows, :, candidate], global_best)
        global_fit = np.where(better, personal_fit[rows, candidate], global_fit)
    return global_best.astype(np.int8)


if HAVE_NUMBA:  # pragma: no branch

    @numba.njit(cache=True)
    def _chunk(
        index,
        keys,
        out,
        tx_count,
        rx_count,
        population,
        iterations,
        c1,
        c2,
        inertia_start,
        inertia_end,
        velocity_clamp,
        set_rule,
    ):
        """One chunk of trials, arrays (bit, particle, trial): the same numbers as run_numpy."""
        trials, num_tx, num_rx = index.shape
        length = num_tx + num_rx
        quads = (length + 3) // 4
        clamp = _F32(velocity_clamp)
        fc1 = _F32(c1)
        fc2 = _F32(c2)
        steps = max(iterations - 1, 1)
        weight = np.empty((num_tx, num_rx, trials))
        for t in range(trials):
            for m in range(num_tx):
                for n in range(num_rx):
                    weight[m, n, t] = index[t, m, n]
        position = np.zeros((length, population, trials), dtype=np.float32)
        base = np.empty(trials, dtype=np.uint64)
        base2 = np.empty(trials, dtype=np.uint64)
        score = np.empty((length, trials), dtype=np.uint64)
        chosen = np.empty(trials, dtype=np.int64)
        for t in range(trials):
            base[t] = stream_base_nb(keys[t], _INIT, 0)
        for p in range(population):
            for j in range(length):
                for t in range(trials):
                    score[j, t] = element_bits_nb(base[t], p * length + j)
            for low, high, count in ((0, num_tx, tx_count), (num_tx, length, rx_count)):
                for _ in range(count):
                    for t in range(trials):
                        chosen[t] = -1
                    for j in range(low, high):
                        for t in range(trials):
                            if position[j, p, t] == _ZERO and (
                                chosen[t] < 0 or score[j, t] > score[chosen[t], t]
                            ):
                                chosen[t] = j
                    for t in range(trials):
                        position[chosen[t], p, t] = _ONE
        velocity = np.zeros((length, population, trials), dtype=np.float32)
        personal_best = position.copy()
        personal_fit = np.full((population, trials), -np.inf)
        global_best = np.zeros((length, trials), dtype=np.float32)
        global_fit = np.full(trials, -np.inf)
        a1 = np.empty((population, trials), dtype=np.float32)
        a2 = np.empty((population, trials), dtype=np.float32)
        u = np.empty((4 * quads, population, trials), dtype=np.float32)
        count_tx = np.empty((population, trials), dtype=np.float32)
        count_rx = np.empty((population, trials), dtype=np.float32)
        fit = np.empty((population, trials))
        row = np.empty((population, trials))
        bit = np.empty((length, population, trials))
        improved = np.empty((population, trials), dtype=np.bool_)
        best_fit = np.empty(trials)
        for q in range(iterations + 1):
            if q > 0:
                it = q - 1
                inertia = _F32(inertia_start - (inertia_start - inertia_end) * it / steps)
                for t in range(trials):
                    base[t] = stream_base_nb(keys[t], _R1, it)
                    base2[t] = stream_base_nb(keys[t], _R2, it)
                for p in range(population):
                    for t in range(trials):
                        a1[p, t] = fc1 * (_F32(element_bits_nb(base[t], p) >> _SHIFT24) * _UNIT24)
                        a2[p, t] = fc2 * (_F32(element_bits_nb(base2[t], p) >> _SHIFT24) * _UNIT24)
                for t in range(trials):
                    base[t] = stream_base_nb(keys[t], _FLIP, it)
                for k in range(quads):
                    for p in range(population):
                        for t in range(trials):
                            h = element_bits_nb(base[t], p * quads + k)
                            u[4 * k, p, t] = (_F32(h & _MASK16) + _HALF) * _UNIT16
                            u[4 * k + 1, p, t] = (_F32((h >> np.uint64(16)) & _MASK16) + _HALF) * _UNIT16
                            u[4 * k + 2, p, t] = (_F32((h >> np.uint64(32)) & _MASK16) + _HALF) * _UNIT16
                            u[4 * k + 3, p, t] = (_F32(h >> np.uint64(48)) + _HALF) * _UNIT16
                for j in range(length):
                    for p in range(population):
                        for t in range(trials):
                            d = position[j, p, t]
                            v = inertia * velocity[j, p, t] + a1[p, t] * (personal_best[j, p, t] - d)
                            v = v + a2[p, t] * (global_best[j, t] - d)
                            v = min(max(v, -clamp), clamp)
                            velocity[j, p, t] = v
                            y = v * _SCALE
                            e = _ONE + y * (_ONE + y * (_C2 + y * (_C3 + y * (_C4 + y * (_C5 + y * _C6)))))
                            e = e * e
                            e = e * e
                            e = e * e
                            e = e * e
                            e = e * e
                            hit = u[j, p, t] * (_ONE + e) < _ONE
                            if set_rule:
                                position[j, p, t] = _ONE if hit else _ZERO
                            else:
                                position[j, p, t] = (_ONE - d) if hit else d
            count_tx[:] = _ZERO
            count_rx[:] = _ZERO
            fit[:] = 0.0
            for m in range(num_tx):
                for p in range(population):
                    for t in range(trials):
                        count_tx[p, t] += position[m, p, t]
            for n in range(num_tx, length):
                for p in range(population):
                    for t in range(trials):
                        count_rx[p, t] += position[n, p, t]
            for j in range(length):
                for p in range(population):
                    for t in range(trials):
                        bit[j, p, t] = np.float64(position[j, p, t])
            for m in range(num_tx):  # eq19 as sum_m x_m (sum_n y_n w_mn)
                row[:] = 0.0
                for n in range(num_rx):
                    for p in range(population):
                        for t in range(trials):
                            row[p, t] = row[p, t] + bit[num_tx + n, p, t] * weight[m, n, t]
                for p in range(population):
                    for t in range(trials):
                        fit[p, t] = fit[p, t] + bit[m, p, t] * row[p, t]
            for p in range(population):
                for t in range(trials):
                    ok = (
                        count_tx[p, t] == tx_count
                        and count_rx[p, t] == rx_count
                        and fit[p, t] > personal_fit[p, t]
                    )
                    improved[p, t] = ok
                    personal_fit[p, t] = fit[p, t] if ok else personal_fit[p, t]
            for j in range(length):
                for p in range(population):
                    for t in range(trials):
                        if improved[p, t]:
                            personal_best[j, p, t] = position[j, p, t]
            for t in range(trials):
                chosen[t] = 0
                best_fit[t] = personal_fit[0, t]
            for p in range(1, population):
                for t in range(trials):
                    if personal_fit[p, t] > best_fit[t]:
                        best_fit[t] = personal_fit[p, t]
                        chosen[t] = p
            for t in range(trials):
                if best_fit[t] > global_fit[t]:
                    global_fit[t] = best_fit[t]
                    for j in range(length):
                        global_best[j, t] = personal_best[j, chosen[t], t]
        for t in range(trials):
            for j in range(length):
                out[t, j] = np.int8(global_best[j, t])

    @numba.njit(cache=True, parallel=True)
    def run_numba(
        index,
        tx_count,
        rx_count,
        keys,
        population,
        iterations,
        c1,
        c2,
        inertia_start,
        inertia_end,
        velocity_clamp,
        set_rule,
    ):
        """Same numbers as :func:`run_numpy`; chunks of :data:`CHUNK` trials run in parallel."""
        batch, num_tx, num_rx = index.shape
        out = np.empty((batch, num_tx + num_rx), dtype=np.int8)
        chunks = (batch + CHUNK - 1) // CHUNK
        for c in numba.prange(chunks):
            start = c * CHUNK
            stop = min(start + CHUNK, batch)
            _chunk(
                index[start:stop],
                keys[start:stop],
                out[start:stop],
                tx_count,
                rx_count,
                population,
                iterations,
                c1,
                c2,
                inertia_start,
                inertia_end,
                velocity_clamp,
                set_rule,
            )
        return out
