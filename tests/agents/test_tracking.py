"""tracking-ucb: MG-CRB-CL's learning, selecting for tracking; against direct computations."""

import itertools

import gymnasium as gym
import numpy as np
import pytest

import agents
from agents import env_options_for as policy_env_options
from benchmarks.harness import make_policy
from mimo_radar_env import VERSIONS, EnvOptions, RadarModel, load_scenario
from mimo_radar_env.core.geometry import bistatic_measurement
from tests.helpers import vector_env


def _jacobian(position, tx, rx):
    """Finite-difference Jacobian (2 x 2) of eq6's range sum and azimuth in position."""
    jac = np.zeros((2, 2))
    for i in range(2):
        step = np.zeros(2)
        step[i] = 1e-3
        jac[:, i] = (
            bistatic_measurement(position + step, tx, rx) - bistatic_measurement(position - step, tx, rx)
        ) / 2e-3
    return jac


def _quality_db(sinr, s_min, peak):
    """eq32 on the dB scale, written out: (S_dB - S_min,dB) / (S_max,dB - S_min,dB) + 0.2 in [0.2, 1.2]."""
    lam = (10 * np.log10(sinr) - 10 * np.log10(s_min)) / (10 * np.log10(peak) - 10 * np.log10(s_min)) + 0.2
    return np.clip(lam, 0.2, 1.2)


def _brute_force(agent, obs, model, fusion):
    """Every super arm scored one by one: optimistic SINR -> lambda -> R -> information -> posterior."""
    sc = agent.scenario
    learning = agent.learning
    optimistic = learning.predicted[0] + np.sqrt(learning.beta * np.log(agent.t) / learning.counts[0])  # eq18
    sigma0 = np.diag(sc.measurement_covariance)
    scores = {}
    for tx_idx in itertools.combinations(range(sc.num_tx), sc.tx_per_step):
        for rx_idx in itertools.combinations(range(sc.num_rx), sc.rx_per_step):
            total = 0.0
            for k in range(sc.num_targets):
                position = obs["track_pred"][0, k][[0, 2]]
                prior = np.linalg.inv(obs["track_pred_pos_cov"][0, k])
                gains = []
                for m in tx_idx:
                    for n in rx_idx:
                        lam = _quality_db(optimistic[k, m, n], model.min_sinr[k], sc.peak_sinr)
                        jac = _jacobian(position, sc.tx_positions[m], sc.rx_positions[n])
                        gains.append(jac.T @ np.diag(lam / sigma0) @ jac)
                if fusion == "centralized":
                    posterior = np.linalg.inv(prior + sum(gains))
                else:  # eq22: the mean of the single-channel posteriors
                    posterior = np.mean([np.linalg.inv(prior + g) for g in gains], axis=0)
                total += sc.weights[k] * np.trace(posterior)
            scores[(tx_idx, rx_idx)] = total
    return min(scores, key=scores.get)


@pytest.mark.parametrize("fusion", ["centralized", "average"])
def test_selection_is_the_brute_force_minimum_with_optimistic_sinr(fusion):
    env = gym.make("MimoRadarSelect-v1", horizon=30, fusion=fusion, prediction_covariance=True)
    sc = env.unwrapped.scenario
    agent = agents.make_agent("tracking-ucb", sc, fusion=fusion, lambda_scale="db")
    model = RadarModel.from_scenario(sc)
    obs, _ = env.reset(seed=2)
    agent.reset(obs)
    for _ in range(8):
        action = agent.act(obs)
        batch = {key: np.asarray(value)[None] for key, value in obs.items()}
        chosen = (tuple(np.flatnonzero(action[: sc.num_tx])), tuple(np.flatnonzero(action[sc.num_tx :])))
        assert chosen == _brute_force(agent, batch, model, fusion)
        obs, reward, *_ = env.step(action)
        agent.update(obs, reward)


