"""fixed, fix1 and fix2: the same super arm every step, the stations checked by name."""

import numpy as np
import pytest

import agents
from agents.fixed import PAPER_FIXED
from tests.helpers import vector_env


def test_fix2_plays_the_papers_stations_every_step():
    venv = vector_env("MimoRadarSelect-v0", 8, scenario="paper-3")
    fix2 = agents.make_agent("fix2", venv.scenario)
    obs, _ = venv.reset(seed=0)
    fix2.reset(obs)
    # fix2 = {TX3, TX4; RX4, RX5, RX6}, 1-based in the paper
    expected = np.array([0, 0, 1, 1, 0, 0, 0, 1, 1, 1])
    for _ in range(20):
        action = fix2.act(obs)
        np.testing.assert_array_equal(action, np.tile(expected, (8, 1)))
        obs, *_ = venv.step(action)
    assert PAPER_FIXED["fix2"] == ((2, 3), (3, 4, 5))


def test_a_fixed_selection_of_given_stations_and_bad_stations_named():
    fixed = agents.make_agent("fixed", "paper-1", tx=[1, 0], rx=[5, 2, 0])
    venv = vector_env("MimoRadarSelect-v0", 2, scenario="paper-1")
    obs, _ = venv.reset(seed=0)
    fixed.reset(obs)
    np.testing.assert_array_equal(fixed.act(obs)[0], [1, 1, 0, 0, 1, 0, 1, 0, 0, 1])
    for tx, rx, match in [
        ([0], [0, 1, 2], "tx must be 2 distinct transmitter indices in 0..3"),
        ([0, 0], [0, 1, 2], "tx must be 2 distinct"),
        ([0, 4], [0, 1, 2], "tx must be 2 distinct"),
        ([0, 1], [0, 1, 6], "rx must be 3 distinct receiver indices in 0..5"),
        ("01", [0, 1, 2], "tx must be a list of 0-based station indices"),
        ([0, 1.0], [0, 1, 2], r"tx must hold integer station indices, got \[0, 1.0\]"),
        ([0, True], [0, 1, 2], "tx must hold integer station indices"),
    ]:
        with pytest.raises(ValueError, match=match):
            agents.make_agent("fixed", "paper-1", tx=tx, rx=rx)
