"""mimo-radar-env: a Gymnasium testbed for transmitter/receiver selection in distributed MIMO radar.

Importing the package registers ``MimoRadarSelect-v0`` (reading 0 of the paper's ambiguous
points, unchanged since its release) and ``MimoRadarSelect-v1`` (reading 1), idempotently.
"""

from gymnasium.envs.registration import register, registry

from .core.model import RadarModel
from .envs import (
    DEFAULT_VERSION,
    VERSIONS,
    EnvOptions,
    EnvVersion,
    MimoRadarSelectEnv,
    MimoRadarSelectVectorEnv,
    default_config,
    env_version,
)
from .envs.versions import (
    ENV_IDS,
    FLAT_ENV_IDS,
    PAPER_SCENARIOS,
    SCENARIO_SETS,
    VERSION_DEFAULTS,
    paper_scenario,
)
from .scenarios import (
    Maneuver,
    Scenario,
    ScenarioError,
    Target,
    available_scenarios,
    load_scenario,
    random_scenario,
)

ENV_ID = ENV_IDS["v0"]

for _version in VERSIONS.values():
    if _version.env_id not in registry:
        register(
            id=_version.env_id,
            entry_point="mimo_radar_env.envs:MimoRadarSelectEnv",
            vector_entry_point="mimo_radar_env.envs:MimoRadarSelectVectorEnv",
            kwargs=_version.registration_kwargs(),
        )
    if _version.flat_env_id not in registry:
        register(
            id=_version.flat_env_id,
            entry_point="mimo_radar_env.wrappers:make_flat_env",
            vector_entry_point="mimo_radar_env.wrappers:MimoRadarSelectFlatVectorEnv",
            kwargs=_version.registration_kwargs(),
        )

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_VERSION",
    "ENV_ID",
    "ENV_IDS",
    "FLAT_ENV_IDS",
    "PAPER_SCENARIOS",
    "SCENARIO_SETS",
    "VERSIONS",
    "VERSION_DEFAULTS",
    "EnvOptions",
    "EnvVersion",
    "Maneuver",
    "MimoRadarSelectEnv",
    "MimoRadarSelectVectorEnv",
    "RadarModel",
    "Scenario",
    "ScenarioError",
    "Target",
    "available_scenarios",
    "default_config",
    "env_version",
    "load_scenario",
    "paper_scenario",
    "random_scenario",
]
