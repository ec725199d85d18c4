"""The simulation core against the model's formulas (docs/model.md) computed independently here."""

import gymnasium as gym
import numpy as np
from scipy import stats

from mimo_radar_env import RadarModel, load_scenario
from mimo_radar_env.core.simulation import RadarSimulation
from mimo_radar_env.core.streams import keys_from_generator
from mimo_radar_env.core.superarm import exact_super_arm
from tests.helpers import vector_env


def spec_mean_sinr(scenario, constant, positions):
    """eq5 with the scenario constant written out, positions (K, 2):
    C psi P / ((R_tx R_rx)^2 (noise + interference))."""
    out = np.zeros((scenario.num_targets, scenario.num_tx, scenario.num_rx))
    for k, (x, y) in enumerate(positions):
        for m, (xt, yt) in enumerate(scenario.tx_positions):
            for n, (xr, yr) in enumerate(scenario.rx_positions):
                r_tx = np.hypot(x - xt, y - yt)
                r_rx = np.hypot(x - xr, y - yr)
                out[k, m, n] = (
                    constant
                    * scenario.rcs[k, m, n]
                    * scenario.tx_power[m]
                    / ((r_tx * r_rx) ** 2 * (scenario.noise_power + scenario.interference_power[n]))
                )
    return out


def spec_constant_paper1(scenario):
    """C for paper-1: the nominal NCV track x(t) = x0 + v t, every step 0..T."""
    x0 = scenario.targets[0].initial_state
    t = np.arange(scenario.horizon + 1)
    px, py = x0[0] + x0[1] * t, x0[2] + x0[3] * t
    r_tx = np.hypot(px[:, None] - scenario.tx_positions[:, 0], py[:, None] - scenario.tx_positions[:, 1])
    r_rx = np.hypot(px[:, None] - scenario.rx_positions[:, 0], py[:, None] - scenario.rx_positions[:, 1])
    raw = 1000.0 / ((r_tx[:, :, None] * r_rx[:, None, :]) ** 2 * (1e-26 + 0.5e-21))
    return 10.0 / raw.max()


def test_mean_sinr_equals_spec_formula_from_info():
    env = gym.make("MimoRadarSelect-v0", scenario="paper-3")
    _, info = env.reset(seed=5)
    scenario = env.unwrapped.scenario
    constant = env.unwrapped.engine.model.sinr_constant
    rng = np.random.default_rng(0)
    for _ in range(5):
        _, _, _, _, info = env.step(env.action_space.sample())
        state = info["true_state"]
        expected = spec_mean_sinr(scenario, constant, state[:, [0, 2]])
        np.testing.assert_allclose(info["mean_sinr"], expected, rtol=1e-12)
    del rng


def test_constant_puts_the_peak_at_ten():
    scenario = load_scenario("paper-1")
    model = RadarModel.from_scenario(scenario)
    np.testing.assert_allclose(model.sinr_constant, spec_constant_paper1(scenario), rtol=1e-12)
    for name in ("paper-1", "paper-2", "paper-3"):
        model = RadarModel.from_scenario(load_scenario(name))
        nominal = np.swapaxes(model.nominal[..., [0, 2]], 0, 1)  # (T+1, K, 2)
        sinr = model.mean_sinr(nominal)
        np.testing.assert_allclose(sinr.max(), 10.0, rtol=1e-12)
        np.testing.assert_allclose(sinr.min(axis=(0, 2, 3)), model.min_sinr, rtol=1e-12)


def test_optimal_super_arms_on_the_noise_free_track():
    model = RadarModel.from_scenario(load_scenario("paper-1"))
    for t, best_tx, best_rx in ((100, [0, 1], [0, 1, 2]), (800, [2, 3], [1, 3, 4])):
        sinr = model.mean_sinr(model.nominal[None, :, t, [0, 2]])
        tx, rx, _ = exact_super_arm(model.channel_weights(sinr), 2, 3)
        assert np.flatnonzero(tx[0]).tolist() == best_tx
        assert np.flatnonzero(rx[0]).tolist() == best_rx


