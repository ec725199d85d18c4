"""Agents by name: ``make_agent("mg-crb-cl", scenario, **params)``.

A policy of a benchmark run is written ``NAME`` or ``NAME:ARGUMENT``; the argument goes to
the agent's registered ``argument`` parameter (a trained PPO model: ``ppo:runs/ppo/model.zip``;
tracking-ucb's SINR weight: ``tracking-ucb:0.5``).
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from mimo_radar_env import Scenario

from .base import Agent
from .fixed import PAPER_FIXED, FixedAgent
from .greedy import EpsilonGreedy
from .mg_crb_cl import MGCRBCL
from .oracle import BestAgent, BestTrackingAgent
from .planning import PlanTrackingAgent, PlanTrackingUCB
from .ppo import MaskablePPOAgent, PPOAgent, RecurrentPPOAgent
from .recency import RecencyBasedExploration
from .thompson import CombinatorialThompson, DiscountedThompson
from .tracking import TrackingUCB
from .ucb import CUCB, UCB1, DiscountedUCB, SlidingWindowUCB
from .uniform import RandomAgent


@dataclass(frozen=True)
class AgentSpec:
    """A registered agent: its class, preset parameters, summary, and the parameter that
    ``NAME:ARGUMENT`` sets (``None``: the agent takes no argument)."""

    cls: type[Agent]
    preset: dict[str, Any] = field(default_factory=dict)
    summary: str = ""
    argument: str | None = None
    argument_type: Callable[[str], Any] = str


_REGISTRY: dict[str, AgentSpec] = {}


def register_agent(
    name: str,
    cls: type[Agent],
    summary: str = "",
    argument: str | None = None,
    argument_type: Callable[[str], Any] = str,
    **preset: Any,
) -> None:
    """Register an agent class (with preset parameters) under ``name``; ``NAME:ARGUMENT`` sets
    its parameter ``argument`` to ``argument_type(ARGUMENT)``."""
    _REGISTRY[name] = AgentSpec(cls, preset, summary, argument, argument_type)


def _first_line(cls: type) -> str:
    return (inspect.getdoc(cls) or "").splitlines()[0]


for _cls in (
    MGCRBCL,
    UCB1,
    EpsilonGreedy,
    CUCB,
    DiscountedUCB,
    SlidingWindowUCB,
    DiscountedThompson,
    CombinatorialThompson,
    RecencyBasedExploration,
    BestAgent,
    BestTrackingAgent,
    RandomAgent,
    FixedAgent,
):
    register_agent(_cls.name, _cls, _first_line(_cls))
for _learned in (PPOAgent, MaskablePPOAgent, RecurrentPPOAgent):
    register_agent(_learned.name, _learned, _first_line(_learned), argument="path")
# plan-tracking:10 plans 10 steps ahead: several horizons in one run
register_agent(
    PlanTrackingAgent.name,
    PlanTrackingAgent,
    _first_line(PlanTrackingAgent),
    argument="horizon",
    argument_type=int,
)
register_agent(
    "plan-tracking-rollout",
    PlanTrackingAgent,
    "plan-tracking searching by rollout (every first super arm continued greedily)",
    argument="horizon",
    argument_type=int,
    search="rollout",
)
register_agent(
    "plan-tracking-mcts",
    PlanTrackingAgent,
    "plan-tracking searching by Monte-Carlo tree search (64 simulations over 8 candidates per node)",
    argument="horizon",
    argument_type=int,
    search="mcts",
)
register_agent(
    PlanTrackingUCB.name, PlanTrackingUCB, _first_line(PlanTrackingUCB), argument="horizon", argument_type=int
)
# tracking-ucb:0.5 is tracking-ucb with sinr_weight=0.5: points of its trade-off in one run
register_agent(
    TrackingUCB.name, TrackingUCB, _first_line(TrackingUCB), argument="sinr_weight", argument_type=float
)
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
    """The parameters ``make_agent(name, ...)`` accepts (besides the scenario): its signature's,
    and the fields of its ``keyword_parameters`` (a dataclass its ``**`` keywords build)."""
    spec = _spec(name)
    params = [
        p
        for p, value in inspect.signature(spec.cls.__init__).parameters.items()
        if value.kind is not inspect.Parameter.VAR_KEYWORD
    ]
    keyword = getattr(spec.cls, "keyword_parameters", None)
    params += [f.name for f in dataclasses.fields(keyword)] if keyword is not None else []
    return [p for p in params if p not in ("self", "scenario") and p not in spec.preset]


def required_parameters(name: str) -> list[str]:
    """The parameters ``make_agent(name, ...)`` needs (no default)."""
    spec = _spec(name)
    params = inspect.signature(spec.cls.__init__).parameters
    return [
        p
        for p, value in params.items()
        if p not in ("self", "scenario")
        and p not in spec.preset
        and value.default is inspect.Parameter.empty
        and value.kind not in (inspect.Parameter.VAR_KEYWORD, inspect.Parameter.VAR_POSITIONAL)
    ]


def agent_summary(name: str) -> str:
    return _spec(name).summary


def agent_class(name: str) -> type[Agent]:
    """The class of a registered agent."""
    return _spec(name).cls


def learned_agents() -> list[str]:
    """The agents that evaluate a trained model (``NAME:PATH``): PPO and the sb3-contrib learners."""
    from .ppo import PPOAgent

    return [name for name in available_agents() if issubclass(_REGISTRY[name].cls, PPOAgent)]


def agent_argument(name: str) -> str | None:
    """The parameter that ``NAME:ARGUMENT`` sets, or ``None``."""
    return _spec(name).argument


def _spec(name: str) -> AgentSpec:
    if name not in _REGISTRY:
        raise ValueError(f"unknown agent {name!r}; available agents are {available_agents()}")
    return _REGISTRY[name]


def split_policy(policy: str) -> tuple[str, dict[str, Any]]:
    """``"ppo:runs/a/model.zip"`` -> ``("ppo", {"path": "runs/a/model.zip"})``,
    ``"tracking-ucb:0.5"`` -> ``("tracking-ucb", {"sinr_weight": 0.5})``;
    ``"ucb1"`` -> ``("ucb1", {})``."""
    name, sep, argument = policy.partition(":")
    spec = _spec(name)
    if not sep:
        return name, {}
    if spec.argument is None:
        raise ValueError(f"agent {name!r} takes no argument, got {policy!r}")
    if not argument:
        raise ValueError(
            f"{policy!r}: give the {spec.argument} after the colon ({name}:{spec.argument.upper()})"
        )
    try:
        value = spec.argument_type(argument)
    except ValueError:
        raise ValueError(
            f"{policy!r}: the {spec.argument} after the colon must be a {spec.argument_type.__name__}, "
            f"got {argument!r}"
        ) from None
    return name, {spec.argument: value}


def make_agent(name: str, scenario: Scenario | str, **params: Any) -> Agent:
    """Create a registered agent; unknown or missing parameters raise an error naming them."""
    spec = _spec(name)
    allowed = agent_parameters(name)
    unknown = sorted(set(params) - set(allowed))
    if unknown:
        raise ValueError(f"unknown parameter(s) {unknown} for agent {name!r}; allowed: {allowed}")
    missing = sorted(set(required_parameters(name)) - set(params))
    if missing:
        raise ValueError(f"agent {name!r} needs the parameter(s) {missing}")
    return spec.cls(scenario, **spec.preset, **params)
