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
