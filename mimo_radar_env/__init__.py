"""mimo-radar-env: a Gymnasium testbed for transmitter/receiver selection in distributed MIMO radar.

Importing the package registers ``MimoRadarSelect-v0`` (reading 0 of the paper's ambiguous
points, unchanged since its release) and ``MimoRadarSelect-v1`` (reading 1), idempotently.
"""

from gymnasium.envs.registration import register, registry

from .core.model import RadarModel
from .envs import EnvOptions, MimoRadarSelectEnv, MimoRadarSelectVectorEnv, default_config
from .envs.options import ENV_IDS, FLAT_ENV_IDS, PAPER_SCENARIOS, VERSION_DEFAULTS, paper_scenario
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

for _version, _env_id in ENV_IDS.items():
    if _env_id not in registry:
        register(
            id=_env_id,
            entry_point="mimo_radar_env.envs:MimoRadarSelectEnv",
            vector_entry_point="mimo_radar_env.envs:MimoRadarSelectVectorEnv",
            kwargs={**VERSION_DEFAULTS[_version], "scenario": PAPER_SCENARIOS[_version][0]},
        )
    if FLAT_ENV_IDS[_version] not in registry:
        register(
            id=FLAT_ENV_IDS[_version],
            entry_point="mimo_radar_env.wrappers:make_flat_env",
            kwargs={**VERSION_DEFAULTS[_version], "scenario": PAPER_SCENARIOS[_version][0]},
        )

__version__ = "0.1.0"

__all__ = [
    "ENV_ID",
    "ENV_IDS",
    "FLAT_ENV_IDS",
    "PAPER_SCENARIOS",
    "VERSION_DEFAULTS",
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
    "paper_scenario",
    "random_scenario",
]
