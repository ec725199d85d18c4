"""The agents' BPSO kernel before its rework, kept as the speed reference (not used by any agent).

``python -m benchmarks.speed.solver_speed`` and ``mimo-radar-bench perf`` time the agents'
kernel (:mod:`agents.solvers._bpso_kernels`) against this one in one thread, side by side in
the same run, so the speed-up is a ratio measured on one machine at one time. The two give the
same selections (tests/bench/test_bpso_reference.py): the rework changed the layout, not the
numbers. The source is frozen on purpose: it is a measuring stick, not a second home of the
algorithm, which lives in :mod:`agents.solvers._bpso_kernels` (its numpy kernel is the
reference of the numbers).
"""

from __future__ import annotations

import numpy as np

from agents.solvers._bpso_kernels import _C3, _C4, _C5, _C6, _FLIP, _R1, _R2
from mimo_radar_env.core.compiled import HAVE_NUMBA, numba

if HAVE_NUMBA:  # pragma: no branch
    from mimo_radar_env.core.counter_hash import element_bits_nb, stream_base_nb, to_unit_nb

if HAVE_NUMBA:  # pragma: no branch

    def _reference(
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
    ):
        """The agents' kernel as it was before the float64 (bit, particle) layout and eq19's table:
        int8 positions, eq19 summed per particle. Same arguments and numbers as
        :func:`agents.solvers._bpso_kernels.run_numpy`."""
        batch, population, length = positions.shape
        num_tx = index.shape[1]
        num_rx = index.shape[2]
        lanes = (length + 3) // 4
        result = np.empty((batch, length), dtype=np.int8)
        steps = max(iterations - 1, 1)
        for b in range(batch):
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
                    base_r1 = stream_base_nb(key, _R1, it)
                    base_r2 = stream_base_nb(key, _R2, it)
                    base_flip = stream_base_nb(key, _FLIP, it)
                    for p in range(population):
                        a1[p] = c1 * to_unit_nb(element_bits_nb(base_r1, p))
                        a2[p] = c2 * to_unit_nb(element_bits_nb(base_r2, p))
                    for lane in range(lanes):
                        for p in range(population):
                            hashes[lane, p] = element_bits_nb(base_flip, p * lanes + lane)
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
                            hit = np.int8(u * (1.0 + e) < 1.0)
                            position[j, p] = hit if set_rule else d ^ hit
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

    #: The pre-rework kernel, one thread.
    run_reference = numba.njit(cache=True)(_reference)