def test_sinr_weight_one_is_mg_crb_cl_with_exact_search():
    venv = vector_env("MimoRadarSelect-v1", 4, prediction_covariance=True)
    tucb = agents.make_agent("tracking-ucb", venv.scenario, sinr_weight=1.0)
    mg = agents.make_agent("mg-crb-cl", venv.scenario, solver="exact")
    obs, _ = venv.reset(seed=0)
    tucb.reset(obs)
    mg.reset(obs)
    for _ in range(40):
        action = mg.act(obs)
        np.testing.assert_array_equal(tucb.act(obs), action)
        obs, reward, *_ = venv.step(action)
        mg.update(obs, reward)
        tucb.update(obs, reward)


class _TruthWithheld(gym.Wrapper):
    """Gives the agent nothing but observations: info is emptied and the oracles raise."""

    def step(self, action):
        obs, reward, terminated, truncated, _ = self.env.step(action)
        return obs, reward, terminated, truncated, {}

    def reset(self, **kwargs):
        obs, _ = self.env.reset(**kwargs)
        return obs, {}


def test_with_a_constant_quality_it_scores_geometry_only():
    """measurement_quality=q: every channel has lambda = q, so the choice is the criterion's
    minimum with R = Sigma0 / q, whatever the SINR estimates."""
    from mimo_radar_env.tracking.information import channel_information
    from mimo_radar_env.tracking.selection import select_for_tracking

    env = gym.make(
        "MimoRadarSelect-v1",
        scenario="paper-3-v1",
        prediction_covariance=True,
        measurement_quality=0.7,
    )
    sc = env.unwrapped.scenario
    agent = agents.make_agent("tracking-ucb", sc, measurement_quality=0.7)
    obs, _ = env.reset(seed=5)
    agent.reset(obs)
    shape = (1, sc.num_targets, sc.num_tx, sc.num_rx, 2)
    variance = np.broadcast_to(np.diag(sc.measurement_covariance) / 0.7, shape)
    for _ in range(5):
        action = agent.act(obs)
        batch = {key: np.asarray(value)[None] for key, value in obs.items()}
        info = channel_information(
            batch["track_pred"][..., [0, 2]], sc.tx_positions, sc.rx_positions, variance
        )
        tx, rx = select_for_tracking(
            batch["track_pred_pos_cov"], info, sc.weights, sc.tx_per_step, sc.rx_per_step, fusion="average"
        )
        np.testing.assert_array_equal(action, np.concatenate([tx[0], rx[0]]).astype(np.int8))
        obs, reward, *_ = env.step(action)
        agent.update(obs, reward)


def test_it_reads_no_truth():
    def run(withhold):
        env = gym.make("MimoRadarSelect-v1", horizon=60, prediction_covariance=True)
        if withhold:

            def refuse(*args, **kwargs):
                raise AssertionError("the policy read the truth")

            env.unwrapped.engine.oracle_action = refuse
            env.unwrapped.engine.tracking_oracle_action = refuse
            env = _TruthWithheld(env)
        agent = agents.make_agent("tracking-ucb", env.unwrapped.scenario)
        assert not agent.needs.oracle
        obs, info = env.reset(seed=4)
        assert (info == {}) == withhold
        agent.reset(obs)
        actions = []
        for _ in range(60):
            actions.append(agent.act(obs))
            obs, reward, *_ = env.step(actions[-1])
            agent.update(obs, reward)
        return np.array(actions)

    np.testing.assert_array_equal(run(withhold=True), run(withhold=False))


def test_it_needs_the_predicted_covariance_and_checks_its_parameters():
    env = gym.make("MimoRadarSelect-v1")
    obs, _ = env.reset(seed=0)
    with pytest.raises(ValueError, match="prediction_covariance=True"):
        agents.make_agent("tracking-ucb", env.unwrapped.scenario).reset(obs)
    for params, message in [
        ({"sinr_weight": 1.5}, r"sinr_weight must be in \[0, 1\], got 1.5"),
        ({"criterion": "max"}, r"criterion must be one of \['trace', 'logdet'\], got 'max'"),
        ({"fusion": "mean"}, r"fusion must be one of \['average', 'centralized'\], got 'mean'"),
        ({"lambda_scale": "log"}, r"lambda_scale must be one of \['linear', 'db'\], got 'log'"),
    ]:
        with pytest.raises(ValueError, match=message):
            agents.make_agent("tracking-ucb", "paper-1-v1", **params)
    with pytest.raises(ValueError, match="prediction_covariance=True observes .* needs tracking=True"):
        EnvOptions(tracking=False, prediction_covariance=True)


