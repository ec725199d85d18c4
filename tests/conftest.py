import matplotlib
import pytest

matplotlib.use("Agg")

import mimo_radar_env


@pytest.fixture(scope="session")
def paper1():
    return mimo_radar_env.load_scenario("paper-1")
