"""Scenarios: the paper's against the specification, overrides through gym.make, and each bad field
with its error."""

import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from mimo_radar_env import Scenario, ScenarioError, available_scenarios, load_scenario
from mimo_radar_env.scenarios import turn_rate_schedule


def test_paper_scenarios_match_spec():
    assert {"paper-1", "paper-2", "paper-3"} <= set(available_scenarios())
    s1, s2, s3 = (load_scenario(f"paper-{i}") for i in (1, 2, 3))
    for s in (s1, s2, s3):
        assert (s.num_tx, s.num_rx, s.tx_per_step, s.rx_per_step) == (4, 6, 2, 3)
        assert s.horizon == 1000 and s.sample_time == 1.0 and s.process_noise == 0.1
        np.testing.assert_array_equal(s.tx_positions[2], [75_000, 95_000])
        np.testing.assert_array_equal(s.rx_positions[5], [100_000, 25_000])
        np.testing.assert_allclose(s.interference_power, 0.5e-21)
        np.testing.assert_allclose(s.measurement_covariance, np.diag([5.0, 0.002]))
    np.testing.assert_array_equal(s1.targets[0].initial_state, [5, 100, 5, 100])
    np.testing.assert_array_equal(s1.targets[0].initial_covariance, np.diag([20.0] * 4))
    assert s1.targets[0].maneuvers == ()
    rates = turn_rate_schedule(s2)
    assert rates[0, 399] == 0 and math.isclose(rates[0, 400], math.radians(3)) and rates[0, 440] == 0
    assert math.isclose(rates[0, 639], -math.radians(3)) and rates[0, 640] == 0
    assert s3.num_targets == 2
    np.testing.assert_array_equal(s3.weights, [0.6, 0.4])
    np.testing.assert_array_equal(s3.targets[1].initial_state, [10, 50, 100_010, 0])


def test_overrides_through_gym_make():
    env = gym.make("MimoRadarSelect-v0", scenario="paper-1", horizon=7, tx_per_step=1)
    scenario = env.unwrapped.scenario
    assert scenario.horizon == 7 and scenario.tx_per_step == 1
    # an unknown keyword is a TypeError naming it, as in any Gymnasium env
    with pytest.raises(TypeError, match="unexpected keyword argument 'horizn'.*env options.*scenario fields"):
        gym.make("MimoRadarSelect-v0", horizn=7)


def _paper(**changes):
    data = load_scenario("paper-1").to_dict()
    data.update(changes)
    return data


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"tx_per_step": 5}, r"tx_per_step must be between 1 and 4"),
        ({"rx_per_step": 0}, r"rx_per_step must be between 1 and 6"),
        ({"rx_per_step": 7}, r"rx_per_step must be between 1 and 6"),
        ({"tx_power": -1.0}, r"tx_power must be > 0"),
        ({"tx_power": [1.0, 2.0]}, r"tx_power must be a single number or an array of shape \(4,\)"),
        ({"noise_power": 0.0}, r"noise_power must be > 0"),
        ({"sample_time": -1.0}, r"sample_time must be > 0"),
        ({"interference_power": -1e-21}, r"interference_power must be >= 0"),
        ({"weights": [-1.0]}, r"weights must be >= 0"),
        ({"weights": [0.5, 0.5]}, r"weights must hold one value per target \(1\)"),
        ({"tx_positions": [[0, 0], [0, 0], [1, 1], [2, 2]]}, r"tx_positions has duplicate stations 0 and 1"),
        ({"range_variance": float("nan")}, r"range_variance must be finite"),
        ({"rx_positions": [[1.0, float("inf")]]}, r"rx_positions must be finite"),
        ({"colour": "red"}, r"unknown scenario key\(s\) \['colour'\]"),
        ({"horizon": 0}, r"horizon must be between 1 and 1000000"),
        ({"horizon": 2.5}, r"horizon must be an integer"),
        (
            {"targets": [{"initial_state": [0, 1, 35_000, 0]}]},
            r"targets\[0\].initial_state puts the target on a station",
        ),
        (
            {
                "targets": [
                    {
                        "initial_state": [5, 1, 5, 1],
                        "maneuvers": [{"turn_rate_deg": 3, "start": 990, "stop": 1001}],
                    }
                ]
            },
            r"targets\[0\].maneuvers\[0\] window \[990, 1001\) must lie in \[0, horizon=1000\)",
        ),
        (
            {
                "targets": [
                    {
                        "initial_state": [5, 1, 5, 1],
                        "maneuvers": [{"turn_rate_deg": 3, "start": -1, "stop": 10}],
                    }
                ]
            },
            r"targets\[0\].maneuvers\[0\].start must be >= 0",
        ),
        ({"targets": [{"initial_state": [5, 1, 5]}]}, r"initial_state must be \[x, vx, y, vy\]"),
        (
            {"targets": [{"initial_state": [5, 1, 5, 1], "speed": 3}]},
            r"unknown key\(s\) \['speed'\] in targets\[0\]",
        ),
        (
            {"targets": [{"initial_state": [5, 1, 5, 1], "initial_covariance": [1, -1, 1, 1]}]},
            r"positive definite",
        ),
        ({"targets": []}, r"targets must be a non-empty list"),
    ],
)
def test_each_bad_field_has_its_error(changes, message):
    with pytest.raises(ScenarioError, match=message):
        Scenario.from_dict(_paper(**changes))


def test_unknown_scenario_name_lists_the_shipped_ones():
    import mimo_radar_env.scenarios as package

    shipped = sorted(p.stem for p in Path(package.__file__).parent.glob("*.toml"))
    assert {"paper-1", "paper-2", "paper-3", "paper-1-v1", "paper-2-v1", "paper-3-v1"} <= set(shipped)
    with pytest.raises(ScenarioError) as error:
        load_scenario("paper-9")
    assert f"not a shipped scenario ({', '.join(shipped)})" in str(error.value)


def test_missing_required_key():
    data = _paper()
    del data["tx_positions"]
    with pytest.raises(ScenarioError, match=r"missing required key\(s\) \['tx_positions'\]"):
        Scenario.from_dict(data)


def test_scenarios_compare_by_value_field_by_field():
    """``==`` on two scenarios compares their arrays by value (the dataclass's own ``__eq__``
    raised on an array's truth value), down to the targets' states and covariances."""
    from mimo_radar_env.scenarios.scenario import field_differences

    one = load_scenario("paper-1-v1")
    assert one == load_scenario("paper-1-v1") and one == Scenario.from_dict(one.to_dict())
    assert one != load_scenario("paper-1-v1", horizon=5) and one != "paper-1-v1"
    assert field_differences(one, load_scenario("paper-1-v1", horizon=5, peak_sinr=20.0)) == [
        "horizon",
        "peak_sinr",
    ]
    moved = one.to_dict()
    moved["targets"][0]["initial_state"][0] += 1.0
    assert field_differences(one, Scenario.from_dict(moved)) == ["targets"]
    assert one.targets[0] != Scenario.from_dict(moved).targets[0]
