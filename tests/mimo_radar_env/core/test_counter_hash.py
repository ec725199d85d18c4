"""The counter hash's numba twins give numpy's integers and uniforms bit for bit."""

import numpy as np
import pytest


def test_the_numba_twins_of_the_hash_give_the_numpy_integers_and_uniforms():
    """core/_counter_hash_kernels.py against core/counter_hash.py, bit for bit, on 100,000 keys."""
    from mimo_radar_env.core import counter_hash as numpy_hash
    from mimo_radar_env.core.compiled import HAVE_NUMBA

    if not HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy hash exists")
    import numba

    from mimo_radar_env.core import _counter_hash_kernels as twins

    @numba.njit
    def hashed(keys, streams, steps, elements):
        out = np.empty(len(keys), dtype=np.uint64)
        unit = np.empty(len(keys))
        for i in range(len(keys)):
            base = twins.stream_base_nb(keys[i], streams[i], steps[i])
            out[i] = twins.element_bits_nb(base, elements[i])
            unit[i] = twins.to_unit_nb(out[i])
        return out, unit

    rng = np.random.default_rng(5)
    keys = rng.integers(0, 2**64, size=100_000, dtype=np.uint64)
    streams = rng.integers(0, 20, size=keys.size)
    steps = rng.integers(0, 10_000, size=keys.size)
    elements = rng.integers(0, 1_000, size=keys.size)
    bits, unit = hashed(keys, streams, steps, elements)
    expected = np.array(
        [
            numpy_hash.element_bits(numpy_hash.stream_base(np.array([k]), int(s), int(t)), np.array([e]))[0]
            for k, s, t, e in zip(keys[:2000], streams[:2000], steps[:2000], elements[:2000], strict=True)
        ]
    )
    np.testing.assert_array_equal(bits[:2000], expected)
    np.testing.assert_array_equal(unit, numpy_hash.to_unit(bits))
