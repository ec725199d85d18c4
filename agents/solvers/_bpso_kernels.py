"""BPSO iteration kernels: a numba one and a pure-numpy one that give the same numbers.

Both draw their random numbers from the same counter-based SplitMix64 hash of
(trial key, stream, iteration, element) and evaluate the sigmoid of eq21 with
the same sequence of +, * and / (no libm call), so nothing is computed
differently by the two paths. numba is optional (``pip install numba``);
without it the numpy kernel runs.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

try:  # pragma: no cover - exercised when numba is installed
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    numba = None
    HAVE_NUMBA = False

GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
STREAM_R1, STREAM_R2, STREAM_FLIP = 1, 2, 3
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


def _mix_np(z: NDArray[np.uint64]) -> NDArray[np.uint64]:
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


def _bases_np(keys: NDArray[np.uint64], stream: int, iteration: int) -> NDArray[np.uint64]:
    counter = np.array([(stream << 32) + iteration + 1], dtype=np.uint64)
    return _mix_np(keys ^ _mix_np(counter * GOLDEN))


def _uniform_np(base: NDArray[np.uint64], element: NDArray[np.uint64]) -> NDArray[np.float64]:
    return (_mix_np(base + (element + np.uint64(1)) * GOLDEN) >> np.uint64(11)).astype(np.float64) * 2.0**-53


def _flip_uniform_np(
    base: NDArray[np.uint64], element: NDArray[np.uint64], shift: NDArray[np.uint64]
) -> NDArray[np.float64]:
    """16-bit uniforms, four per hash: ``(lane + 0.5) / 65536``."""
    h = _mix_np(base + (element + np.uint64(1)) * GOLDEN)
    lane = (h >> shift) & np.uint64(0xFFFF)
    return (lane.astype(np.float64) + 0.5) * (1.0 / 65536.0)


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
) -> NDArray[np.int8]:
    """All iterations, vectorised over trials and particles. Returns the global bests (B, L)."""
    batch, population, length = positions.shape
    num_tx = index.shape[1]
    positions = positions.copy()
    velocities = np.zeros(positions.shape)
    fitness, valid = _fitness_np(index, positions, num_tx, tx_count, rx_count)
    personal_best = positions.copy()
    personal_fit = np.where(valid, fitness, -np.inf)
    rows = np.arange(batch)
    first = np.argmax(personal_fit, axis=1)
    global_best = personal_best[rows, first].copy()
    global_fit = personal_fit[rows, first].copy()
    particle = np.arange(population, dtype=np.uint64)[None, :]
    lanes = (length + 3) // 4
    bit = np.arange(length)
    hash_element = (np.arange(population)[:, None] * lanes + bit // 4).astype(np.uint64)[None]  # (1, P, L)
    lane_shift = (16 * (bit % 4)).astype(np.uint64)
    steps = max(iterations - 1, 1)
    for q in range(iterations):
        inertia = inertia_start - (inertia_start - inertia_end) * q / steps
        r1 = _uniform_np(_bases_np(keys, STREAM_R1, q)[:, None], particle)
        r2 = _uniform_np(_bases_np(keys, STREAM_R2, q)[:, None], particle)
        u = _flip_uniform_np(_bases_np(keys, STREAM_FLIP, q)[:, None, None], hash_element, lane_shift)
        velocities = (
            inertia * velocities
            + (c1 * r1)[..., None] * (personal_best - positions)
            + (c2 * r2)[..., None] * (global_best[:, None, :] - positions)
        )  # eq20
        velocities = np.minimum(np.maximum(velocities, -velocity_clamp), velocity_clamp)
        flip = u * (1.0 + exp_negative(velocities)) < 1.0  # eq21: u < sigmoid(V)
        positions = np.where(flip, 1 - positions, positions).astype(np.int8)
        fitness, valid = _fitness_np(index, positions, num_tx, tx_count, rx_count)
        improved = valid & (fitness > personal_fit)
        personal_best = np.where(improved[..., None], positions, personal_best)
        personal_fit = np.where(improved, fitness, personal_fit)
        candidate = np.argmax(personal_fit, axis=1)
        better = personal_fit[rows, candidate] > global_fit
        global_best = np.where(better[:, None], personal_best[rows, candidate], global_best)
        global_fit = np.where(better, personal_fit[rows, candidate], global_fit)
    return global_best


def _fitness_np(
    index: NDArray[np.float64], positions: NDArray[np.int8], num_tx: int, tx_count: int, rx_count: int
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """eq19: index sum over the selected channels (summed TX-major, as the numba kernel), 0 if invalid."""
    tx = positions[..., :num_tx].astype(np.float64)
    rx = positions[..., num_tx:].astype(np.float64)
    tx_ok = positions[..., :num_tx].sum(axis=-1) == tx_count
    valid = tx_ok & (positions[..., num_tx:].sum(axis=-1) == rx_count)
    value = np.zeros(positions.shape[:2])
    for m in range(num_tx):  # loops over stations (not trials or particles) fix the summation order
        for n in range(index.shape[2]):
            value += tx[..., m] * rx[..., n] * index[:, None, m, n]
    return np.where(valid, value, 0.0), valid


if HAVE_NUMBA:  # pragma: no branch

    @numba.njit(cache=True, inline="always")
    def _mix_nb(z):  # noqa: ANN001, ANN202
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        return z ^ (z >> np.uint64(31))

    @numba.njit(cache=True, inline="always")
    def _base_nb(key, stream, iteration):  # noqa: ANN001, ANN202
        counter = np.uint64((stream << 32) + iteration + 1)
        return _mix_nb(key ^ _mix_nb(counter * np.uint64(0x9E3779B97F4A7C15)))

    @numba.njit(cache=True, inline="always")
    def _uniform_nb(base, element):  # noqa: ANN001, ANN202
        h = _mix_nb(base + (np.uint64(element) + np.uint64(1)) * np.uint64(0x9E3779B97F4A7C15))
        return np.float64(h >> np.uint64(11)) * 2.0**-53

    @numba.njit(cache=True, inline="always")
    def _fitness_nb(index, b, position, num_tx, num_rx, tx_count, rx_count):  # noqa: ANN001, ANN202
        ct = 0
        for m in range(num_tx):
            ct += position[m]
        cr = 0
        for n in range(num_rx):
            cr += position[num_tx + n]
        if ct != tx_count or cr != rx_count:
            return 0.0, False
        value = 0.0
        for m in range(num_tx):
            for n in range(num_rx):
                value += np.float64(position[m]) * np.float64(position[num_tx + n]) * index[b, m, n]
        return value, True

    @numba.njit(cache=True, parallel=True)
    def run_numba(
        index,
        tx_count,
        rx_count,
        positions,
        keys,
        iterations,
        c1,
        c2,  # noqa: ANN001, ANN201
        inertia_start,
        inertia_end,
        velocity_clamp,
    ):
        """Same numbers as :func:`run_numpy`. Per trial, arrays are laid out (bit, particle)
        so that every inner loop runs over particles and vectorises."""
        batch, population, length = positions.shape
        num_tx = index.shape[1]
        num_rx = index.shape[2]
        lanes = (length + 3) // 4
        golden = np.uint64(0x9E3779B97F4A7C15)
        result = np.empty((batch, length), dtype=np.int8)
        steps = max(iterations - 1, 1)
        for b in numba.prange(batch):
            position = positions[b].T.copy()  # (L, P)
            velocity = np.zeros((length, population))
            personal_best = position.copy()
            personal_fit = np.empty(population)
            fitness = np.empty(population)
            valid = np.empty(population, dtype=np.bool_)
            a1 = np.empty(population)
            a2 = np.empty(population)
            hashes = np.empty((lanes, population), dtype=np.uint64)
            global_best = np.empty(length, dtype=np.int8)
            global_fit = -np.inf
            key = keys[b]
            for q in range(iterations + 1):
                if q > 0:
                    it = q - 1
                    inertia = inertia_start - (inertia_start - inertia_end) * it / steps
                    base_r1 = _base_nb(key, 1, it)
                    base_r2 = _base_nb(key, 2, it)
                    base_flip = _base_nb(key, 3, it)
                    for p in range(population):
                        a1[p] = c1 * _uniform_nb(base_r1, p)
                        a2[p] = c2 * _uniform_nb(base_r2, p)
                    for lane in range(lanes):
                        for p in range(population):
                            hashes[lane, p] = _mix_nb(
                                base_flip + (np.uint64(p * lanes + lane) + np.uint64(1)) * golden
                            )
                    for j in range(length):
                        shift = np.uint64(16 * (j % 4))
                        lane = j // 4
                        for p in range(population):
                            d = position[j, p]
                            v = inertia * velocity[j, p] + a1[p] * (personal_best[j, p] - d)
                            v = v + a2[p] * (global_best[j] - d)
                            v = min(max(v, -velocity_clamp), velocity_clamp)
                            velocity[j, p] = v
                            u = (np.float64((hashes[lane, p] >> shift) & np.uint64(0xFFFF)) + 0.5) * (
                                1.0 / 65536.0
                            )
                            y = v * (-1.0 / 32.0)
                            e = 1.0 + y * (1.0 + y * (0.5 + y * (_C3 + y * (_C4 + y * (_C5 + y * _C6)))))
                            e = e * e
                            e = e * e
                            e = e * e
                            e = e * e
                            e = e * e
                            position[j, p] = d ^ np.int8(u * (1.0 + e) < 1.0)
                # eq19 for every particle, summed in the order of _fitness_np
                for p in range(population):
                    fitness[p] = 0.0
                for m in range(num_tx):
                    for n in range(num_rx):
                        w = index[b, m, n]
                        for p in range(population):
                            fitness[p] += np.float64(position[m, p]) * np.float64(position[num_tx + n, p]) * w
                for p in range(population):
                    ct = 0
                    for m in range(num_tx):
                        ct += position[m, p]
                    cr = 0
                    for n in range(num_rx):
                        cr += position[num_tx + n, p]
                    valid[p] = ct == tx_count and cr == rx_count
                if q == 0:
                    for p in range(population):
                        personal_fit[p] = fitness[p] if valid[p] else -np.inf
                else:
                    for p in range(population):
                        if valid[p] and fitness[p] > personal_fit[p]:
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
            result[b] = global_best
        return result
