"""The single env: Gymnasium's checks, registration, the rewards and measurements of the model,
the oracle, valid and invalid actions, the class's documentation."""

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AutoresetMode, VectorEnv

from mimo_radar_env import MimoRadarSelectEnv
from tests.helpers import random_valid_actions, vector_env


@pytest.mark.parametrize("scenario", ["paper-1", "paper-2", "paper-3"])
def test_check_env_passes_without_warning(scenario):
    env = gym.make("MimoRadarSelect-v0", scenario=scenario, render_mode="rgb_array")
    # the renderer's import first: its own warnings (an older matplotlib's under a newer
    # pyparsing, .ci/lowest-check) are not the env's
    import matplotlib.backends.backend_agg  # noqa: F401

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # check_env also makes a render_mode="human" env; on a machine without a display that
        # env says so (tests/mimo_radar_env/wrappers/test_flat.py), which is not a failure of the check
        warnings.filterwarnings("ignore", message=".*render_mode='human' shows nothing here")
        check_env(env.unwrapped)


def test_quickstart_and_registration_is_idempotent():
    import importlib

    import mimo_radar_env

    importlib.reload(mimo_radar_env)  # registering twice must not warn or fail
    env = gym.make("MimoRadarSelect-v0", scenario="paper-1")
    obs, info = env.reset(seed=0)
    assert obs["probed"].all() and obs["sinr"].shape == (1, 4, 6)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert set(info) >= {"mean_sinr", "true_state", "expected_reward", "optimal_reward", "action_valid"}
    venv = vector_env("MimoRadarSelect-v0", 5, scenario="paper-3")
    assert isinstance(venv, VectorEnv)
    assert venv.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    obs, info = venv.reset(seed=0)
    assert obs["sinr"].shape == (5, 2, 4, 6) and info["true_state"].shape == (5, 2, 4)


def test_rewards_and_expected_rewards_follow_eq17_and_eq13():
    env = gym.make("MimoRadarSelect-v0", scenario="paper-3")
    obs, info = env.reset(seed=2)
    omega = np.array([0.6, 0.4])
    for _ in range(10):
        action = env.action_space.sample()
        obs, reward, _, _, info = env.step(action)
        tx, rx = action[:4].astype(bool), action[4:].astype(bool)
        if info["action_valid"]:
            mask = tx[:, None] & rx[None, :]
            assert reward == pytest.approx(np.einsum("k,kmn->", omega, obs["sinr"] * mask))
            assert np.array_equal(obs["probed"], mask.astype(np.int8))
            assert info["expected_reward"] == pytest.approx(
                np.einsum("k,kmn->", omega, info["mean_sinr"] * mask)
            )
        else:
            assert reward == 0 and info["expected_reward"] == 0 and not obs["probed"].any()
        # optimal reward: brute force over every super arm
        from itertools import combinations

        weights = np.einsum("k,kmn->mn", omega, info["mean_sinr"])
        best = max(
            weights[np.ix_(t, r)].sum() for t in combinations(range(4), 2) for r in combinations(range(6), 3)
        )
        assert info["optimal_reward"] == pytest.approx(best)
        assert info["optimal_reward"] >= info["expected_reward"]


def test_oracle_action_is_the_optimum_of_the_coming_step():
    venv = vector_env("MimoRadarSelect-v0", 4, scenario="paper-3")
    venv.reset(seed=1)
    for _ in range(5):
        oracle = venv.oracle_action()
        _, _, _, _, info = venv.step(oracle)
        np.testing.assert_array_equal(oracle, info["optimal_action"])
        np.testing.assert_allclose(info["expected_reward"], info["optimal_reward"])
    env = gym.make("MimoRadarSelect-v0")
    env.reset(seed=0)
    assert env.unwrapped.oracle_action().shape == (10,)


