"""A fusion is one component: a third fusion, defined in this file alone, runs through the env,
best-tracking, the planner and the cost model with no other edit.

The fusion here fuses a super arm as if it gave the mean of its channels' information: the
centralised update with every channel's measurement variance multiplied by the channel count.
With one channel it is the centralised update; with several it is checked against the
information form computed here with ``np.linalg.inv``.
"""

import numpy as np
import pytest

import agents
from mimo_radar_env import MimoRadarSelectVectorEnv, random_scenario
from mimo_radar_env.core.superarm import all_super_arms
from mimo_radar_env.envs.cost import operations_per_trial_step
from mimo_radar_env.tracking.fusion import FUSIONS, CentralizedFusion, Fusion, register_fusion
from mimo_radar_env.tracking.information import inverse_2x2, woodbury_gain
from mimo_radar_env.tracking.planning import Planner, posterior_covariance

NAME = "mean-information"
OPERATIONS = 12_345.0


class MeanInformationFusion(Fusion):
    name = NAME

    def update(self, prior, tx_positions, rx_positions, measurement, noise_variance):
        channels = tx_positions.shape[1] * rx_positions.shape[1]
        return CentralizedFusion(use_numba=False).update(
            prior, tx_positions, rx_positions, measurement, noise_variance * channels
        )

    @staticmethod
    def channel_terms(prior_info, information):
        return information

    @staticmethod
    def posterior_from_sum(prior_info, total, count):
        return inverse_2x2(prior_info + total / count)[0]

    @staticmethod
    def planning_gain(information, position_cov, selected):
        count = selected.sum(axis=(1, 2))[:, None, None]
        return woodbury_gain(np.einsum("smn,skmnij->skij", selected / count, information), position_cov)

    @staticmethod
    def update_operations(channels):
        return OPERATIONS * channels


@pytest.fixture
def fusion():
    register_fusion(MeanInformationFusion)
    yield NAME
    FUSIONS.pop(NAME)


def _tracks(scenario, fusion, steps=8, trials=4):
    env = MimoRadarSelectVectorEnv(num_envs=trials, scenario=scenario, fusion=fusion)
    obs, _ = env.reset(seed=3)
    for _ in range(steps):
        obs, *_ = env.step(env.oracle_action())
    return obs["track"]


def test_the_env_tracks_with_it(fusion):
    one_channel = random_scenario(3, 3, 2, 1, 1, horizon=20, seed=1)
    np.testing.assert_allclose(
        _tracks(one_channel, fusion), _tracks(one_channel, "centralized"), rtol=1e-10, atol=1e-8
    )
    several = random_scenario(3, 4, 2, 2, 2, horizon=20, seed=1)
    mine, centralised = _tracks(several, fusion), _tracks(several, "centralized")
    assert np.isfinite(mine).all()
    assert not np.allclose(mine, centralised)  # four channels: a quarter of the information


def _mean_information_posterior(covariance, information, tx, rx):
    """The 4 x 4 posterior by inverting the information form: ``(P^-1 + E' J_mean E)^-1``."""
    selected = (tx[:, None] & rx[None, :]).astype(float)
    mean = np.einsum("mn,kmnij->kij", selected / selected.sum(), information)
    embedded = np.zeros((len(mean), 4, 4))
    embedded[:, 0::2, 0::2] = mean
    return np.linalg.inv(np.linalg.inv(covariance) + embedded)


def test_best_tracking_minimises_its_posterior(fusion):
    scenario = random_scenario(3, 4, 2, 2, 2, horizon=20, seed=5)
    env = MimoRadarSelectVectorEnv(num_envs=3, scenario=scenario, fusion=fusion, prediction_covariance=True)
    agent = agents.make_agent("best-tracking", scenario)
    agent.attach(env)
    obs, _ = env.reset(seed=0)
    agent.reset(obs)
    tx_masks, rx_masks = all_super_arms(3, 4, 2, 2)
    for _ in range(4):
        forecast = env.tracking_forecast(1)
        action = agent.act(obs)
        for b in range(3):
            costs = [
                np.einsum(
                    "k,k->",
                    scenario.weights,
                    np.trace(
                        _mean_information_posterior(
                            forecast.covariance[b], forecast.information[b, 0], tx, rx
                        )[:, 0::2, 0::2],
                        axis1=-2,
                        axis2=-1,
                    ),
                )
                for tx, rx in zip(tx_masks, rx_masks, strict=True)
            ]
            best = int(np.argmin(costs))
            np.testing.assert_array_equal(action[b], np.concatenate([tx_masks[best], rx_masks[best]]))
        obs, *_ = env.step(action)


def test_the_planner_carries_its_posterior(fusion):
    scenario = random_scenario(3, 3, 2, 1, 2, horizon=20, seed=4)
    env = MimoRadarSelectVectorEnv(num_envs=4, scenario=scenario, fusion=fusion)
    env.reset(seed=1)
    forecast = env.tracking_forecast(2)
    tx_masks, rx_masks = all_super_arms(3, 3, 1, 2)
    arms = np.array([0, 4, 2, 7])
    got = posterior_covariance(
        forecast.covariance, forecast.information[:, 0], tx_masks[arms], rx_masks[arms], fusion
    )
    for b, a in enumerate(arms):
        expected = _mean_information_posterior(
            forecast.covariance[b], forecast.information[b, 0], tx_masks[a], rx_masks[a]
        )
        np.testing.assert_allclose(got[b], expected, rtol=1e-9, atol=1e-9)
    plan, cost = Planner(3, 3, 1, 2, search="beam", width=4, fusion=fusion).plan(forecast)
    assert plan.shape == (4, 2) and np.isfinite(cost).all()


def test_the_cost_model_counts_its_update(fusion):
    scenario = random_scenario(4, 5, 3, 2, 3, horizon=20, seed=0)
    K, channels = 3, 2 * 3
    tracked = operations_per_trial_step(scenario, True, fusion)
    untracked = operations_per_trial_step(scenario, False, fusion)
    average = operations_per_trial_step(scenario, True, "average")
    # K targets x 3 models, each update plus the fixed per-model work, and the bound
    assert tracked - untracked == pytest.approx(
        K * (3 * (OPERATIONS * channels + 3000) + channels * 200 + 2000)
    )
    assert tracked != average


def test_an_unregistered_fusion_is_refused_with_the_choices():
    with pytest.raises(ValueError, match=r"fusion must be one of \['average', 'centralized'\]"):
        MimoRadarSelectVectorEnv(num_envs=2, scenario="paper-1-v1", fusion=NAME)
    with pytest.raises(TypeError, match="a Fusion subclass with a name"):
        register_fusion(object)
