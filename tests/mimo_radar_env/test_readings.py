"""The readings of the paper's ambiguous points: each option changes exactly what it says."""

import gymnasium as gym
import numpy as np
import pytest
from scipy import stats

from agents.solvers import BPSOSolver, ExactSolver
from mimo_radar_env import EnvOptions, load_scenario
from mimo_radar_env.core.streams import TrialRandom
from tests.helpers import simulation, vector_env


def test_lambda_scale_db_is_eq32_on_decibels():
    model, sim = simulation("paper-3", 5, lambda_scale="db")
    for _ in range(30):
        sim.advance()
    tx, rx = np.tile([0, 3], (5, 1)), np.tile([1, 2, 5], (5, 1))
    obs = sim.observe(tx, rx, np.ones(5, bool))
    s_db = 10 * np.log10(obs.mean_sinr)  # (B, K, C)
    s_min_db = 10 * np.log10(model.min_sinr)[None, :, None]
    lam = np.clip((s_db - s_min_db) / (10.0 - s_min_db) + 0.2, 0.2, 1.2)  # S_max = 10 is 10 dB
    expected = np.stack([5.0 / lam, 0.002 / lam], axis=-1)
    np.testing.assert_allclose(obs.noise_variance, expected, rtol=1e-12)
    linear = simulation("paper-3", 5)[1]
    for _ in range(30):
        linear.advance()
    assert not np.allclose(linear.observe(tx, rx, np.ones(5, bool)).noise_variance, expected)


def test_shared_truth_is_one_trajectory_and_estimates_start_at_p1_hat_spread():
    batch = 3000
    venv = vector_env("MimoRadarSelect-v1", batch)
    obs, info = venv.reset(seed=0)
    scenario = venv.scenario
    x1, p1 = scenario.targets[0].initial_state, scenario.targets[0].initial_covariance
    np.testing.assert_array_equal(info["true_state"], np.broadcast_to(x1, info["true_state"].shape))
    error = obs["track"][:, 0] - x1  # each trial's initial estimate error
    for i in range(4):  # variance 20 in every component: a chi-square test of each
        statistic = (batch - 1) * error[:, i].var(ddof=1) / p1[i, i]
        assert 0.001 < stats.chi2.cdf(statistic, batch - 1) < 0.999
    assert abs(np.corrcoef(error[:, 0], error[:, 2])[0, 1]) < 4 / np.sqrt(batch)
    action = np.tile(venv.oracle_action()[0], (batch, 1))
    for _ in range(20):
        _, _, _, _, info = venv.step(action)
    truth = info["true_state"]
    assert np.all(truth == truth[0]) and not np.allclose(truth[0], x1)  # one noisy trajectory
    other = vector_env("MimoRadarSelect-v1", 2, truth_seed=1)
    other.reset(seed=0)
    for _ in range(20):
        _, _, _, _, info_other = other.step(action[:2])
    assert not np.allclose(info_other["true_state"][0], truth[0])  # truth_seed picks the trajectory


def test_per_trial_truth_is_v0s():
    venv = vector_env("MimoRadarSelect-v0", 200)
    obs, info = venv.reset(seed=0)
    x1 = venv.scenario.targets[0].initial_state
    np.testing.assert_array_equal(obs["track"][:, 0], np.broadcast_to(x1, (200, 4)))
    assert info["true_state"][:, 0].std(axis=0).min() > 3  # spread sqrt(20) ~ 4.5


def test_bpso_set_rule_finds_the_optimum_in_at_least_95_percent():
    index = np.random.default_rng(11).exponential(size=(1000, 4, 6))
    streams = TrialRandom.for_batch(0, 1000)
    tx, rx = BPSOSolver(2, 3, rule="set").solve(index, streams)  # the paper's swarm: 50 x 100
    etx, erx = ExactSolver(2, 3).solve(index, streams)
    optimal = ((tx == etx).all(axis=1) & (rx == erx).all(axis=1)).mean()
    assert optimal >= 0.95, optimal
    xor_tx, xor_rx = BPSOSolver(2, 3).solve(index, TrialRandom.for_batch(0, 1000))
    assert ((xor_tx == etx).all(axis=1) & (xor_rx == erx).all(axis=1)).mean() < 0.7  # eq21 as written


def test_versions_register_their_defaults():
    assert gym.make("MimoRadarSelect-v0").unwrapped.options == EnvOptions()
    assert gym.make("MimoRadarSelect-v1").unwrapped.options == EnvOptions(lambda_scale="db", truth="shared")
    assert gym.make("MimoRadarSelect-v1", truth="per-trial").unwrapped.options.truth == "per-trial"


def test_each_version_names_its_paper_scenarios():
    from mimo_radar_env import PAPER_SCENARIOS, paper_scenario
    from mimo_radar_env.envs.versions import paper_key

    assert PAPER_SCENARIOS["v0"] == ("paper-1", "paper-2", "paper-3")
    assert [paper_scenario(n, "v1") for n in (1, 2, 3)] == ["paper-1-v1", "paper-2-v1", "paper-3-v1"]
    assert paper_key("paper-2-v1") == paper_key("paper-2") == "paper-2" and paper_key("mine") == "mine"
    for version, names in PAPER_SCENARIOS.items():
        env = gym.make(f"MimoRadarSelect-{version}")
        assert env.unwrapped.scenario.name == names[0]
        for name in names:
            assert load_scenario(name).name == name
    with pytest.raises(ValueError, match="paper scenarios are 1, 2 and 3"):
        paper_scenario(4, "v1")
