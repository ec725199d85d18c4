import matplotlib
import pytest

matplotlib.use("Agg")

import mimo_radar_env  # noqa: E402  (registers the env)


@pytest.fixture(scope="session")
def paper1():
    return mimo_radar_env.load_scenario("paper-1")
