"""The Gymnasium environments and their options."""

from .engine import RadarEngine, check_actions
from .mimo_radar_select import MimoRadarSelectEnv, MimoRadarSelectVectorEnv, observation_space
from .options import DEFAULT_SCENARIO, EnvOptions
from .versions import DEFAULT_VERSION, VERSIONS, EnvVersion, default_config, env_version

__all__ = [
    "DEFAULT_SCENARIO",
    "DEFAULT_VERSION",
    "VERSIONS",
    "EnvOptions",
    "EnvVersion",
    "MimoRadarSelectEnv",
    "MimoRadarSelectVectorEnv",
    "RadarEngine",
    "check_actions",
    "default_config",
    "env_version",
    "observation_space",
]
