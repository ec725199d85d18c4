"""The optimal super arms on paper Scenario 1's noise-free track."""

import numpy as np

from mimo_radar_env import RadarModel, load_scenario
from mimo_radar_env.core.superarm import exact_super_arm


def test_optimal_super_arms_on_the_noise_free_track():
    model = RadarModel.from_scenario(load_scenario("paper-1"))
    for t, best_tx, best_rx in ((100, [0, 1], [0, 1, 2]), (800, [2, 3], [1, 3, 4])):
        sinr = model.mean_sinr(model.nominal[None, :, t, [0, 2]])
        tx, rx, _ = exact_super_arm(model.channel_weights(sinr), 2, 3)
        assert np.flatnonzero(tx[0]).tolist() == best_tx
        assert np.flatnonzero(rx[0]).tolist() == best_rx
