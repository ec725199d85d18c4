"""Agents by name: ``make_agent("mg-crb-cl", scenario, **params)``."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from mimo_radar_env import Scenario

from .base import Agent
from .baselines import PAPER_FIXED, BestAgent, FixedAgent, RandomAgent
from .greedy import EpsilonGreedy
from .mg_crb_cl import MGCRBCL
from .thompson import DiscountedThompson
from .ucb import CUCB, UCB1, DiscountedUCB, SlidingWindowUCB


@dataclass(frozen=True)
class AgentSpec:
    """A registered agent: its class and preset parameters."""

    cls: type[Agent]
    preset: dict[str, Any] = field(default_factory=dict)
    summary: str = ""


_REGISTRY: dict[str, AgentSpec] = {}


def register_agent(name: str, cls: type[Agent], summary: str = "", **preset: Any) -> None:
    """Register an agent class (with preset parameters) under ``name``."""
    _REGISTRY[name] = AgentSpec(cls, preset, summary)


for _cls in (
    MGCRBCL,
    UCB1,
    EpsilonGreedy,
    CUCB,
    DiscountedUCB,
    SlidingWindowUCB,
    DiscountedThompson,
    BestAgent,
    RandomAgent,
    FixedAgent,
):
    register_agent(_cls.name, _cls, (inspect.getdoc(_cls) or "").splitlines()[0])
for _name, (_tx, _rx) in PAPER_FIXED.items():
    register_agent(
        _name,
        FixedAgent,
        f"the paper's {_name}: TX {[i + 1 for i in _tx]}, RX {[i + 1 for i in _rx]}",
        tx=_tx,
        rx=_rx,
    )


def available_agents() -> list[str]:
    """Names of the registered agents."""
    return sorted(_REGISTRY)


def agent_parameters(name: str) -> list[str]:
    """The parameters ``make_agent(name, ...)`` accepts (besides the scenario)."""
    spec = _spec(name)
    params = inspect.signature(spec.cls.__init__).parameters
    return [p for p in params if p not in ("self", "scenario") and p not in spec.preset]


def agent_summary(name: str) -> str:
    return _spec(name).summary


def _spec(name: str) -> AgentSpec:
    if name not in _REGISTRY:
        raise ValueError(f"unknown agent {name!r}; available agents are {available_agents()}")
    return _REGISTRY[name]


def make_agent(name: str, scenario: Scenario | str, **params: Any) -> Agent:
    """Create a registered agent; unknown parameters raise an error listing the allowed ones."""
    spec = _spec(name)
    allowed = agent_parameters(name)
    unknown = sorted(set(params) - set(allowed))
    if unknown:
        raise ValueError(f"unknown parameter(s) {unknown} for agent {name!r}; allowed: {allowed}")
    factory: Callable[..., Agent] = spec.cls
    return factory(scenario, **spec.preset, **params)
