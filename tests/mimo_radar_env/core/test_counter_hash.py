"""The counter hash's numba twins give numpy's integers and uniforms bit for bit."""

import numpy as np
import pytest

from mimo_radar_env.core import counter_hash


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


def test_stream_bases_are_each_steps_stream_base_on_numpy_and_torch():
    """Every step's bases at once give, column by column, the bases of a call per step: numpy's
    uint64 and torch's int64 words (bit for bit), including the step at the counter's top."""
    keys = np.random.default_rng(5).integers(0, 2**64, size=7, dtype=np.uint64, endpoint=False)
    keys[0] = 2**64 - 1
    for stream in (counter_hash.Stream.BPSO_R1, counter_hash.Stream.BPSO_FLIP):
        bases = counter_hash.stream_bases(keys, stream, 40)
        expected = np.stack([counter_hash.stream_base(keys, stream, q) for q in range(40)], axis=1)
        assert bases.dtype == np.uint64
        np.testing.assert_array_equal(bases, expected)
    torch = pytest.importorskip("torch")
    from mimo_radar_env.core.arrays import device_namespace

    words = device_namespace("cpu").words(keys)
    on_torch = counter_hash.stream_bases(words, counter_hash.Stream.BPSO_R2, 40)
    expected = counter_hash.stream_bases(keys, counter_hash.Stream.BPSO_R2, 40)
    assert isinstance(on_torch, torch.Tensor)
    np.testing.assert_array_equal(on_torch.numpy().view(np.uint64), expected)
    with pytest.raises(ValueError, match="steps must be in"):
        counter_hash.stream_bases(keys, counter_hash.Stream.BPSO_R1, 0)
