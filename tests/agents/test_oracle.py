"""best: the optimal super arm of each step, so zero regret."""

import numpy as np

import agents
from tests.helpers import vector_env


def test_best_has_zero_regret():
    venv = vector_env("MimoRadarSelect-v0", 8, scenario="paper-3")
    best = agents.make_agent("best", venv.scenario, env=venv)
    obs, _ = venv.reset(seed=0)
    best.reset(obs)
    for _ in range(50):
        obs, reward, _, _, info = venv.step(best.act(obs))
        np.testing.assert_allclose(info["expected_reward"], info["optimal_reward"], rtol=1e-12)
