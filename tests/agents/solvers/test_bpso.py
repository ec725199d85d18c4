"""The BPSO solver: valid selections and its optimality rate, and its parameters checked with their
ranges."""

import numpy as np
import pytest

from agents.solvers import BPSOSolver
from tests.agents.solvers.helpers import against_exact


def test_bpso_returns_valid_selections_and_its_optimality_rate():
    rng = np.random.default_rng(1)
    index = rng.exponential(size=(300, 4, 6))
    tx, rx, etx, erx, values, best = against_exact(BPSOSolver(2, 3), index)
    optimal = (tx == etx).all(axis=1) & (rx == erx).all(axis=1)
    # docs/agents.md quotes the rate model-figures measures (about 0.5 with eq21 as written)
    assert 0.3 < optimal.mean() < 0.8
    assert (values <= best + 1e-12).all() and (values / best).mean() > 0.9


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"population": 2.5}, "population must be an integer in [1, 10,000], got 2.5"),
        ({"population": True}, "population must be an integer"),
        ({"iterations": 0}, "iterations must be in [1, 20,000], got 0"),
        ({"c1": float("nan")}, "c1 must be a finite number in [0, 10], got nan"),
        ({"velocity_clamp": -1}, "velocity_clamp must be in (0, 100], got -1"),
        ({"use_numba": "yes"}, "use_numba must be true or false"),
    ],
)
def test_bpso_parameters_are_checked_with_their_ranges(params, message):
    with pytest.raises(ValueError) as error:
        BPSOSolver(2, 3, **params)
    assert message in str(error.value)