def test_sample_action_draws_valid_super_arms_uniformly_and_reproducibly():
    from math import comb

    from scipy import stats

    env = gym.make("MimoRadarSelect-v1")
    sc = env.unwrapped.scenario
    env.reset(seed=3)
    draws = np.array([env.unwrapped.sample_action() for _ in range(3000)])
    assert draws.dtype == np.int8 and draws.shape == (3000, sc.num_tx + sc.num_rx)
    assert (draws[:, : sc.num_tx].sum(1) == sc.tx_per_step).all()
    assert (draws[:, sc.num_tx :].sum(1) == sc.rx_per_step).all()
    _, counts = np.unique(draws, axis=0, return_counts=True)
    arms = comb(sc.num_tx, sc.tx_per_step) * comb(sc.num_rx, sc.rx_per_step)
    assert len(counts) == arms  # every super arm drawn, as often as the others (chi-square)
    assert stats.chisquare(counts).pvalue > 0.001
    env.reset(seed=3)
    np.testing.assert_array_equal(env.unwrapped.sample_action(), draws[0])
    obs, reward, *_, info = env.step(env.unwrapped.sample_action())
    assert info["action_valid"] and reward > 0
    venv = vector_env("MimoRadarSelect-v1", 4)
    venv.reset(seed=3)
    batch = venv.sample_action()
    assert batch.shape == (4, sc.num_tx + sc.num_rx) and venv.step(batch)[4]["action_valid"].all()


def test_invalid_actions_probe_nothing_or_raise():
    env = gym.make("MimoRadarSelect-v0")
    env.reset(seed=0)
    action = np.zeros(10, dtype=np.int8)
    action[[0, 1, 2, 4, 5, 6]] = 1  # three transmitters
    obs, reward, _, _, info = env.step(action)
    assert reward == 0.0 and not info["action_valid"] and not obs["probed"].any() and not obs["sinr"].any()
    strict = gym.make("MimoRadarSelect-v0", invalid_action="raise")
    strict.reset(seed=0)
    with pytest.raises(ValueError, match="selects 3 TX and 3 RX; exactly tx_per_step=2 and rx_per_step=3"):
        strict.step(action)


