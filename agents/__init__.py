"""Selection policies for MimoRadarSelect and their super-arm solvers.

``make_agent(name, scenario, **params)`` creates an agent by name;
``available_agents()`` lists them. Every agent is batch-native: the same object
acts on the single env and on the vector env; :class:`Rollout` (with :func:`make_env`) is the
one loop that runs an agent on an env.
"""

from . import costs
from .base import Agent, IndexPolicy
from .costs import Needs
from .fixed import PAPER_FIXED, FixedAgent
from .greedy import EpsilonGreedy
from .mg_crb_cl import MGCRBCL
from .oracle import BestAgent, BestTrackingAgent
from .planning import PlanTrackingAgent, PlanTrackingUCB
from .ppo import MaskablePPOAgent, PPOAgent, RecurrentPPOAgent, TorchPPOAgent
from .recency import RecencyBasedExploration
from .registry import (
    agent_argument,
    agent_class,
    agent_parameters,
    agent_summary,
    available_agents,
    learned_agents,
    make_agent,
    register_agent,
    split_policy,
)
from .rollout import Rollout, Step, env_options_for, make_env
from .solvers import SOLVERS, SuperArmSolver, make_solver
from .thompson import CombinatorialThompson, DiscountedThompson
from .tracking import TrackingUCB
from .ucb import CUCB, UCB1, DiscountedUCB, SlidingWindowUCB
from .uniform import RandomAgent

#: Marks this package as mimo-radar-env's (another distribution may install an ``agents``).
DISTRIBUTION = "mimo-radar-env"

__all__ = [
    "CUCB",
    "MGCRBCL",
    "PAPER_FIXED",
    "SOLVERS",
    "UCB1",
    "Agent",
    "BestAgent",
    "BestTrackingAgent",
    "PlanTrackingAgent",
    "PlanTrackingUCB",
    "CombinatorialThompson",
    "DiscountedThompson",
    "DiscountedUCB",
    "EpsilonGreedy",
    "FixedAgent",
    "IndexPolicy",
    "Needs",
    "MaskablePPOAgent",
    "PPOAgent",
    "RecurrentPPOAgent",
    "TorchPPOAgent",
    "RandomAgent",
    "RecencyBasedExploration",
    "Rollout",
    "Step",
    "SlidingWindowUCB",
    "SuperArmSolver",
    "TrackingUCB",
    "agent_argument",
    "learned_agents",
    "agent_class",
    "agent_parameters",
    "agent_summary",
    "available_agents",
    "costs",
    "env_options_for",
    "make_agent",
    "make_env",
    "make_solver",
    "register_agent",
    "split_policy",
]
