"""The counter-based random streams: the laws of their draws, and draws that depend only on key,
stream, step and index."""

import numpy as np
from scipy import stats

from mimo_radar_env.core.counter_hash import Stream
from mimo_radar_env.core.streams import TrialStreams, full_index


def _streams(batch=4000, seed=3):
    rng = np.random.default_rng(seed)
    return TrialStreams(rng.integers(0, 2**64, size=(batch, 2), dtype=np.uint64))


def test_laws_of_the_hashed_draws():
    streams = _streams()
    index = full_index(streams.batch_size, (5,))
    u = streams.uniform(Stream.SINR, 7, index).ravel()
    assert stats.kstest(u, "uniform").pvalue > 0.01
    e = streams.exponential(Stream.SINR, 8, index).ravel()
    assert stats.kstest(e, "expon").pvalue > 0.01
    z = streams.normal(Stream.MEASUREMENT, 9, index).ravel()
    assert stats.kstest(z, "norm").pvalue > 0.01
    # consecutive steps and neighbouring elements are uncorrelated
    z2 = streams.normal(Stream.MEASUREMENT, 10, index).ravel()
    assert abs(np.corrcoef(z, z2)[0, 1]) < 4 / np.sqrt(z.size)
    assert abs(np.corrcoef(z[:-1], z[1:])[0, 1]) < 4 / np.sqrt(z.size)


def test_draws_depend_only_on_key_stream_step_and_index():
    streams = _streams(batch=6)
    index = full_index(6, (3, 4))
    a = streams.normal(Stream.PROCESS_NOISE, 5, index)
    np.testing.assert_array_equal(a, streams.normal(Stream.PROCESS_NOISE, 5, index))
    # a subset of the indices gives the same numbers for those indices
    sub = index[:, 1:, 2:]
    np.testing.assert_array_equal(streams.normal(Stream.PROCESS_NOISE, 5, sub), a[:, 1:, 2:])
    # a single trial alone draws what it draws inside a batch
    alone = TrialStreams(streams.keys[2:3])
    np.testing.assert_array_equal(alone.normal(Stream.PROCESS_NOISE, 5, index[:1]), a[2:3])
    assert not np.array_equal(streams.normal(Stream.PROCESS_NOISE, 6, index), a)
    assert not np.array_equal(streams.normal(Stream.INITIAL_STATE, 5, index), a)
