"""mimo-radar-env: a Gymnasium testbed for transmitter/receiver selection in distributed MIMO radar.

Importing the package registers ``MimoRadarSelect-v0`` (idempotently).
"""

from gymnasium.envs.registration import register, registry

from .core.model import RadarModel
from .envs import EnvOptions, MimoRadarSelectEnv, MimoRadarSelectVectorEnv, default_config
from .scenarios import (
    Maneuver,
    Scenario,
    ScenarioError,
    Target,
    available_scenarios,
    load_scenario,
    random_scenario,
)

ENV_ID = "MimoRadarSelect-v0"

if ENV_ID not in registry:
    register(
        id=ENV_ID,
        entry_point="mimo_radar_env.envs:MimoRadarSelectEnv",
        vector_entry_point="mimo_radar_env.envs:MimoRadarSelectVectorEnv",
    )

__version__ = "0.1.0"

__all__ = [
    "ENV_ID",
    "EnvOptions",
    "Maneuver",
    "MimoRadarSelectEnv",
    "MimoRadarSelectVectorEnv",
    "RadarModel",
    "Scenario",
    "ScenarioError",
    "Target",
    "available_scenarios",
    "default_config",
    "load_scenario",
    "random_scenario",
]
