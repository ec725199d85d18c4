"""The numba twins of :mod:`.counter_hash` (``mix``, ``stream_base``, ``element_bits``,
``to_unit``) for compiled kernels: the same numbers, imported only by the kernels that draw."""

import numpy as np

from .compiled import numba


@numba.njit(cache=True, inline="always")
def mix_nb(z):
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@numba.njit(cache=True, inline="always")
def stream_base_nb(key, stream, step):
    count = np.uint64((stream << 32) + step + 1)
    return mix_nb(key ^ mix_nb(count * np.uint64(0x9E3779B97F4A7C15)))


@numba.njit(cache=True, inline="always")
def element_bits_nb(base, element):
    return mix_nb(base + (np.uint64(element) + np.uint64(1)) * np.uint64(0x9E3779B97F4A7C15))


@numba.njit(cache=True, inline="always")
def to_unit_nb(bits):
    return np.float64(bits >> np.uint64(11)) * 2.0**-53
