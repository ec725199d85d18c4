"""Scenarios as validated data: the paper's three ship with the package (``paper-1``,
``paper-2``, ``paper-3``, TOML files in this folder); users load their own from YAML or
TOML with :func:`load_scenario`, build one in Python with :meth:`Scenario.from_dict`, or
draw a random layout with :func:`random_scenario`."""

from .files import available_scenarios, load_scenario
from .random_layouts import random_scenario
from .scenario import MAX_HORIZON, MIN_STATION_DISTANCE, Maneuver, Scenario, Target, turn_rate_schedule
from .validation import ScenarioError

__all__ = [
    "MAX_HORIZON",
    "MIN_STATION_DISTANCE",
    "Maneuver",
    "Scenario",
    "ScenarioError",
    "Target",
    "available_scenarios",
    "load_scenario",
    "random_scenario",
    "turn_rate_schedule",
]
