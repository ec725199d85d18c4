"""Scenario files: a round trip through YAML and TOML, and user files."""

from pathlib import Path

import gymnasium as gym
import pytest

import mimo_radar_env.scenarios
from mimo_radar_env import Scenario, load_scenario
from mimo_radar_env.scenarios.validation import ScenarioError


def test_round_trip_and_user_files(tmp_path: Path):
    s = load_scenario("paper-3")
    again = Scenario.from_dict(s.to_dict())
    assert again.to_dict() == s.to_dict()
    toml_file = tmp_path / "mine.toml"
    toml_file.write_text(
        "tx_positions = [[0, 0], [1000, 0], [0, 1000]]\n"
        "rx_positions = [[500, 500], [2000, 2000]]\n"
        "tx_per_step = 1\nrx_per_step = 1\nhorizon = 50\n"
        "[[targets]]\ninitial_state = [100, 1, 900, 0]\n"
    )
    mine = load_scenario(toml_file)
    assert mine.name == "mine" and mine.num_tx == 3 and mine.horizon == 50
    yaml_file = tmp_path / "mine.yaml"
    yaml_file.write_text(
        "tx_positions: [[0, 0], [1000, 0]]\nrx_positions: [[500, 500]]\n"
        "tx_per_step: 2\nrx_per_step: 1\n"
        "targets:\n  - initial_state: [100, 1, 900, 0]\n    maneuvers:\n"
        "      - {turn_rate_deg: 2, start: 3, stop: 9}\n"
    )
    assert load_scenario(yaml_file).targets[0].maneuvers[0].stop == 9
    env = gym.make("MimoRadarSelect-v0", scenario=str(toml_file))
    obs, _ = env.reset(seed=1)
    assert obs["sinr"].shape == (1, 3, 2)


@pytest.mark.parametrize(
    ("file", "name"),
    [("my layout.toml", "my-layout"), ("v1+jitter.2.toml", "v1+jitter.2"), ("...toml", "custom")],
)
def test_a_file_without_a_name_is_named_after_the_file_as_far_as_a_name_may_be(tmp_path, file, name):
    text = (Path(mimo_radar_env.scenarios.__file__).parent / "paper-1-v1.toml").read_text()
    path = tmp_path / file
    path.write_text("\n".join(line for line in text.splitlines() if not line.startswith("name =")))
    assert load_scenario(path).name == name


@pytest.mark.parametrize("given", [None, 3, b"paper-1-v1", ["paper-1-v1"]])
def test_a_scenario_that_is_no_name_path_or_scenario_is_refused_by_its_type(given):
    """It was read as ``str(given)``: "unknown scenario 'None'" for ``scenario=None``, as if
    "None" were a name that could have existed."""
    message = rf"a path to a \.toml/\.yaml file or a Scenario, got {type(given).__name__} "
    with pytest.raises(ScenarioError, match=message):
        load_scenario(given)
    with pytest.raises(ScenarioError, match=message):
        gym.make("MimoRadarSelect-v1", scenario=given)
