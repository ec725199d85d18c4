"""What a policy needs from the env and what it costs, declared apart from its logic.

A policy class declares :class:`Needs` (``needs = Needs(tracking=True)``) and the parts of its
cost (``costs = (BOOKKEEPING, SOLVER)``); the rollout loop and the benchmark harness read them,
the policy's own code never does. Each part is an upper estimate per trial of the memory at the
peak of a step and of the arithmetic of a step, with the rate its kind of work runs at on the
developers' machine (the harness sizes shards and estimates a run's time with them:
:func:`memory_per_trial`, :func:`seconds_per_trial_step`), and Python's time per step of a
whole batch where a search loops over steps (:func:`seconds_per_step`); a policy's cost is the
sum of its parts. ``benchmarks.speed.policy_cost`` measures every policy against what it
declares, and the rates are fitted to it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from mimo_radar_env.core.compiled import HAVE_NUMBA
from mimo_radar_env.core.superarm import search_operations, search_seconds, super_arm_count
from mimo_radar_env.tracking.selection import selection_memory_per_trial, selection_operations_per_trial

if TYPE_CHECKING:
    from .base import Agent


@dataclass(frozen=True)
class Needs:
    """What a policy needs from the env.

    Attributes
    ----------
    oracle : bool
        It reads the truth, through the env it is attached to (``attach(env)``).
    tracking : bool
        It reads the tracker's keys of the observation (checked at ``reset``).
    observation_options : mapping
        Env options that add observation keys it reads and change no number of the env
        (tracking-ucb's ``{"prediction_covariance": True}``); the rollout loop sets them.
    env_option_params : tuple of str
        Its parameters named after env options (``"fusion"``...), which must match the env's:
        the harness passes the run's unless they are given, and a rollout refuses an env of
        other values (:meth:`agents.Agent.env_option_values`).
    tracking_search : bool
        It selects with the tracking search, whose numba kernel a run compiles.
    device : bool
        It acts on the torch tensors of an env made with ``device=`` (its state and draws on that
        device, :attr:`agents.Agent.xp`); without it such an env is refused at ``reset``, and the
        harness refuses ``--device`` runs of it before they start.
    """

    oracle: bool = False
    tracking: bool = False
    observation_options: Mapping[str, Any] = field(default_factory=dict)
    env_option_params: tuple[str, ...] = ()
    tracking_search: bool = False
    device: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "observation_options", MappingProxyType(dict(self.observation_options)))


#: Seconds per declared operation of work done in numpy over the batch, on the developers'
#: machine (a part whose work runs otherwise declares its own :attr:`Cost.seconds_per_operation`).
NUMPY_SECONDS_PER_OPERATION = 1e-9


class Cost:
    """One part of a policy's cost (nothing, unless a subclass says otherwise)."""

    #: How long one of its declared operations takes on the developers' machine: its kind of
    #: work's speed there, fitted to ``benchmarks.speed.policy_cost``'s measurements.
    seconds_per_operation: float = NUMPY_SECONDS_PER_OPERATION
    #: Its work runs in a compiled kernel that spreads a batch's trials over threads (numba's
    #: ``prange``): the harness counts it as shared by a task's threads.
    threaded: bool = False

    def memory_per_trial(self, agent: Agent) -> int:
        return 0

    def operations_per_trial_step(self, agent: Agent) -> float:
        return 0.0

    def seconds_per_step(self, agent: Agent) -> float:
        return 0.0

    def seconds_per_trial_step(self, agent: Agent) -> float:
        """Its operations at its :attr:`seconds_per_operation`."""
        return self.operations_per_trial_step(agent) * self.seconds_per_operation

    def is_threaded(self, agent: Agent) -> bool:
        """Whether ``agent``'s work of this part is :attr:`threaded` (without numba no kernel
        is compiled, and its numpy path runs on one thread)."""
        return self.threaded and HAVE_NUMBA


def _channels(agent: Agent) -> int:
    sc = agent.scenario
    return sc.num_targets * sc.num_tx * sc.num_rx


class Bookkeeping(Cost):
    """Every policy's per-channel state (its estimates and counts) and their update."""

    seconds_per_operation = 1.9e-10

    def memory_per_trial(self, agent: Agent) -> int:
        return 8 * 8 * _channels(agent)

    def operations_per_trial_step(self, agent: Agent) -> float:
        return 20.0 * _channels(agent)


class Solver(Cost):
    """An index policy's super-arm solver (``agent.solver``)."""

    def memory_per_trial(self, agent: Agent) -> int:
        return agent.solver.memory_per_trial(agent.num_tx, agent.num_rx)  # type: ignore[attr-defined]

    def operations_per_trial_step(self, agent: Agent) -> float:
        return agent.solver.operations_per_trial(agent.num_tx, agent.num_rx)  # type: ignore[attr-defined]

    def seconds_per_trial_step(self, agent: Agent) -> float:
        """At the solver's own rate (:attr:`agents.solvers.SuperArmSolver.seconds_per_operation`)."""
        return self.operations_per_trial_step(agent) * agent.solver.seconds_per_operation  # type: ignore[attr-defined]

    def is_threaded(self, agent: Agent) -> bool:
        return agent.solver.threaded  # type: ignore[attr-defined]


class GammaSampler(Cost):
    """A Gamma draw per target and channel (a few rejection rounds): the sampler's scratch
    draws normals and uniforms for every one (``benchmarks.speed.policy_cost`` measured about 38
    float64 per target and channel)."""

    seconds_per_operation = 2.4e-9

    def memory_per_trial(self, agent: Agent) -> int:
        return 8 * 48 * _channels(agent)

    def operations_per_trial_step(self, agent: Agent) -> float:
        return 150.0 * _channels(agent)


class OracleSearch(Cost):
    """The env's search of the optimal super arm (its ``oracle_action()``)."""

    def operations_per_trial_step(self, agent: Agent) -> float:
        sc = agent.scenario
        return search_operations(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)

    def seconds_per_trial_step(self, agent: Agent) -> float:
        sc = agent.scenario
        return search_seconds(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)


class TrackingSearch(Cost):
    """The tracking search (``mimo_radar_env.tracking.selection.select_for_tracking``) on the
    agent's scenario."""

    seconds_per_operation = 6.5e-10
    threaded = True  # most of its arithmetic: the compiled sums of the super arms' channels

    @staticmethod
    def _size(agent: Agent) -> tuple[int, int, int, int, int]:
        sc = agent.scenario
        return sc.num_tx, sc.num_rx, sc.num_targets, sc.tx_per_step, sc.rx_per_step

    def memory_per_trial(self, agent: Agent) -> int:
        return selection_memory_per_trial(*self._size(agent))

    def operations_per_trial_step(self, agent: Agent) -> float:
        return selection_operations_per_trial(*self._size(agent))


#: Python's time per planned step of a batch, and per step of an MCTS simulation (s): the
#: searches loop over them (``benchmarks.speed.policy_cost`` measures them at a few trials).
PLAN_STEP_SECONDS = 2e-4


class Plan(Cost):
    """A receding-horizon search (``agent.search``, ``width``, ``horizon``, ``simulations``):
    every scored plan extended by every super arm at every planned step (MCTS: at every step of
    every simulation). Its later steps sum channels by one matrix product (BLAS), faster per
    operation than elementwise numpy."""

    seconds_per_operation = 4.1e-10

    @staticmethod
    def _states(agent: Any) -> tuple[int, int]:
        """The super arms, and the plans a search scores at once (the beam, one per super arm for
        the rollout, one node at a time for MCTS)."""
        sc = agent.scenario
        arms = super_arm_count(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        if agent.search == "rollout":
            return arms, arms
        if agent.search == "mcts":
            return arms, 1
        return arms, min(agent.width, arms ** max(agent.horizon - 1, 0))

    def memory_per_trial(self, agent: Any) -> int:
        """Each plan scored at once scores every super arm of a step (its 2 x 2 posteriors and
        their criterion: ``benchmarks.speed.policy_cost`` measured about 14 float64 per plan,
        super arm and target), with its prior and the channels' information; the horizon's
        information; MCTS's tree (a covariance and the candidates' costs and counts per node)."""
        sc = agent.scenario
        arms, states = self._states(agent)
        channels = _channels(agent)
        tree = 8 * (1 + agent.simulations) * (16 * sc.num_targets + 5 * arms) if agent.search == "mcts" else 0
        return (
            8 * states * (arms * (8 + 16 * sc.num_targets) + channels * 4 * 4)
            + 8 * agent.horizon * channels * 12
            + tree
        )

    def operations_per_trial_step(self, agent: Any) -> float:
        sc = agent.scenario
        arms, states = self._states(agent)
        repeats = agent.simulations if agent.search == "mcts" else 1
        return repeats * agent.horizon * states * arms * sc.num_targets * (2.0 * sc.num_tx * sc.num_rx + 60)

    def seconds_per_step(self, agent: Any) -> float:
        return PLAN_STEP_SECONDS * agent.horizon * (agent.simulations if agent.search == "mcts" else 1)


class Network(Cost):
    """A learned policy's features and a forward pass of its network (``network_weights`` of
    them): about two operations per weight."""

    def operations_per_trial_step(self, agent: Any) -> float:
        return 2.0 * agent.network_weights + 10.0 * agent.features.size


BOOKKEEPING, SOLVER, GAMMA_SAMPLER = Bookkeeping(), Solver(), GammaSampler()
ORACLE_SEARCH, TRACKING_SEARCH, PLAN, NETWORK = OracleSearch(), TrackingSearch(), Plan(), Network()


def memory_per_trial(agent: Agent) -> int:
    """Bytes one trial of ``agent`` needs at its peak within a step, roughly (an upper estimate):
    the sum of its cost parts. The harness adds it to the env's to size shards."""
    return sum(part.memory_per_trial(agent) for part in agent.costs)


def operations_per_trial_step(agent: Agent) -> float:
    """Arithmetic operations one trial of ``agent`` does per step (act and update), roughly (an
    upper estimate): the sum of its parts'."""
    return sum(part.operations_per_trial_step(agent) for part in agent.costs)


def seconds_per_trial_step(agent: Agent) -> float:
    """One trial's share of a step's time on the developers' machine, roughly: each part's
    share (:meth:`Cost.seconds_per_trial_step`: its operations at its rate). The harness adds the env's
    (:func:`mimo_radar_env.envs.cost.seconds_per_trial_step`) to estimate a run's time."""
    return sum(part.seconds_per_trial_step(agent) for part in agent.costs)


def threaded_seconds_per_trial_step(agent: Agent) -> float:
    """The part of :func:`seconds_per_trial_step` that a task's threads share (its
    :attr:`Cost.threaded` parts)."""
    return sum(part.seconds_per_trial_step(agent) for part in agent.costs if part.is_threaded(agent))


def seconds_per_step(agent: Agent) -> float:
    """Time per step of a whole batch that does not grow with its trials (Python's share of a
    search that loops over steps or simulations), roughly; 0 for most agents."""
    return sum(part.seconds_per_step(agent) for part in agent.costs)
