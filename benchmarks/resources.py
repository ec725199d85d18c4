"""What a run costs before it starts: its memory, its time and its schedule.

From the costs the env and the agents declare (:mod:`mimo_radar_env.envs.cost`,
:mod:`agents.costs`): each policy's seconds per step of a shard (:data:`StepCost`), the shard
sizes that fit the machine's memory (:func:`fit_shard_size`) and those that end a run soonest
(:func:`plan_shard_sizes`), a run's estimated time (:func:`estimate_seconds`, refused beyond
``max_hours`` by :func:`check_time`), the order its tasks start in (:func:`longest_first`) and
the threads per worker (:func:`choose_threads`). :mod:`benchmarks.harness` plans each run with
them; ``benchmarks.speed.policy_cost`` prints measured / estimated time for every policy.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

import agents
from mimo_radar_env import EnvOptions, Scenario
from mimo_radar_env.core import compiled
from mimo_radar_env.envs.cost import (
    machine_memory,
    memory_parts,
    seconds_per_trial_step,
    threaded_seconds_per_trial_step,
)

from . import machine_rate
from .errors import HarnessError

if TYPE_CHECKING:
    from .harness import RunConfig


#: The share of the machine's memory the tasks running at once may take together.
MEMORY_FRACTION = 0.5

#: The largest shard :func:`auto_shard_size` makes: a shard is saved whole, so this bounds the
#: work an interruption loses (well under a minute of the v1 paper study's slowest policy).
MAX_AUTO_SHARD_SIZE = 500

#: Seconds per step of a shard that do not grow with its trials (Python's share: calls and small
#: arrays), on the developers' machine (``benchmarks.speed.policy_cost`` prints measured /
#: estimated time for every policy).
STEP_OVERHEAD_SECONDS = 1.7e-3

#: The longest run ``run`` and the studies start without ``--max-hours`` (hours).
DEFAULT_MAX_HOURS = 24.0

#: A policy's estimated seconds per step of a shard: the part that does not grow with its
#: trials, each trial's share, and the part of that share a task's threads share.
StepCost = tuple[float, float, float]


def declared_seconds(
    built: dict[str, agents.Agent],
) -> tuple[dict[str, float], dict[str, float], dict[str, float]]:
    """Each built agent's declared seconds per trial-step, per step of a batch, and the part of
    the first that a task's threads share."""
    costs = agents.costs
    return (
        {policy: costs.seconds_per_trial_step(agent) for policy, agent in built.items()},
        {policy: costs.seconds_per_step(agent) for policy, agent in built.items()},
        {policy: costs.threaded_seconds_per_trial_step(agent) for policy, agent in built.items()},
    )


def policy_step_costs(
    sc: Scenario, options: EnvOptions, built: dict[str, agents.Agent]
) -> dict[str, StepCost]:
    """Each built policy's estimated seconds per step of a shard (:func:`step_costs`)."""
    return step_costs(sc, options, *declared_seconds(built))


def step_costs(
    scenario: Scenario,
    options: EnvOptions,
    agent_trial_seconds: dict[str, float],
    agent_seconds: dict[str, float] | None = None,
    agent_threaded_seconds: dict[str, float] | None = None,
) -> dict[str, StepCost]:
    """Each policy's estimated seconds per step of a shard (:data:`StepCost`):
    :data:`STEP_OVERHEAD_SECONDS` and its own fixed time (``agent_seconds``); the env's
    :func:`~mimo_radar_env.envs.cost.seconds_per_trial_step` and its own
    (``agent_trial_seconds``); of which the env's threaded part
    (:func:`~mimo_radar_env.envs.cost.threaded_seconds_per_trial_step`) and its own
    (``agent_threaded_seconds``)."""
    env = seconds_per_trial_step(scenario, options.tracking, options.fusion)
    env_threaded = threaded_seconds_per_trial_step(scenario, options.tracking, options.fusion)
    fixed, threaded = agent_seconds or {}, agent_threaded_seconds or {}
    return {
        policy: (
            STEP_OVERHEAD_SECONDS + fixed.get(policy, 0.0),
            env + own,
            env_threaded + threaded.get(policy, 0.0),
        )
        for policy, own in agent_trial_seconds.items()
    }


