import os

import matplotlib
import pytest

matplotlib.use("Agg")
# time estimates at the developers' machine's speed, whatever a `compile` measured on this one
# (benchmarks.machine_rate); the tests that calibrate name a file of their own
os.environ["MIMO_RADAR_RATE_FILE"] = ""

import mimo_radar_env


@pytest.fixture(scope="session")
def paper1():
    return mimo_radar_env.load_scenario("paper-1")


@pytest.fixture(scope="module")
def small_model(tmp_path_factory):
    """A PPO of train-ppo trained for 128 steps on paper-1-v1 (its folder), once per module."""
    pytest.importorskip("stable_baselines3", reason="PPO needs the rl extra")
    from benchmarks.training import train_ppo

    folder = tmp_path_factory.mktemp("ppo") / "small"
    train_ppo("paper-1-v1", 128, folder, seed=0, progress=False)
    return folder
