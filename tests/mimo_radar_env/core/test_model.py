"""The radar model: the mean SINR against the specification's formula, and the constant that puts
the peak at 10."""

import gymnasium as gym
import numpy as np

from mimo_radar_env import RadarModel, load_scenario


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


def test_the_nominal_tracks_and_their_channel_weights_follow_the_formulas():
    """paper-1's one target moves straight (NCV): its nominal positions are x0 + v t at every
    step, and each channel's nominal weight is Omega S (eq5) there."""
    scenario = load_scenario("paper-1")
    model = RadarModel.from_scenario(scenario)
    x0 = scenario.targets[0].initial_state
    t = np.arange(scenario.horizon + 1)
    track = np.stack([x0[0] + x0[1] * t, x0[2] + x0[3] * t], axis=-1)[:, None]  # (T+1, 1, 2)
    np.testing.assert_allclose(model.nominal_positions, track, rtol=1e-12)
    steps = range(0, scenario.horizon + 1, 50)
    expected = [
        scenario.weights[0] * spec_mean_sinr(scenario, model.sinr_constant, track[i])[0] for i in steps
    ]
    np.testing.assert_allclose(model.nominal_channel_weights()[steps], expected, rtol=1e-12)