def test_sinr_samples_are_exponential_with_the_mean_sinr():
    venv = vector_env("MimoRadarSelect-v0", 400)
    obs, info = venv.reset(seed=11)
    ratio = (obs["sinr"] / info["mean_sinr"]).ravel()  # every channel probed at reset
    assert stats.kstest(ratio, "expon").pvalue > 0.01
    rng = np.random.default_rng(1)
    ratios = []
    for _ in range(5):
        action = venv.action_space.sample()
        action[:] = 0
        tx = np.argsort(rng.random((400, 4)), axis=1)[:, :2]
        rx = np.argsort(rng.random((400, 6)), axis=1)[:, :3]
        np.put_along_axis(action, tx, 1, axis=1)
        np.put_along_axis(action, 4 + rx, 1, axis=1)
        obs, _, _, _, info = venv.step(action)
        probed = obs["probed"][:, None].astype(bool)
        ratios.append(obs["sinr"][probed] / info["mean_sinr"][probed])
    ratios = np.concatenate(ratios)
    assert ratios.size == 5 * 400 * 6
    assert stats.kstest(ratios, "expon").pvalue > 0.01


def test_measurement_residuals_have_covariance_sigma0_over_lambda():
    scenario = load_scenario("paper-3")
    model = RadarModel.from_scenario(scenario)
    batch = 3000
    sim = RadarSimulation(model, batch)
    rng = np.random.default_rng(4)
    sim.reset(np.stack([keys_from_generator(rng) for _ in range(batch)]))
    sim.advance()
    tx_index = np.tile([1, 3], (batch, 1))
    rx_index = np.tile([0, 2, 5], (batch, 1))
    obs = sim.observe(tx_index, rx_index, np.ones(batch, dtype=bool))
    # independent lambda of eq32 and the residuals
    s_max = 10.0
    lam = np.clip(
        (obs.mean_sinr - model.min_sinr[None, :, None]) / (s_max - model.min_sinr[None, :, None]) + 0.2,
        0.2,
        1.2,
    )
    np.testing.assert_allclose(obs.noise_variance[..., 0], 5.0 / lam, rtol=1e-12)
    np.testing.assert_allclose(obs.noise_variance[..., 1], 0.002 / lam, rtol=1e-12)
    pos = sim.state[..., [0, 2]][:, :, None, :]
    tx = scenario.tx_positions[obs.tx_index][:, None]
    rx = scenario.rx_positions[obs.rx_index][:, None]
    true_range = np.linalg.norm(pos - tx, axis=-1) + np.linalg.norm(pos - rx, axis=-1)
    true_azimuth = np.arctan2(pos[..., 1] - rx[..., 1], pos[..., 0] - rx[..., 0])
    res_r = (obs.measurement[..., 0] - true_range) / np.sqrt(obs.noise_variance[..., 0])
    res_a = np.angle(np.exp(1j * (obs.measurement[..., 1] - true_azimuth))) / np.sqrt(
        obs.noise_variance[..., 1]
    )
    for res in (res_r.ravel(), res_a.ravel()):
        assert abs(res.mean()) < 4 / np.sqrt(res.size)
        assert stats.kstest(res, "norm").pvalue > 0.01
    assert abs(np.corrcoef(res_r.ravel(), res_a.ravel())[0, 1]) < 4 / np.sqrt(res_r.size)


def test_truth_follows_the_motion_model():
    """Increments of the truth have the process-noise covariance Q = G diag(Qs, Qs) G'."""
    scenario = load_scenario("paper-1")
    model = RadarModel.from_scenario(scenario)
    batch = 4000
    sim = RadarSimulation(model, batch)
    rng = np.random.default_rng(2)
    sim.reset(np.stack([keys_from_generator(rng) for _ in range(batch)]))
    start = sim.state.copy()
    np.testing.assert_allclose(
        np.cov(start[:, 0].T), np.diag([20.0] * 4), atol=1.5
    )  # 4.7 sigma of a sample covariance
    sim.advance()
    F = np.array([[1, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1.0]])
    noise = sim.state[:, 0] - start[:, 0] @ F.T
    Q = 0.1 * np.array([[0.25, 0.5, 0, 0], [0.5, 1, 0, 0], [0, 0, 0.25, 0.5], [0, 0, 0.5, 1]])
    np.testing.assert_allclose(np.cov(noise.T), Q, atol=0.012)