def step_seconds(cost: StepCost, trials: int, threads: int = 1) -> float:
    """Seconds per step of a task of ``trials`` trials on ``threads`` threads by ``cost``: its
    fixed part, and each trial's share, whose threaded part runs in chunks of
    :data:`~mimo_radar_env.core.compiled.CHUNK` trials spread over the threads (a batch of one
    chunk runs on one thread)."""
    fixed, per_trial, threaded = cost
    spread = trials
    if threads > 1 and trials > compiled.CHUNK:
        chunks = -(-trials // compiled.CHUNK)
        spread = min(trials, compiled.CHUNK * -(-chunks // threads))
    return fixed + (per_trial - threaded) * trials + threaded * spread


def estimate_seconds(
    scenario: Scenario,
    options: EnvOptions,
    agent_trial_seconds: dict[str, float],
    trials: int,
    steps: int,
    shard_size: int | Mapping[str, int],
    parallel: int = 1,
    agent_seconds: dict[str, float] | None = None,
) -> float:
    """A run's wall time, roughly: every (policy, shard) task takes, per step,
    :data:`STEP_OVERHEAD_SECONDS` and the policy's own fixed time
    (:func:`agents.costs.seconds_per_step`, ``agent_seconds``) plus each trial's share (the
    env's, :func:`~mimo_radar_env.envs.cost.seconds_per_trial_step`, and the policy's,
    :func:`agents.costs.seconds_per_trial_step`, ``agent_trial_seconds``);
    ``parallel`` tasks run at once; all of it at the developers' machine's speed, scaled by this
    machine's where ``mimo-radar-bench compile`` measured it (:func:`benchmarks.machine_rate.factor`).
    ``shard_size`` is every policy's, or each policy's (a mapping)."""
    costs = step_costs(scenario, options, agent_trial_seconds, agent_seconds)
    sizes = shard_size if isinstance(shard_size, Mapping) else dict.fromkeys(costs, shard_size)
    shards = {policy: -(-trials // sizes[policy]) for policy in costs}
    total = sum(
        steps * (shards[p] * fixed + trials * per_trial) for p, (fixed, per_trial, _) in costs.items()
    )
    return total * (machine_rate.factor() or 1.0) / max(1, min(parallel, sum(shards.values())))


def auto_shard_size(trials: int, parallel: int, policies: int = 1) -> int:
    """The shard size when none is given: each policy's trials cut into the fewest shards that
    make the run's tasks a multiple of the ``parallel`` tasks that run at once
    (``parallel // gcd(policies, parallel)`` shards per policy: with 6 policies and 2 workers,
    one shard per policy; with 1 policy, one per worker), so that every task steps as large a
    batch as it can (a step's fixed costs are shared by the batch) while no worker is left
    without a task of the last round, at most :data:`MAX_AUTO_SHARD_SIZE`. Trial ``i`` is seeded
    ``seed + i`` whatever its shard, so the numbers depend on it only through floating-point
    rounding (a batch of another size may sum in another order: a relative 1e-12)."""
    parallel, policies = max(1, parallel), max(1, policies)
    shards = parallel // math.gcd(policies, parallel)
    return max(1, min(MAX_AUTO_SHARD_SIZE, -(-trials // shards)))


def makespan(durations: Sequence[float], workers: int) -> float:
    """When tasks of ``durations`` end, queued in that order on ``workers`` workers (list
    scheduling: each task to the first free worker)."""
    free = [0.0] * max(1, workers)
    for seconds in durations:
        heapq.heappush(free, heapq.heappop(free) + seconds)
    return max(free)


def plan_shard_sizes(
    costs: Mapping[str, StepCost], trials: int, parallel: int, max_size: int = MAX_AUTO_SHARD_SIZE
) -> dict[str, int]:
    """Each policy's shard size for ``parallel`` tasks at once, from its cost per step of a shard
    (``costs``, :func:`policy_step_costs`, on one thread: :func:`step_seconds`): the sizes whose tasks,
    queued the longest first on ``parallel`` workers, end soonest by that cost model. Splitting a
    policy's trials into more shards shortens its longest task but pays its fixed part once more
    per shard (a smaller batch); so the costliest policies get the smallest shards and the cheap
    ones keep large batches. The search splits, one shard at a time, the policy whose task is
    the longest (at most :data:`MAX_AUTO_SHARD_SIZE` trials a shard, up to four tasks per
    worker), and keeps the best plan it met; ties go to the fewest shards."""
    parallel = max(1, parallel)
    shards = {policy: -(-trials // max_size) for policy in costs}

    def span(plan: dict[str, int]) -> float:
        durations = []
        for policy, n in plan.items():
            size = -(-trials // n)
            durations += [
                step_seconds(costs[policy], min(s + size, trials) - s) for s in range(0, trials, size)
            ]
        return makespan(sorted(durations, reverse=True), parallel)

    best, best_span = dict(shards), span(shards)
    while sum(shards.values()) < 4 * parallel:
        splittable = [p for p in shards if shards[p] < trials]
        if not splittable:
            break
        longest = max(splittable, key=lambda p: step_seconds(costs[p], -(-trials // shards[p])))
        shards[longest] += 1
        length = span(shards)
        if length < best_span * (1 - 1e-9):
            best, best_span = dict(shards), length
    return {policy: -(-trials // n) for policy, n in best.items()}


def planned_shard_sizes(config: RunConfig, parallel: int) -> dict[str, int]:
    """The shard sizes :func:`~benchmarks.harness.make_config` plans for ``config``'s run with
    ``parallel`` tasks at once (without ``shard_size``, before the memory check)."""
    return plan_shard_sizes(config.step_costs, config.trials, parallel)


def fit_shard_size(
    scenario: Scenario,
    agent_per_trial: dict[str, int],
    shard_size: int,
    workers: int,
    say: Callable[[str], None] = print,
    available: int | None = None,
) -> int:
    """The largest shard size, at most ``shard_size``, whose ``workers`` concurrent tasks fit
    in :data:`MEMORY_FRACTION` of the machine's memory (each task: the env's memory for its
    trials plus its policy's per trial, :func:`agents.costs.memory_per_trial`). Says when it
    lowers the shard size; raises :class:`~benchmarks.errors.HarnessError` with the estimate when one trial is
    already too much."""
    available = machine_memory() if available is None else available
    if available is None:  # pragma: no cover - not POSIX
        return shard_size
    fixed, env_per_trial = memory_parts(scenario)
    policy, agent = max(agent_per_trial.items(), key=lambda item: item[1])
    per_trial = env_per_trial + agent
    budget = MEMORY_FRACTION * available / workers
    fits = int((budget - fixed) // per_trial)
    gib = 2**30
    if fits < 1:
        raise HarnessError(
            f"one trial of {policy!r} on {scenario.name!r} ({scenario.num_tx} x {scenario.num_rx} "
            f"stations, {scenario.num_targets} targets) needs about {(fixed + per_trial) / gib:.2f} GiB "
            f"per task; {workers} task(s) at once may use {budget * workers / gib:.1f} GiB of this "
            f"machine's {available / gib:.1f} GiB: use fewer `workers`, a smaller layout or fewer targets"
        )
    if fits < shard_size:
        say(
            f"shards of {fits} trials instead of {shard_size}: {policy!r} needs about "
            f"{per_trial / 2**20:.0f} MiB per trial on {scenario.name!r}, and {workers} task(s) at "
            f"once may use {budget * workers / gib:.1f} GiB of this machine's {available / gib:.1f} GiB"
        )
        return fits
    return shard_size


def task_seconds(config: RunConfig, threads: int = 1) -> dict[tuple[str, int], float]:
    """Every (policy, shard) task's estimated seconds on ``threads`` threads
    (:func:`step_seconds` of its trials, at this machine's speed as :func:`estimate_seconds`):
    the order in which a run starts its tasks, the longest first."""
    costs = config.step_costs
    factor = machine_rate.factor() or 1.0
    return {
        (policy, shard): config.steps
        * step_seconds(costs[policy], len(config.shard_trials(policy, shard)), threads)
        * factor
        for policy, shard in config.tasks()
    }


def run_seconds(config: RunConfig, parallel: int = 1) -> float:
    """A configured run's estimated wall time, ``parallel`` tasks at once: its tasks' estimates
    (:func:`task_seconds`, which add up to :func:`estimate_seconds` of the whole run)."""
    costs = task_seconds(config)
    return sum(costs.values()) / max(1, min(parallel, len(costs)))


def longest_first(
    config: RunConfig, tasks: list[tuple[str, int]], cost: dict[tuple[str, int], float] | None = None
) -> list[tuple[str, int]]:
    """The (policy, shard) ``tasks`` of a run in the order they start: the longest declared cost
    first (``cost``, default :func:`task_seconds`), ties in the shard order."""
    if len(tasks) < 2:
        return list(tasks)
    cost = cost if cost is not None else task_seconds(config)
    return sorted(tasks, key=lambda task: -cost[task])


def choose_threads(
    configs: Sequence[RunConfig], todo: Sequence[tuple[int, str, int]], workers: int
) -> tuple[int, float, float]:
    """The threads per worker process for the ``todo`` (run, policy, shard) tasks on ``workers``
    cores, in their order: of every split into ``workers // threads`` processes of ``threads``
    threads, the one whose tasks end soonest by their declared costs (:func:`task_seconds`; ties
    go to fewer threads); with its estimated seconds and those of one thread per worker."""
    spans = []
    for threads in range(1, workers + 1):
        seconds = {number: task_seconds(configs[number], threads) for number in {n for n, _, _ in todo}}
        spans.append(makespan([seconds[n][p, s] for n, p, s in todo], workers // threads))
    best = 0
    for index, span in enumerate(spans):
        if span < spans[best] * (1 - 1e-9):
            best = index
    return best + 1, spans[best], spans[0]


def duration(seconds: float) -> str:
    """``"45 s"``, ``"12 min"``, ``"3.5 h"``, ``"4.2 days"``."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def check_time(
    seconds: float, where: str, slowest: str, max_hours: float | None, say: Callable[[str], None] = print
) -> None:
    """Says a run's estimated time ``seconds`` (:func:`estimate_seconds`; ``where`` describes the
    run) when it is a minute or more; raises :class:`~benchmarks.errors.HarnessError` with the
    estimate and what to change when it exceeds ``max_hours`` (``None``: no limit)."""
    if max_hours is not None and seconds > 3600 * max_hours:
        raise HarnessError(
            f"{where} would take about {duration(seconds)} (the slowest policy: {slowest!r}), more than "
            f"`max_hours` {max_hours:g}: use fewer `trials` or `steps`, more `workers`, a smaller layout, "
            "or a larger `max_hours`"
        )
    if seconds >= 60:
        say(f"{where}: about {duration(seconds)} {estimated_where()}")


def estimated_where() -> str:
    """Whose speed an estimate is: this machine's where ``compile`` measured it."""
    if machine_rate.factor() is None:
        return (
            "on a machine like the developers' (a rough estimate; 'mimo-radar-bench compile' times this one)"
        )
    return "on this machine (a rough estimate, from the speed 'mimo-radar-bench compile' measured here)"
