"""The simulation's draws: SINR samples exponential with their mean, measurement residuals with
covariance sigma0 / lambda."""

import numpy as np
from scipy import stats

from tests.helpers import simulation, vector_env


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
    batch = 3000
    model, sim = simulation("paper-3", batch, seed=4)
    scenario = model.scenario
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
