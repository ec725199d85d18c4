"""The Gymnasium environments and their options."""

from .engine import RadarEngine, check_actions
from .mimo_radar_select import MimoRadarSelectEnv, MimoRadarSelectVectorEnv, observation_space
from .options import DEFAULT_SCENARIO, EnvOptions, default_config

__all__ = [
    "DEFAULT_SCENARIO",
    "EnvOptions",
    "MimoRadarSelectEnv",
    "MimoRadarSelectVectorEnv",
    "RadarEngine",
    "check_actions",
    "default_config",
    "observation_space",
]
