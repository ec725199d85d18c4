"""What the solver tests share: a selection's value, its validity, and the trials' streams."""

import numpy as np

from mimo_radar_env.core.streams import TrialRandom


def value_of(index, tx, rx):
    return index[np.ix_(np.flatnonzero(tx), np.flatnonzero(rx))].sum()


def assert_valid(tx, rx, ms, ns):
    assert tx.dtype == bool and rx.dtype == bool
    assert (tx.sum(axis=1) == ms).all() and (rx.sum(axis=1) == ns).all()


def streams(index, seed=0):
    return TrialRandom.for_batch(seed, index.shape[0])
