"""Every solver of the registry: valid selections on ties and zeros, and its errors."""

import numpy as np
import pytest

from agents.solvers import ExactSolver, make_solver
from mimo_radar_env.core.streams import TrialRandom
from tests.agents.solvers.helpers import assert_valid, streams


@pytest.mark.parametrize("solver", ["exact", "bpso", "alternating"])
def test_every_solver_is_valid_on_ties_and_zeros(solver):
    rng = np.random.default_rng(0)
    s = make_solver(solver, 2, 3, **({"iterations": 10} if solver == "bpso" else {}))
    for index in (np.zeros((4, 4, 6)), np.ones((4, 4, 6)), np.round(rng.random((4, 4, 6)))):
        tx, rx = s.solve(index, streams(index))
        assert_valid(tx, rx, 2, 3)


def test_solver_errors():
    with pytest.raises(ValueError, match="unknown solver 'simplex'; available solvers are"):
        make_solver("simplex", 2, 3)
    with pytest.raises(
        ValueError, match=r"solver 'bpso': unknown \['swarm'\]; it takes \['population', 'iterations', "
    ):
        make_solver("bpso", 2, 3, swarm=3)
    with pytest.raises(ValueError, match=r"solver 'exact': unknown \['population'\]; it takes none"):
        make_solver("exact", 2, 3, population=3)
    with pytest.raises(ValueError, match=r"population must be an integer in \[1, 10,000\], got 'x'"):
        make_solver("bpso", 2, 3, population="x")  # a bad value keeps its own line
    with pytest.raises(ValueError, match="NaN"):
        ExactSolver(2, 3).solve(np.full((1, 4, 6), np.nan), TrialRandom.for_batch(0, 1))
