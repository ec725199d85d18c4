"""Helpers shared by the tests."""

import numpy as np


def random_valid_actions(rng: np.random.Generator, batch: int, num_tx: int, num_rx: int, ms: int, ns: int):
    """Uniformly random valid super arms as (B, M + N) int8 actions."""
    tx = np.argsort(rng.random((batch, num_tx)), axis=1)[:, :ms]
    rx = np.argsort(rng.random((batch, num_rx)), axis=1)[:, :ns]
    action = np.zeros((batch, num_tx + num_rx), dtype=np.int8)
    np.put_along_axis(action, tx, 1, axis=1)
    np.put_along_axis(action, num_tx + rx, 1, axis=1)
    return action
