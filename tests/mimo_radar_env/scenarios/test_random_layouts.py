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


def test_random_layouts_refuse_bad_arguments_in_one_line_before_drawing():
    """Each argument is checked before any draw: a negative count, a float, a seed or an extent
    out of range came back as numpy's errors ('negative dimensions are not allowed', 'high - low
    < 0'), and a million stations as a MemoryError of 14.6 TiB."""
    import pytest

    from mimo_radar_env import ScenarioError, random_scenario

    sizes = {"num_tx": 4, "num_rx": 6, "num_targets": 1, "tx_per_step": 2, "rx_per_step": 3}
    for changes, message in [
        ({"num_tx": -2}, r"num_tx must be between 1 and 1000 \(a number of transmitters\), got -2"),
        ({"num_rx": 10**6}, r"num_rx must be between 1 and 1000 \(a number of receivers\), got 1000000"),
        ({"num_tx": 2.5}, r"num_tx must be an integer, got 2.5"),
        ({"num_targets": 10**9}, r"num_targets must be between 1 and 100 \(a number of targets\)"),
        ({"horizon": "5"}, r"horizon must be an integer, got '5'"),
        ({"seed": -1}, r"seed must be between 0 and 9223372036854775807 \(a seed\), got -1"),
        ({"extent": -1.0}, r"extent must be in \(0, 1e\+08\] m, got -1.0"),
        ({"extent": float("nan")}, r"extent must be finite numbers, got nan"),
    ]:
        with pytest.raises(ScenarioError, match=message):
            random_scenario(**{**sizes, **changes})


def test_a_scenario_holds_at_most_a_thousand_stations_a_side():
    """Its pairwise check of the stations grows with their square: 40,000 (a 1 MiB file holds
    that many) would need 40,000^2 x 2 float64, 25.6 GB. 1,000 a side is accepted."""
    import pytest

    from mimo_radar_env import ScenarioError, load_scenario

    row = [[100.0 * i, -50_000.0] for i in range(1001)]
    with pytest.raises(ScenarioError, match="rx_positions may hold at most 1000 stations, got 1001"):
        load_scenario("paper-1-v1", rx_positions=row)
    assert load_scenario("paper-1-v1", rx_positions=row[:1000], interference_power=0.5e-21).num_rx == 1000