@pytest.mark.parametrize(
    ("action", "message"),
    [
        (np.zeros(9, dtype=np.int8), r"shape \(10,\)"),
        (np.zeros((1, 10), dtype=np.int8), r"shape \(10,\)"),
        (np.array(["1"] * 10), "dtype <U1"),
        (np.array([2, 0, 0, 0, 1, 1, 1, 0, 0, 0]), r"values must be 0 or 1, got \[2\]"),
        (np.array([np.nan, 1, 0, 0, 1, 1, 1, 0, 0, 0]), "NaN"),
    ],
)
def test_actions_outside_the_space_raise(action, message):
    env = gym.make("MimoRadarSelect-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


def test_vector_env_bad_actions_and_float_actions():
    venv = vector_env("MimoRadarSelect-v0", 2)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(2, 10\)"):
        venv.step(np.zeros((3, 10), dtype=np.int8))
    action = np.array([[1, 1, 0, 0, 1, 1, 1, 0, 0, 0]] * 2, dtype=np.float32)  # 0/1 floats are accepted
    _, _, _, _, info = venv.step(action)
    assert info["action_valid"].all()


def test_env_class_docstring_documents_the_sections():
    for section in (
        "## Description",
        "## Action Space",
        "## Observation Space",
        "## Rewards",
        "## Episode End",
        "## Arguments",
    ):
        assert section in MimoRadarSelectEnv.__doc__


def test_spec_max_episode_steps_is_the_horizon_and_the_repr_names_the_setup():
    env = gym.make("MimoRadarSelect-v1", horizon=37, fusion="centralized")
    assert env.spec.max_episode_steps == 37 and env.spec.kwargs["horizon"] == 37
    assert not any(w.name == "TimeLimit" for w in env.spec.additional_wrappers)
    env.reset(seed=0)
    steps, truncated = 0, False
    while not truncated:
        _, _, _, truncated, _ = env.step(env.unwrapped.oracle_action())
        steps += 1
    assert steps == 37
    text = repr(env.unwrapped)
    assert text.startswith("<MimoRadarSelectEnv<MimoRadarSelect-v1> scenario='paper-1-v1'")
    for option in ("fusion='centralized'", "lambda_scale='db'", "truth='shared'"):
        assert option in text
    assert "tracking" not in text  # options at their default are left out
    v0 = "<MimoRadarSelectEnv<MimoRadarSelect-v0> scenario='paper-1'>"
    assert str(gym.make("MimoRadarSelect-v0").unwrapped) == v0
    assert gym.make("MimoRadarSelect-v0").spec.max_episode_steps == 1000
    remade = gym.make(env.spec)  # a spec recreates the env; its TimeLimit agrees with the horizon
    assert remade.spec.max_episode_steps == 37
    vec = vector_env("MimoRadarSelect-v1", 2)
    assert repr(vec).endswith("truth='shared', num_envs=2>")


def test_measurements_in_info_are_eq6_plus_noise_of_the_stated_covariance():
    from mimo_radar_env.core.geometry import bistatic_measurement

    env = gym.make("MimoRadarSelect-v1", measurements=True, horizon=301)
    _, info = env.reset(seed=3)
    assert "measurement" not in info  # nothing is measured at reset
    sc = env.unwrapped.scenario
    rng = np.random.default_rng(0)
    normalised = []
    for action in random_valid_actions(rng, 300, sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step):
        _, _, _, _, info = env.step(action)
        tx, rx = sc.tx_positions[info["measurement_tx"]], sc.rx_positions[info["measurement_rx"]]
        assert set(zip(info["measurement_tx"], info["measurement_rx"], strict=True)) == {
            (m, n) for m in np.flatnonzero(action[: sc.num_tx]) for n in np.flatnonzero(action[sc.num_tx :])
        }
        truth = info["true_state"][:, None, [0, 2]]  # (K, 1, 2)
        clean = bistatic_measurement(truth, tx[None], rx[None])  # (K, C, 2)
        cov = info["measurement_covariance"]
        assert np.all(cov[..., 0, 1] == 0) and np.all(cov[..., 1, 0] == 0)
        # filter_noise="true": Sigma0 / lambda, lambda from eq32 on dB of the true mean SINR
        mean = info["mean_sinr"][:, info["measurement_tx"], info["measurement_rx"]]  # (K, C)
        s_min = env.unwrapped.engine.model.min_sinr[:, None]
        lam = np.clip(np.log10(mean / s_min) / np.log10(sc.peak_sinr / s_min) + 0.2, 0.2, 1.2)
        np.testing.assert_allclose(cov[..., 0, 0], sc.range_variance / lam, rtol=1e-12)
        np.testing.assert_allclose(cov[..., 1, 1], sc.azimuth_variance / lam, rtol=1e-12)
        error = info["measurement"] - clean
        error[..., 1] = np.angle(np.exp(1j * error[..., 1]))
        normalised.append(error / np.sqrt(np.diagonal(cov, axis1=-2, axis2=-1)))
    z = np.concatenate([n.reshape(-1, 2) for n in normalised])
    assert z.shape == (300 * 6, 2)
    assert abs(z.mean()) < 0.06 and abs(z.std() - 1) < 0.04  # standard normal, 3600 draws
    _, _, _, _, info = env.step(np.zeros(sc.num_tx + sc.num_rx, np.int8))
    assert np.isnan(info["measurement"]).all() and np.isnan(info["measurement_covariance"]).all()


def test_information_reward_is_the_trackers_log_det_reduction_and_info_has_both_terms():
    for reward_kind in ("sinr", "information"):
        env = gym.make("MimoRadarSelect-v1", scenario="paper-3-v1", reward=reward_kind).unwrapped
        obs, _ = env.reset(seed=2)
        weights = env.scenario.weights
        rng = np.random.default_rng(0)
        sc = env.scenario
        for step, action in enumerate(random_valid_actions(rng, 40, sc.num_tx, sc.num_rx, 2, 3)):
            if step == 5:
                action = np.zeros_like(action)  # probes nothing: no information, no SINR
            tracker = env.engine.tracker
            predicted = tracker.predicted_covariance()[..., [0, 2], :][..., [0, 2]][0]  # before the step
            obs, reward, _, _, info = env.step(action)
            posterior = tracker.covariance[0][..., [0, 2], :][..., [0, 2]]
            gain = sum(
                weights[k] * (np.log(np.linalg.det(predicted[k])) - np.log(np.linalg.det(posterior[k])))
                for k in range(sc.num_targets)
            )
            sinr = np.einsum("k,kmn->", weights, obs["sinr"])  # eq17 from the observed samples
            assert info["reward_information"] == pytest.approx(gain, rel=1e-8, abs=1e-10)
            assert info["reward_sinr"] == pytest.approx(sinr, rel=1e-12)
            assert reward == (
                info["reward_information"] if reward_kind == "information" else info["reward_sinr"]
            )
            if step == 5:
                assert reward == 0 and info["reward_information"] == pytest.approx(0, abs=1e-12)
            else:
                assert info["reward_information"] > 0  # a measurement shrinks the position uncertainty
    with pytest.raises(ValueError, match="needs tracking=True"):
        gym.make("MimoRadarSelect-v1", reward="information", tracking=False)
