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


def against_exact(solver, index):
    """``solver``'s selections (checked valid), the exact optimum's, and each trial's value under
    both: (tx, rx, etx, erx, values, best)."""
    from agents.solvers import ExactSolver

    tx, rx = solver.solve(index, streams(index))
    assert_valid(tx, rx, solver.tx_count, solver.rx_count)
    etx, erx = ExactSolver(solver.tx_count, solver.rx_count).solve(index, streams(index))
    values = np.array([value_of(index[b], tx[b], rx[b]) for b in range(len(index))])
    best = np.array([value_of(index[b], etx[b], erx[b]) for b in range(len(index))])
    return tx, rx, etx, erx, values, best
