"""Best has zero regret; a fixed selection always plays its super arm."""

import numpy as np
import pytest

import agents
from tests.helpers import vector_env


def test_best_has_zero_regret_and_fixed_always_plays_its_arm():
    venv = vector_env("MimoRadarSelect-v0", 8, scenario="paper-3")
    best = agents.make_agent("best", venv.scenario, env=venv)
    fix2 = agents.make_agent("fix2", venv.scenario)
    obs, _ = venv.reset(seed=0)
    best.reset(obs)
    fix2.reset(obs)
    expected_fix2 = np.array([0, 0, 1, 1, 0, 0, 0, 1, 1, 1])
    for _ in range(50):
        np.testing.assert_array_equal(fix2.act(obs), np.tile(expected_fix2, (8, 1)))
        obs, reward, _, _, info = venv.step(best.act(obs))
        np.testing.assert_allclose(info["expected_reward"], info["optimal_reward"], rtol=1e-12)
    with pytest.raises(ValueError, match="tx must be 2 distinct transmitter indices"):
        agents.make_agent("fixed", venv.scenario, tx=[0], rx=[0, 1, 2])
