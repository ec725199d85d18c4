"""The Gymnasium environments."""

from .engine import RadarEngine, check_actions, default_config
from .mimo_radar_select import MimoRadarSelectEnv, MimoRadarSelectVectorEnv, observation_space

__all__ = [
    "MimoRadarSelectEnv",
    "MimoRadarSelectVectorEnv",
    "RadarEngine",
    "check_actions",
    "default_config",
    "observation_space",
]
