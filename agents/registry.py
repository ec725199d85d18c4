"""Agents by name: ``make_agent("mg-crb-cl", scenario, **params)``.

A policy of a benchmark run is written ``NAME`` or ``NAME:ARGUMENT``; the argument goes to
the agent's registered ``argument`` parameter (a trained PPO model: ``ppo:runs/ppo/model.zip``;
tracking-ucb's SINR weight: ``tracking-ucb:0.5``).

A user's agent needs no edit of this package, in three ways:

* ``module:Class`` (Gymnasium's entry-point form, ``mypkg.agents:MyAgent``) names an
  :class:`~agents.Agent` subclass; it is imported where it is first named, in every worker too;
* an installed package lists agents in its entry-point group ``mimo_radar_env.agents``
  (``my-agent = mypkg.agents:MyAgent``), registered under their entry-point names;
* :func:`register_agent` in the calling process.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
import importlib.metadata
import inspect
import re
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
from .ppo import MaskablePPOAgent, PPOAgent, RecurrentPPOAgent, TorchPPOAgent
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
#: The names this package registers (set below): each keeps its meaning in every process.
_SHIPPED: frozenset[str] = frozenset()


def register_agent(
    name: str,
    cls: type[Agent],
    summary: str = "",
    argument: str | None = None,
    argument_type: Callable[[str], Any] = str,
    **preset: Any,
) -> None:
    """Register an agent class (with preset parameters) under ``name``; ``NAME:ARGUMENT`` sets
    its parameter ``argument`` to ``argument_type(ARGUMENT)``. A name of your own may be
    registered again (the last class wins: a notebook's cell run twice); a shipped agent's name
    is refused, as an installed package's entry point of that name is skipped."""
    if not (isinstance(cls, type) and issubclass(cls, Agent)):
        raise TypeError(f"register_agent: cls must be a subclass of agents.Agent, got {cls!r}")
    if not isinstance(name, str) or not name.strip() or "," in name:
        raise ValueError(f"register_agent: name must be a non-empty string without commas, got {name!r}")
    if name in _SHIPPED:
        raise ValueError(
            f"register_agent: {name!r} is a shipped agent and keeps its meaning; register yours under "
            "another name"
        )
    _REGISTRY[name] = AgentSpec(cls, preset, summary, argument, argument_type)


def _first_line(cls: type) -> str:
    """The docstring's first paragraph, on one line (a summary that never stops mid-sentence)."""
    paragraph = (inspect.getdoc(cls) or "").split("\n\n")[0]
    paragraph = re.sub(r":\w+:`~?([^`]+)`", r"\1", paragraph).replace("``", "")  # reST roles, literals
    return " ".join(paragraph.split())


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
for _learned in (PPOAgent, MaskablePPOAgent, RecurrentPPOAgent, TorchPPOAgent):
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
_SHIPPED = frozenset(_REGISTRY)


#: The entry-point group through which installed packages add agents by name.
ENTRY_POINT_GROUP = "mimo_radar_env.agents"


@functools.cache
def load_plugins() -> list[str]:
    """Registers the agents installed packages list in :data:`ENTRY_POINT_GROUP` (once per
    process); their names."""
    names = []
    for entry in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        if entry.name in _REGISTRY:
            continue  # a shipped name keeps its meaning
        cls = _agent_subclass(entry.value, entry.load())
        register_agent(entry.name, cls, _first_line(cls))
        names.append(entry.name)
    return names


def _agent_subclass(reference: str, obj: Any) -> type[Agent]:
    if not (isinstance(obj, type) and issubclass(obj, Agent)):
        raise ValueError(f"{reference!r} is {obj!r}, not a subclass of agents.Agent")
    return obj


def _is_reference(name: str) -> bool:
    """Whether ``name`` has the form ``module.path:Class`` (dotted identifiers on both sides)."""
    module, sep, attribute = name.partition(":")
    return bool(sep) and all(p.isidentifier() for p in (*module.split("."), *attribute.split(".")))


def _load_reference(name: str) -> None:
    """Imports and registers the agent class ``module:Class`` under that name."""
    module_name, _, attribute = name.partition(":")
    try:
        obj: Any = importlib.import_module(module_name)
    except ImportError as exc:
        raise ValueError(f"policy {name!r}: cannot import module {module_name!r} ({exc})") from None
    for part in attribute.split("."):
        if not hasattr(obj, part):
            raise ValueError(f"policy {name!r}: module {module_name!r} has no {attribute!r}")
        obj = getattr(obj, part)
    cls = _agent_subclass(name, obj)
    register_agent(name, cls, _first_line(cls))


def available_agents() -> list[str]:
    """Names of the registered agents (the shipped ones and those of installed plugins)."""
    load_plugins()
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


def agent_parameter_defaults(name: str) -> dict[str, Any]:
    """Each parameter of :func:`agent_parameters` with its default (``inspect.Parameter.empty``
    for a required one)."""
    spec = _spec(name)
    signature = inspect.signature(spec.cls.__init__).parameters
    keyword = getattr(spec.cls, "keyword_parameters", None)
    fields = {f.name: f.default for f in dataclasses.fields(keyword)} if keyword is not None else {}
    defaults = {
        p: signature[p].default if p in signature else fields.get(p, inspect.Parameter.empty)
        for p in agent_parameters(name)
    }
    if defaults.get("solver", "") is None:  # None: the class's own solver
        defaults["solver"] = getattr(spec.cls, "default_solver", None)
    return defaults


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
    """The agents that evaluate a trained model (``NAME:PATH``): PPO, the sb3-contrib learners and
    the project's own torch-ppo."""
    from .ppo import PPOAgent, TorchPPOAgent

    return [name for name in available_agents() if issubclass(_REGISTRY[name].cls, PPOAgent | TorchPPOAgent)]


def agent_argument(name: str) -> str | None:
    """The parameter that ``NAME:ARGUMENT`` sets, or ``None``."""
    return _spec(name).argument


class UnknownAgentError(ValueError):
    """A policy name that is no registered agent, plugin or ``module:Class``."""


class AgentParameterError(TypeError, ValueError):
    """A parameter an agent does not take, or one it needs and was not given: a ``TypeError``,
    as Python and Gymnasium raise for keywords, that is also the ``ValueError`` of the library's
    other bad input."""


def _spec(name: str) -> AgentSpec:
    _check_name(name)
    if name not in _REGISTRY:
        load_plugins()
    if name not in _REGISTRY and _is_reference(name):
        _load_reference(name)
    if name not in _REGISTRY:
        raise UnknownAgentError(
            f"unknown agent {name!r}; available agents are {available_agents()}, or an agents.Agent "
            "subclass as module:Class"
        )
    return _REGISTRY[name]


def _check_name(name: Any) -> None:
    """An agent is named by a str: TypeError naming what was given instead."""
    if isinstance(name, str):
        return
    if isinstance(name, type):
        given = f"the class {name.__name__} (make it by calling it: {name.__name__}(scenario, seed=...))"
    else:
        given = f"{type(name).__name__} {name!r}"
    raise TypeError(f"an agent's name must be a str, a registered name or module:Class, got {given}")


def split_policy(policy: str) -> tuple[str, dict[str, Any]]:
    """``"ppo:runs/a/model.zip"`` -> ``("ppo", {"path": "runs/a/model.zip"})``,
    ``"tracking-ucb:0.5"`` -> ``("tracking-ucb", {"sinr_weight": 0.5})``;
    ``"ucb1"`` -> ``("ucb1", {})``."""
    _check_name(policy)
    name, sep, argument = policy.partition(":")
    if name not in _REGISTRY and _is_reference(policy):
        load_plugins()
        if name not in _REGISTRY:  # module:Class, a user's agent
            _spec(policy)
            return policy, {}
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
    """Create a registered agent; unknown or missing parameters raise
    :class:`AgentParameterError` naming them."""
    spec = _spec(name)
    allowed = agent_parameters(name)
    unknown = sorted(set(params) - set(allowed))
    if unknown:
        raise AgentParameterError(f"unknown parameter(s) {unknown} for agent {name!r}; allowed: {allowed}")
    missing = sorted(set(required_parameters(name)) - set(params))
    if missing:
        raise AgentParameterError(f"agent {name!r} needs the parameter(s) {missing}")
    agent = spec.cls(scenario, **spec.preset, **params)
    agent.name = name  # its messages name it as it was made: fix1, not its class's "fixed"
    return agent