def test_the_harness_gives_it_the_runs_fusion_scale_and_observation():
    options = VERSIONS["v0"].options(fusion="centralized").to_dict()
    sc = load_scenario("paper-1")
    agent = make_policy("tracking-ucb", sc, {}, seed=0, options=options)
    selector = agent.selector
    assert (selector.fusion, selector.lambda_scale, selector.measurement_quality) == (
        "centralized",
        "linear",
        None,
    )
    constant = make_policy("tracking-ucb", sc, {}, seed=0, options=options | {"measurement_quality": 0.5})
    assert constant.selector.measurement_quality == 0.5
    assert policy_env_options(agent, options) == {**options, "prediction_covariance": True}
    same = make_policy("tracking-ucb", sc, {"fusion": "centralized"}, seed=0, options=options)
    assert same.selector.fusion == "centralized"
    with pytest.raises(ValueError, match=r"tracking-ucb.fusion='average' differs from the run's fusion="):
        make_policy("tracking-ucb", sc, {"fusion": "average"}, seed=0, options=options)
    ucb = make_policy("ucb1", sc, {}, seed=0, options=options)
    assert policy_env_options(ucb, options) == options


def test_the_observation_key_is_the_trackers_predicted_position_covariance():
    for version in ("v0", "v1"):
        env = gym.make(f"MimoRadarSelect-{version}", prediction_covariance=True).unwrapped
        plain = gym.make(f"MimoRadarSelect-{version}").unwrapped
        obs, _ = env.reset(seed=3)
        ref, _ = plain.reset(seed=3)
        assert env.observation_space.contains(obs) and "track_pred_pos_cov" not in plain.observation_space
        for _ in range(5):
            full = env.engine.tracker.predicted_covariance()[0]
            np.testing.assert_array_equal(obs["track_pred_pos_cov"], full[:, [0, 2]][:, :, [0, 2]])
            action = np.asarray(env.oracle_action()).reshape(-1)
            obs, *_ = env.step(action)
            ref, *_ = plain.step(action)
            for key in ref:  # the option changes no number of the env
                np.testing.assert_array_equal(obs[key], ref[key])


def test_it_is_composed_of_mg_crb_cls_learning_and_the_tracking_selector():
    """No solver it does not use, no index it does not play; its estimates are MG-CRB-CL's."""
    from agents.base import IndexPolicy
    from agents.tracking import TrackingSelector

    venv = vector_env("MimoRadarSelect-v1", 3, prediction_covariance=True)
    tracking = agents.make_agent("tracking-ucb", venv.scenario, alpha_bar=0.3)
    mg = agents.make_agent("mg-crb-cl", venv.scenario, seed=0, solver="exact", alpha_bar=0.3)
    assert not isinstance(tracking, IndexPolicy) and not hasattr(tracking, "solver")
    assert not hasattr(tracking, "index") and isinstance(tracking.selector, TrackingSelector)
    obs, _ = venv.reset(seed=5)
    tracking.reset(obs)
    mg.reset(obs)
    for _ in range(12):
        action = tracking.act(obs)
        mg.act(obs)  # MG-CRB-CL updates on the same (tracking-ucb's) observations
        np.testing.assert_array_equal(tracking.learning.predicted, mg.predicted)
        obs, reward, *_ = venv.step(action)
        tracking.update(obs, reward)
        mg.update(obs, reward)
        np.testing.assert_array_equal(tracking.learning.estimate, mg.estimate)
        np.testing.assert_array_equal(tracking.learning.counts, mg.counts)
