"""Random layouts are valid, reproducible and keep the tracks off the stations."""

import numpy as np


def test_random_layouts_are_valid_reproducible_and_keep_tracks_off_the_stations():
    from mimo_radar_env import random_scenario
    from mimo_radar_env.core.model import RadarModel
    from mimo_radar_env.scenarios.scenario import closest_approach

    first = random_scenario(7, 9, 3, 2, 3, horizon=120, seed=4)
    again = random_scenario(7, 9, 3, 2, 3, horizon=120, seed=4)
    other = random_scenario(7, 9, 3, 2, 3, horizon=120, seed=5)
    assert first.to_dict() == again.to_dict() and first.to_dict() != other.to_dict()
    assert (first.num_tx, first.num_rx, first.num_targets, first.tx_per_step, first.rx_per_step) == (
        7,
        9,
        3,
        2,
        3,
    )
    stations = np.concatenate([first.tx_positions, first.rx_positions])
    assert np.all((stations >= 0) & (stations <= 100e3))
    model = RadarModel.from_scenario(first)
    for k in range(first.num_targets):
        distance, _, _ = closest_approach(model.nominal[k][:, [0, 2]], stations)
        assert distance > 0
    turning = [t for t in first.to_dict()["targets"] if t.get("maneuvers")]
    assert len(turning) == 2  # the 1st and 3rd targets turn at -3 deg/s from horizon // 3
