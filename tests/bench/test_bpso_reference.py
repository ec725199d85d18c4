"""The pre-rework BPSO kernel kept as the speed reference (benchmarks.speed.bpso_reference)."""

import numpy as np
import pytest

from agents.random_streams import TrialRandom
from agents.solvers import BPSOSolver, _bpso_kernels
from benchmarks.speed import bpso_reference

pytestmark = pytest.mark.skipif(not bpso_reference.HAVE_NUMBA, reason="numba is not installed")


@pytest.mark.parametrize("set_rule", [False, True])
def test_reference_kernel_selects_what_the_agents_kernels_select(set_rule):
    """The measuring stick of solver_speed and perf gives the same super arms as the agents'
    compiled kernel and its numpy twin, at the paper's size (fewer iterations)."""
    index = np.random.default_rng(11).exponential(size=(30, 4, 6))
    positions, keys = BPSOSolver(2, 3).initial_swarm(TrialRandom.for_batch(5, 30), 4, 6)
    args = (index, 2, 3, positions, keys, 25, 2.0, 2.0, 0.9, 0.4, 6.0, set_rule)
    reference = bpso_reference.run_reference(*args)
    np.testing.assert_array_equal(_bpso_kernels.run_numba_serial(*args), reference)
    np.testing.assert_array_equal(_bpso_kernels.run_numpy(*args), reference)
