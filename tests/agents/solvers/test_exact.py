"""The exact solver against brute force."""

from itertools import combinations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from agents.solvers import ExactSolver
from tests.agents.solvers.helpers import assert_valid, streams, value_of


def brute_force(index, ms, ns):
    best = (-np.inf, None, None)
    M, N = index.shape
    for tx in combinations(range(M), ms):
        for rx in combinations(range(N), ns):
            value = index[np.ix_(tx, rx)].sum()
            if value > best[0]:
                best = (value, tx, rx)
    return best


@st.composite
def problems(draw):
    M = draw(st.integers(1, 7))
    N = draw(st.integers(1, 7))
    ms = draw(st.integers(1, M))
    ns = draw(st.integers(1, N))
    seed = draw(st.integers(0, 2**31))
    return M, N, ms, ns, seed


@settings(max_examples=60, deadline=None)
@given(problems())
def test_exact_equals_brute_force(problem):
    M, N, ms, ns, seed = problem
    rng = np.random.default_rng(seed)
    index = rng.exponential(size=(3, M, N))
    tx, rx = ExactSolver(ms, ns).solve(index, streams(index))
    assert_valid(tx, rx, ms, ns)
    for b in range(3):
        expected, _, _ = brute_force(index[b], ms, ns)
        assert value_of(index[b], tx[b], rx[b]) == pytest.approx(expected, rel=1e-12)
