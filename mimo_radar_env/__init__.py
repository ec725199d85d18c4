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

#: The env id of the default version (``MimoRadarSelect-v1``).
ENV_ID = ENV_IDS[DEFAULT_VERSION]

for _version in VERSIONS.values():
    for _id, _entry, _vector in (
        (_version.env_id, "envs:MimoRadarSelectEnv", "envs:MimoRadarSelectVectorEnv"),
        (_version.flat_env_id, "wrappers:make_flat_env", "wrappers:MimoRadarSelectFlatVectorEnv"),
    ):
        if _id not in registry:
            register(
                id=_id,
                entry_point=f"mimo_radar_env.{_entry}",
                vector_entry_point=f"mimo_radar_env.{_vector}",
                kwargs=_version.registration_kwargs(),
            )

#: The package's version: written here only (pyproject.toml reads it).
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
