"""The Monte-Carlo harness: policies x trials x steps, in shards, resumable.

A run is fixed by a :class:`RunConfig`. Its trials are cut into shards of
``shard_size`` trials; one task runs one policy on one shard with the vector env
(trial ``i`` seeded ``seed + i``, so every policy sees the same target trajectories
for trial ``i``) and returns the shard's per-trial arrays (:mod:`benchmarks.shards`). Each finished
task is written at once to ``DIR/shards/<policy>/shard_<k>.npz`` (atomically), so
an interrupted run started again with the same configuration and ``DIR`` skips
what is done and loses or double-counts nothing; a different configuration
pointed at the same ``DIR`` is refused.

Tasks run in the calling process (``workers=1``), in local worker processes, or on
a Ray cluster (``backend="ray"``). A task's result depends only on the
configuration and its shard, so every backend gives the same numbers.
"""

from __future__ import annotations

import collections
import contextlib
import fcntl
import functools
import hashlib
import json
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

import agents
from agents.ppo import model_file
from agents.solvers import compiled_kernels as solver_kernels
from mimo_radar_env import EnvOptions, Scenario, ScenarioError, load_scenario
from mimo_radar_env.core import compiled
from mimo_radar_env.core.compiled import uncached
from mimo_radar_env.core.streams import MAX_AGENT_SEED
from mimo_radar_env.envs.cost import machine_memory
from mimo_radar_env.envs.device_forms import check_device_mode
from mimo_radar_env.envs.versions import env_version, scenario_version
from mimo_radar_env.tracking.fusion import compiled_kernels
from mimo_radar_env.tracking.selection import compiled_kernels as selection_kernels

from . import backends
from .errors import BenchError, HarnessError
from .resources import (
    StepCost,
    check_time,
    choose_threads,
    declared_seconds,
    duration,
    estimate_seconds,
    estimated_where,
    fit_shard_size,
    longest_first,
    plan_shard_sizes,
    policy_step_costs,
    task_seconds,
)
from .shards import (
    DATA_FIELDS,
    TRIAL_FIELDS,
    TRUTH_FIELD,
    ShardRecorder,
    config_hash,
    read_shard,
    set_aside,
    shard_path,
    write_shard,
)

CONFIG_FILE = "config.json"
LOCK_FILE = ".lock"
PAPER_POLICIES = ("best", "mg-crb-cl", "ucb1", "epsilon-greedy", "fix1", "fix2")


@dataclass(frozen=True)
class RunConfig:
    """Everything that determines a run's numbers.

    Attributes
    ----------
    scenario : dict
        The scenario's data (``Scenario.to_dict()``): a changed file changes the run.
    policies : list of str
        Registered agent names, ``NAME:ARGUMENT`` for agents that take one (``ppo:PATH``).
    trials, steps, seed, shard_size : int
    shard_sizes : dict
        ``{policy: trials per shard}`` where a policy's shards differ from ``shard_size`` (the
        cost-aware schedule, :func:`plan_shard_sizes`); empty: every policy's are
        ``shard_size``.
    env_options : dict
        Every env option (:class:`~mimo_radar_env.EnvOptions`), defaults included.
    agent_params : dict
        ``{policy: {parameter: value}}``.
    policy_files : dict
        ``{policy: {file: sha256}}`` for policies read from files (a trained model and its
        normalisation statistics): a changed file is a different run.
    """

    scenario: dict[str, Any]
    policies: list[str]
    trials: int
    steps: int
    seed: int = 0
    shard_size: int = 50
    env_options: dict[str, Any] = field(default_factory=lambda: EnvOptions().to_dict())
    agent_params: dict[str, dict[str, Any]] = field(default_factory=dict)
    policy_files: dict[str, dict[str, str]] = field(default_factory=dict)
    shard_sizes: dict[str, int] = field(default_factory=dict)

    def size_of(self, policy: str) -> int:
        """Trials per shard of ``policy``."""
        return self.shard_sizes.get(policy, self.shard_size)

    def shards_of(self, policy: str) -> int:
        return -(-self.trials // self.size_of(policy))

    def shard_trials(self, policy: str, shard: int) -> range:
        size = self.size_of(policy)
        return range(shard * size, min((shard + 1) * size, self.trials))

    def tasks(self) -> list[tuple[str, int]]:
        """Every (policy, shard) task, shard by shard."""
        shards = {policy: self.shards_of(policy) for policy in self.policies}
        return [(p, s) for s in range(max(shards.values())) for p in self.policies if s < shards[p]]

    @functools.cached_property
    def scenario_object(self) -> Scenario:
        """The scenario, built and checked once per process."""
        return Scenario.from_dict(self.scenario)

    @property
    def options(self) -> EnvOptions:
        return EnvOptions(**self.env_options)

    @functools.cached_property
    def step_costs(self) -> dict[str, StepCost]:
        """Each policy's declared cost per step of a shard (:func:`policy_step_costs`), built once."""
        return policy_step_costs(self.scenario_object, self.options, _policies(self))

    def to_json(self) -> dict[str, Any]:
        """The configuration as config.json holds it (``shard_sizes`` only where it says
        something, so a run written before it existed is the same run)."""
        out = asdict(self)
        if not out["shard_sizes"]:
            del out["shard_sizes"]
        return out


def make_config(
    scenario: str | Path | Scenario,
    policies: Sequence[str],
    trials: int,
    steps: int | None = None,
    seed: int = 0,
    shard_size: int | Mapping[str, int] | None = None,
    agent_params: dict[str, dict[str, Any]] | None = None,
    options: EnvOptions | Mapping[str, Any] | None = None,
    workers: int = 1,
    say: Callable[[str], None] = print,
    max_hours: float | None = None,
    parallel: int | None = None,
) -> RunConfig:
    """Validate every piece of a run and build its configuration; nothing is written.

    Each policy is built and reset on a one-trial env with the run's options, so a bad
    parameter, a missing model or an agent that needs the tracker fails here, with a
    one-line :class:`HarnessError` naming the argument, before any output exists. The memory a
    task needs (:func:`fit_shard_size`) is checked against the machine for ``workers`` tasks at
    once: the shard size is lowered until it fits, and ``say`` says so, or the run is refused.
    Its time (:func:`estimate_seconds`, with ``parallel`` tasks at once, default ``workers``) is
    said when it is a minute or more, and a run estimated at more than ``max_hours`` is refused.
    ``shard_size`` None is the cost-aware schedule for those tasks (:func:`plan_shard_sizes`);
    a mapping gives each policy's (a resumed run's, :func:`recorded_shard_size`). ``options``
    are the env's: an :class:`~mimo_radar_env.EnvOptions`, or a mapping of options over the
    defaults of the version ``scenario`` belongs to (``paper-1-v1`` v1's, ``paper-1`` v0's, any
    other scenario v1's); None, those defaults.
    """
    try:
        sc = load_scenario(scenario)
    except ScenarioError as exc:
        raise HarnessError(str(exc)) from exc
    options = check_options(options, scenario_version(scenario))  # v1's for a scenario of no version
    _check_max_hours(max_hours)
    _check_counts(("workers", workers, 1), ("parallel", 1 if parallel is None else parallel, 1))
    parallel = parallel or workers
    if isinstance(shard_size, Mapping):
        if sorted(shard_size) != sorted(policies):
            raise HarnessError(
                f"`shard_size` names {sorted(shard_size)}, not the run's policies {list(policies)}"
            )
        for size in shard_size.values():
            _check_sizes(sc, trials, steps, seed, size)
    steps = _check_sizes(sc, trials, steps, seed, None if isinstance(shard_size, Mapping) else shard_size)
    params = _check_policies(policies, agent_params or {})
    built = {policy: _probe(policy, sc, params.get(policy, {}), seed, options) for policy in policies}
    sizes = _shard_sizes(sc, options, built, trials, shard_size, parallel, workers, say)
    shard_size = max(sizes.values())
    _check_run_time(sc, options, built, trials, steps, sizes, parallel, max_hours, say)
    try:  # config.json is strict JSON: a parameter that is not (NaN, infinity, an object) is refused here
        json.dumps(params, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise HarnessError(f"`agent_params`: a value cannot be recorded in config.json ({exc})") from None
    return RunConfig(
        policy_files={p: files for p in policies if (files := _policy_files(p, built[p]))},
        scenario=sc.to_dict(),
        policies=list(policies),
        trials=trials,
        steps=steps,
        seed=seed,
        shard_size=shard_size,
        shard_sizes={p: n for p, n in sizes.items() if n != shard_size},
        env_options=options.to_dict(),
        agent_params={k: dict(v) for k, v in params.items()},
    )


def _shard_sizes(
    sc: Scenario,
    options: EnvOptions,
    built: dict[str, agents.Agent],
    trials: int,
    given: int | Mapping[str, int] | None,
    parallel: int,
    workers: int,
    say: Callable[[str], None],
) -> dict[str, int]:
    """Each policy's shard size: ``given`` (one for all, or each policy's), or planned by cost
    (:func:`plan_shard_sizes`, said where they differ); lowered where ``workers`` tasks at once
    would not fit in memory (:func:`fit_shard_size`)."""
    if given is None:
        sizes = plan_shard_sizes(policy_step_costs(sc, options, built), trials, parallel)
    else:
        sizes = dict(given) if isinstance(given, Mapping) else dict.fromkeys(built, given)
    per_trial = {policy: agents.costs.memory_per_trial(agent) for policy, agent in built.items()}
    fitted = fit_shard_size(sc, per_trial, max(sizes.values()), workers, say)
    sizes = {policy: min(size, fitted) for policy, size in sizes.items()}
    if given is None and len(set(sizes.values())) > 1:
        say("shards by cost: " + ", ".join(f"{p} {-(-trials // n)} of {n} trials" for p, n in sizes.items()))
    return sizes


def _check_sizes(sc: Scenario, trials: int, steps: int | None, seed: int, shard_size: int | None) -> int:
    """Refuses a count that is not a whole number in its range; the run's steps."""
    _check_counts(("trials", trials, 1), ("seed", seed, 0))
    if seed + trials - 1 > MAX_AGENT_SEED:  # trial i's agent is seeded seed + i (TrialRandom)
        raise HarnessError(
            f"`seed` must be at most 2**63 - {trials} for {trials} trials (trial i is seeded seed + i, "
            f"and agents' seeds are at most 2**63 - 1), got {seed}"
        )
    if shard_size is not None:
        _check_counts(("shard_size", shard_size, 1))
    steps = sc.horizon if steps is None else steps
    if isinstance(steps, bool) or not isinstance(steps, int) or not 1 <= steps <= sc.horizon:
        raise HarnessError(f"`steps` must be between 1 and the scenario horizon {sc.horizon}, got {steps!r}")
    return steps


def check_options(options: EnvOptions | Mapping[str, Any] | None, version: str) -> EnvOptions:
    """The run's env options: ``options`` as it is, or a mapping of options over the defaults of
    env ``version``, or those defaults (an unknown option is a ``TypeError``, as in
    :class:`~mimo_radar_env.EnvOptions`)."""
    if isinstance(options, EnvOptions):
        return options
    if options is not None and not isinstance(options, Mapping):
        raise HarnessError(
            f"`options` must be an EnvOptions or a mapping of env options, got {type(options).__name__}"
        )
    try:
        return env_version(version).options(**(options or {}))
    except ValueError as exc:
        raise HarnessError(f"`options`: {exc}") from None


def _check_counts(*given: tuple[str, Any, int]) -> None:
    """Refuses each ``(name, value, low)`` whose value is not an integer >= low."""
    for name, value, low in given:
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise HarnessError(f"`{name}` must be an integer >= {low}, got {value!r}")


def _check_max_hours(max_hours: float | None) -> None:
    if max_hours is not None and (
        isinstance(max_hours, bool) or not isinstance(max_hours, int | float) or not max_hours > 0
    ):
        raise HarnessError(f"`max_hours` must be a number of hours > 0 or None (no limit), got {max_hours!r}")


def _check_policies(policies: Sequence[str], params: dict[str, dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Refuses no policy, a policy twice, an unknown one, and parameters of a policy not in the
    run or setting the agent's seed; the parameters."""
    if isinstance(policies, str):
        raise HarnessError(f"policies must be a list of policy names, got the string {policies!r}")
    if not policies:
        raise HarnessError("give at least one policy")
    if len(set(policies)) != len(policies):
        raise HarnessError(f"policies are listed twice: {list(policies)}")
    if not isinstance(params, Mapping) or not all(isinstance(v, Mapping) for v in params.values()):
        raise HarnessError(
            "`agent_params` must map policy names to mappings of their parameters, e.g. "
            f"{{'ucb1': {{'beta': 1.0}}}}, got {params!r}"
        )
    for policy, values in params.items():
        if "seed" in values:
            raise HarnessError(
                f"`agent_params` {policy}.seed: agents' seeds are set by the run (`seed`), not per agent"
            )
        if policy not in policies:
            raise HarnessError(
                f"`agent_params` names policy {policy!r}, which is not in the run {list(policies)}"
            )
    for policy in policies:
        try:
            agents.split_policy(policy)
        except agents.registry.UnknownAgentError:
            raise HarnessError(
                f"unknown policy {policy!r}; available policies are {agents.available_agents()} "
                "(and NAME:ARGUMENT for those that take one, e.g. ppo:PATH/model.zip, or an agents.Agent "
                "subclass as module:Class)"
            ) from None
        except ValueError as exc:
            raise HarnessError(str(exc)) from None
    return params


def _probe(policy: str, sc: Scenario, params: dict[str, Any], seed: int, options: EnvOptions) -> agents.Agent:
    """The policy's agent, built and reset on a one-trial env of the run (a bad parameter, a
    missing model or a missing env option fails here)."""
    try:
        agent = make_policy(policy, sc, params, seed=seed, options=options.to_dict())
        agents.Rollout(agent, agents.make_env(agent, 1, options, sc), seed=seed)
    except HarnessError as exc:  # its arguments kept marked for the command line
        raise HarnessError(f"policy {policy!r}: {exc.args[0]}") from exc
    except (ValueError, TypeError, OSError) as exc:
        raise HarnessError(f"policy {policy!r}: {exc}") from exc
    return agent


def _check_run_time(
    sc: Scenario,
    options: EnvOptions,
    built: dict[str, agents.Agent],
    trials: int,
    steps: int,
    shard_size: int | Mapping[str, int],
    parallel: int,
    max_hours: float | None,
    say: Callable[[str], None],
) -> None:
    """Says the run's estimated time, or refuses it beyond ``max_hours`` (:func:`check_time`)."""
    size = (trials, steps, shard_size)
    alone = {p: _built_seconds(sc, options, {p: built[p]}, size, 1) for p in built}
    where = (
        f"{trials} trials x {steps} steps of {len(built)} polic{'y' if len(built) == 1 else 'ies'} "
        f"on {sc.name!r}, {parallel} task(s) at once"
    )
    seconds = _built_seconds(sc, options, built, size, parallel)
    check_time(seconds, where, max(alone, key=alone.__getitem__), max_hours, say)


def _built_seconds(
    sc: Scenario,
    options: EnvOptions,
    built: dict[str, agents.Agent],
    size: tuple[int, int, int | Mapping[str, int]],
    parallel: int,
) -> float:
    """:func:`estimate_seconds` of the built agents' declared costs; ``size`` is the run's
    (trials, steps, shard size)."""
    per_trial, fixed, _ = declared_seconds(built)
    return estimate_seconds(sc, options, per_trial, *size, parallel, fixed)


def _policies(config: RunConfig) -> dict[str, agents.Agent]:
    """Every policy of ``config``'s run, built as its tasks build it (for its declared costs)."""
    sc = config.scenario_object
    return {
        policy: make_policy(policy, sc, config.agent_params.get(policy, {}), seed=config.seed,
                            options=config.env_options)
        for policy in config.policies
    }  # fmt: skip


def _policy_files(policy: str, agent: Any) -> dict[str, str]:
    """``{path: sha256}`` of the files a ``NAME:PATH`` policy reads: its model and the
    normalisation statistics the built agent applies (``agent.normalization_file``)."""
    name, argument = agents.split_policy(policy)
    if agents.agent_argument(name) != "path" or not argument:
        return {}
    files = [model_file(argument["path"]), getattr(agent, "normalization_file", None)]
    return {
        str(f): hashlib.sha256(f.read_bytes()).hexdigest() for f in files if f is not None and f.is_file()
    }


# ------------------------------------------------------------------ one task
def run_task(
    config: dict[str, Any], policy: str, shard: int, device: Any = None, device_mode: str = "eager"
) -> dict[str, NDArray]:
    """Run ``policy`` on shard ``shard`` of the run; the shard's fields
    (:mod:`benchmarks.shards` lists them): per-trial float64 arrays of the mean rewards, the
    squared position errors and bounds, the matches with the optimal super arm, the station
    selection counts, the compute time and the first trial's truth. ``device`` runs the env and
    the agent on torch there (the same numbers to rounding), the step in form ``device_mode``;
    the fields come back to numpy."""
    cfg = RunConfig(**config)
    scenario = cfg.scenario_object
    trials = cfg.shard_trials(policy, shard)
    start = time.perf_counter()
    agent = make_policy(
        policy,
        scenario,
        cfg.agent_params.get(policy, {}),
        seed=cfg.seed + trials.start,
        options=cfg.env_options,
    )
    env = agents.make_env(
        agent, len(trials), cfg.env_options, scenario, device=device, device_mode=device_mode
    )
    episode = agents.Rollout(agent, env, seed=cfg.seed + trials.start)
    host = env.engine.xp.to_numpy
    record = ShardRecorder(
        env.engine.xp,
        host,
        len(trials),
        cfg.steps,
        scenario.num_targets,
        scenario.num_tx + scenario.num_rx,
        episode.info["true_state"][0],
    )
    for step in episode.run(cfg.steps):
        backends.follow_thread_budget()
        record.add(step.action, step.info)
    out = record.result()
    repairs = episode.info.get("tracker_repairs")
    out["tracker_repairs"] = np.array(float(0 if repairs is None else np.sum(host(repairs))))
    out["wall_s"] = np.array(time.perf_counter() - start)
    return out


def run_kernels(config: RunConfig, threads: int | None = None) -> list[Any]:
    """The numba kernels a run's tasks call (the env's fusion and bound, the policies' solvers),
    with ``threads`` numba threads in each task (None: numba's count here): the twins over
    threads where a task has threads and more than one chunk of trials to spread."""
    threads = threads or (compiled.threads() if compiled.HAVE_NUMBA else 1)
    threaded = threads > 1 and max(config.size_of(p) for p in config.policies) > compiled.CHUNK
    kernels = compiled_kernels(config.options.fusion, threaded) if config.options.tracking else []
    for policy in config.policies:
        cls = agents.agent_class(agents.split_policy(policy)[0])
        if cls.needs.tracking_search:
            kernels += selection_kernels(threaded)
        solver = config.agent_params.get(policy, {}).get("solver", getattr(cls, "default_solver", None))
        if isinstance(solver, str):
            kernels += solver_kernels(solver, threads)
    return kernels


def make_policy(
    policy: str,
    scenario: Scenario,
    params: dict[str, Any],
    seed: int,
    options: dict[str, Any] | None = None,
) -> agents.Agent:
    """The agent of a policy entry ``NAME`` or ``NAME:ARGUMENT`` with its parameters; the
    parameters it names after env options (``Agent.needs.env_option_params``), left out, take
    the run's ``options``, and given, must equal them (else the agent could not run on the run's
    env)."""
    name, argument = agents.split_policy(policy)
    from_env = {}
    for key in agents.agent_class(name).needs.env_option_params if options is not None else ():
        if key not in params:
            from_env[key] = options[key]
        elif params[key] != options[key]:
            raise HarnessError(
                f"`agent_params` {policy}.{key}={params[key]!r} differs from the run's "
                f"{key}={options[key]!r}; leave it out (the agent takes the run's)"
            )
    return agents.make_agent(name, scenario, seed=seed, **argument, **from_env, **params)


# ------------------------------------------------------------------ the Python call
def policy_name(policy: str | type[agents.Agent], workers: int = 1) -> str:
    """The policy entry of a registered name (as it is) or of an :class:`agents.Agent` subclass:
    its registered name, else ``module:Class``, which every worker imports. A class defined in
    ``__main__`` is registered here and needs ``workers`` 1 (workers cannot import it)."""
    if isinstance(policy, str):
        return policy
    if not (isinstance(policy, type) and issubclass(policy, agents.Agent)):
        raise HarnessError(f"a policy must be a name or an agents.Agent subclass, got {policy!r}")
    reference = f"{policy.__module__}:{policy.__qualname__}"
    if policy.__module__ == "__main__":
        if workers != 1:
            raise HarnessError(
                f"{policy.__qualname__} is defined in __main__, which worker processes cannot import: "
                "put it in a module (then it runs as module:Class), or use `workers` 1"
            )
        agents.register_agent(reference, policy)
    return reference


# ------------------------------------------------------------------ storage
def recorded_shard_size(
    out: str | Path, policies: Sequence[str] | None = None
) -> int | dict[str, int] | None:
    """The shard size of the run already in ``out``, each policy's where they differ (None: no
    readable run there, or one of other ``policies``), which a resumed run without
    ``--shard-size`` keeps, whatever its number of workers."""
    try:
        config = json.loads((Path(out) / CONFIG_FILE).read_text())
        size, sizes = config.get("shard_size"), config.get("shard_sizes", {})
    except (OSError, ValueError, AttributeError):
        return None

    def count(value: Any) -> bool:
        return isinstance(value, int) and not isinstance(value, bool) and value >= 1

    if not count(size) or not isinstance(sizes, dict) or not all(map(count, sizes.values())):
        return None
    if not sizes:
        return size
    recorded = config.get("policies")
    if not isinstance(recorded, list) or not all(isinstance(p, str) for p in recorded):
        return None
    if not set(sizes) <= set(recorded) or (policies is not None and sorted(policies) != sorted(recorded)):
        return None
    return {policy: sizes.get(policy, size) for policy in recorded}


def prepare_output(out: Path, config: RunConfig) -> None:
    """Create DIR, or check that the run already in it has the same configuration."""
    path = out / CONFIG_FILE
    wanted = json.loads(json.dumps(config.to_json(), allow_nan=False))
    try:
        for name, kind in (("shards", "a folder"), ("summary.json", "a file"), ("table.md", "a file")):
            other = out / name
            if other.exists() and (other.is_dir() != (kind == "a folder")):
                raise HarnessError(
                    f"{other} should be {kind} of a run: `out` {out} is damaged or not a run's folder; "
                    "remove it or choose another `out`"
                )
        if path.exists():
            try:
                existing = json.loads(path.read_text())
            except (UnicodeDecodeError, json.JSONDecodeError) as exc:
                raise HarnessError(
                    f"{path} is not a run's configuration (not JSON: {exc}): "
                    "remove it or choose another `out`"
                ) from exc
            if not isinstance(existing, dict):
                raise HarnessError(f"{path} is not a run's configuration: remove it or choose another `out`")
            if existing != wanted:
                changed = sorted(k for k in set(existing) | set(wanted) if existing.get(k) != wanted.get(k))
                raise HarnessError(
                    f"{out} holds a run with a different configuration (differs in {changed}); "
                    "resume it with the same arguments or choose another `out`"
                )
        else:
            path.write_text(json.dumps(wanted, indent=2, allow_nan=False))
    except OSError as exc:
        raise HarnessError(f"cannot use `out` {out}: {exc.strerror or exc}") from exc


def output_folder(out: str | Path) -> Path:
    """``out``, made where it is new; refused in one line where it is a file or cannot be made or
    written into. A command whose outputs come at the end of its work calls it first, so that
    nothing measured is lost to a bad ``out``."""
    out = _folder_path(out)
    if out.exists() and not out.is_dir():
        raise HarnessError(f"`out` {out} is a file, not a folder: choose a folder, new or a run's own")
    try:
        out.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=out).close()
    except OSError as exc:
        raise HarnessError(f"cannot write into `out` {out}: {exc.strerror or exc}") from exc
    return out


def _folder_path(out: str | os.PathLike[str]) -> Path:
    """``out`` as a path; an empty string (``Path("")`` is the current folder) refused."""
    if isinstance(out, str) and not out.strip():
        raise HarnessError(f"`out` must name a folder, got {out!r}")
    return Path(out)


@contextlib.contextmanager
def output_lock(out: Path) -> Iterator[None]:
    """Hold DIR/.lock for the run: a second run into the same DIR is refused, not interleaved.
    A run refused while holding it (a damaged folder, say) leaves the folder as it found it:
    the lock file, and the folder, are removed again where this call made them."""
    made_folder = not out.exists()
    made_lock = not (out / LOCK_FILE).exists()
    output_folder(out)
    try:
        handle = open(out / LOCK_FILE, "a+")  # held (and locked) for the whole run
    except OSError as exc:
        raise HarnessError(f"cannot write into `out` {out}: {exc.strerror or exc}") from exc
    locked = False
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            locked = True
        except BlockingIOError:
            raise HarnessError(
                f"another run is writing into {out}; wait for it to finish or choose another `out`"
            ) from None
        yield
    except BenchError:
        if locked and made_lock:
            (out / LOCK_FILE).unlink(missing_ok=True)
            if made_folder and not any(out.iterdir()):
                out.rmdir()
        raise
    finally:
        handle.close()  # releases the lock


def _tasks_to_run(
    out: Path,
    config: RunConfig,
    warn: Callable[[str], None],
    keep: Callable[[str, int, dict], None] | None = None,
) -> list[tuple[str, int]]:
    """Tasks without a valid shard; damaged or foreign shards are named and set aside. Each valid
    shard's data is handed to ``keep(policy, shard, data)``."""
    payload = config.to_json()
    todo = []
    for policy, shard in config.tasks():
        path = shard_path(out, policy, shard)
        if path.exists():
            try:
                data = read_shard(path, config.shard_trials(policy, shard), config_hash(payload, policy))
                if keep is not None:
                    keep(policy, shard, data)
                continue
            except ValueError as exc:
                moved = set_aside(path)
                warn(f"shard {path} is not valid ({exc}); set aside as {moved.name}, computing it again")
        todo.append((policy, shard))
    return todo


# ------------------------------------------------------------------ running
class RunInterrupted(HarnessError):
    """Ctrl-C stopped the run; every finished task is saved and the run can be resumed."""


def run(
    config: RunConfig,
    out: str | Path,
    workers: int = 1,
    backend: str = "local",
    address: str | None = None,
    progress: bool = True,
    max_tasks: int | None = None,
    device: Any = None,
    threads: int | None = None,
    device_mode: str = "eager",
) -> dict[str, dict[str, NDArray]] | None:
    """Run every (policy, shard) task not yet in ``out``; return every policy's shard fields
    joined over trials (:func:`load_per_trial`).

    ``max_tasks`` stops after that many new tasks (to test resumption); the run is
    then incomplete and ``None`` is returned. Ctrl-C raises :class:`RunInterrupted` after
    the finished tasks are saved. ``workers``, ``threads``, ``device`` and ``device_mode`` as in
    :func:`run_many`.
    """
    joined: list[dict[str, dict[str, NDArray]]] = []
    run_many(
        [(config, out)],
        workers,
        backend,
        address,
        progress,
        max_tasks,
        on_complete=lambda _, per_trial: joined.append(per_trial),
        device=device,
        threads=threads,
        device_mode=device_mode,
    )
    return joined[0] if joined else None


def run_many(
    runs: Sequence[tuple[RunConfig, str | Path]],
    workers: int = 1,
    backend: str = "local",
    address: str | None = None,
    progress: bool = True,
    max_tasks: int | None = None,
    on_complete: Callable[[int, dict[str, dict[str, NDArray]]], None] | None = None,
    device: Any = None,
    threads: int | None = None,
    device_mode: str = "eager",
    on_policy: Callable[[int, str, dict[str, NDArray]], None] | None = None,
) -> list[bool]:
    """Run the tasks of several runs (a study's) on one set of workers; whether each run is
    complete.

    Each run's tasks not yet in its folder are started the longest first
    (:func:`task_seconds`), run after run, without waiting for one run to end before the
    next starts, so that no worker idles at a run's end. ``on_complete(i, per_trial)`` is called
    in this process as soon as run ``i`` has all its shards (at once for a run already complete),
    with its shards joined (:func:`load_per_trial`), while the workers go on with the next run's
    tasks: the place to write its outputs. ``on_policy(i, policy, joined)`` is called likewise as
    soon as this call has saved the last shard of one policy of run ``i``, with that policy's
    shards joined (the same arrays ``on_complete`` then gets): the place to start on that policy's
    outputs while the workers go on. The shards this call checked or wrote are joined from
    memory (up to :func:`held_bytes` of them), not read again. ``max_tasks``
    and Ctrl-C as in :func:`run`. ``device`` (``"cuda"``, ``"cpu"``...) runs every task on torch
    on that device, the step in form ``device_mode`` (``"eager"``, ``"graph"``, ``"compiled"``),
    on the local backend: in this process, or in ``workers`` processes sharing the device, so
    that one process's kernel launches leave the device to another's work.

    ``workers`` counts cores: with more than one (or on Ray) the tasks run on
    ``workers // threads`` worker processes of ``threads`` compute threads each (the compiled
    kernels spread a task's trials over them). ``threads`` None chooses it from the tasks'
    declared costs (:func:`choose_threads`) and says so where it is more than one. One worker
    runs the tasks in this process, on numba's threads (all the cores unless ``threads``).
    The numbers are the same whatever the threads.
    """
    configs, folders = _checked_runs(runs)
    _check_execution(backend, workers, address, folders, device, configs, threads, device_mode)
    if backend == "local" and workers > 1:
        # the workers' imports, while this process plans the run
        backends.start_fork_server(device=device is not None)
    with contextlib.ExitStack() as locks:
        for config, out in zip(configs, folders, strict=True):
            locks.enter_context(output_lock(out))
            prepare_output(out, config)
        held = _Held(held_bytes() if on_complete is not None or on_policy is not None else 0)
        todo, estimated = _queue(configs, folders, max_tasks, held)
        started = time.perf_counter()
        saving = _Saving(configs, folders, todo, on_complete, held, on_policy)
        if max_tasks is None:
            _say_resumed(configs, folders, saving.left)
        threads = _threads_for(configs, todo, workers, backend, threads, device is not None)
        saving.bar = _progress_bar(configs, todo, saving.steps_of, progress)
        on_device = () if device is None else (str(device), device_mode)
        tasks = [(saving.payloads[number], policy, shard, *on_device) for number, policy, shard in todo]
        try:
            saving.runs_already_done()
            _dispatch(
                tasks,
                saving.finished,
                workers,
                backend,
                address,
                threads,
                configs,
                starting=functools.partial(_say_compiling, saving.bar, configs, todo, threads),
                on_device=device is not None,
            )
            _say_if_slow(time.perf_counter() - started, estimated / max(1, min(workers, len(todo))))
        except KeyboardInterrupt:
            raise RunInterrupted(
                f"interrupted: {len(saving.saved)} of {len(todo)} tasks finished and saved in "
                f"{', '.join(str(f) for f in folders)}; run the same command again to resume"
            ) from None
        finally:
            saving.bar.close()
        return saving.complete


#: At most this many bytes of shard data, and at most :data:`HELD_SHARE` of this machine's memory,
#: are held between a shard's check or write and its run's ``on_complete`` (the others are read
#: again from their files).
HELD_BYTES = 1 << 30
HELD_SHARE = 1 / 16


def held_bytes() -> int:
    """How many bytes of shard data :func:`run_many` holds for the runs' ``on_complete``."""
    memory = machine_memory()
    return HELD_BYTES if memory is None else min(HELD_BYTES, int(HELD_SHARE * memory))


class _Held:
    """The shard data a :func:`run_many` call has checked or written, by run, kept up to
    ``budget`` bytes in all for the runs' ``on_complete``."""

    def __init__(self, budget: int) -> None:
        self.shards: dict[int, dict[tuple[str, int], dict[str, NDArray]]] = {}
        self.nbytes, self.budget = 0, budget

    def add(self, number: int, policy: str, shard: int, data: Mapping[str, Any]) -> None:
        arrays = {key: np.asarray(data[key]) for key in DATA_FIELDS}
        size = sum(a.nbytes for a in arrays.values())
        if self.nbytes + size > self.budget:
            return
        # a read-only array is a backend's buffer (Ray's object store, released at its shutdown,
        # before the caller is done with the run's arrays): held as a copy
        held = {key: a if a.flags.writeable else a.copy() for key, a in arrays.items()}
        self.shards.setdefault(number, {})[policy, shard] = held
        self.nbytes += size

    def pop(self, number: int) -> dict[tuple[str, int], dict[str, NDArray]]:
        shards = self.shards.pop(number, {})
        self.nbytes -= sum(a.nbytes for data in shards.values() for a in data.values())
        return shards

    def pop_policy(self, number: int, policy: str) -> dict[tuple[str, int], dict[str, NDArray]]:
        """The shards of one policy of run ``number``, no longer held."""
        run = self.shards.get(number, {})
        shards = {key: run.pop(key) for key in [key for key in run if key[0] == policy]}
        self.nbytes -= sum(a.nbytes for data in shards.values() for a in data.values())
        return shards


class _Saving:
    """A run's finished tasks: each one's shard written at once (and held, :class:`_Held`), the
    progress bar moved, ``on_policy(i, policy, joined)`` called as soon as one policy of run ``i``
    has all its shards and ``on_complete(i, per_trial)`` as soon as run ``i`` has."""

    def __init__(
        self,
        configs: Sequence[RunConfig],
        folders: Sequence[Path],
        todo: list[tuple[int, str, int]],
        on_complete: Callable[[int, dict[str, dict[str, NDArray]]], None] | None,
        held: _Held,
        on_policy: Callable[[int, str, dict[str, NDArray]], None] | None = None,
    ) -> None:
        self.configs, self.folders, self.todo, self.on_complete = configs, folders, todo, on_complete
        self.held, self.on_policy = held, on_policy
        self.payloads = [config.to_json() for config in configs]
        self.left_of_policy = collections.Counter((n, p) for n, p, _ in todo)
        self.joined: dict[int, dict[str, dict[str, NDArray]]] = {}  # the policies given to on_policy
        self.steps_of = [  # the trial-steps of each run's tasks
            {(p, s): len(c.shard_trials(p, s)) * c.steps for p, s in c.tasks()} for c in configs
        ]
        self.saved: list[int] = []
        self.complete = [False] * len(configs)
        self.bar: Any = None

    def runs_already_done(self) -> None:
        for number, left in enumerate(self.left):
            if left == 0:
                self.run_done(number)

    def run_done(self, number: int) -> None:
        # every shard of the run is one checked when the run was queued or one written here (the
        # folder is locked): complete unless ``max_tasks`` left some out
        config, folder = self.configs[number], self.folders[number]
        if all(shard_path(folder, p, s).exists() for p, s in config.tasks()):
            self.complete[number] = True
            held, joined = self.held.pop(number), self.joined.pop(number, {})
            if self.on_complete is not None:
                self.on_complete(number, load_per_trial(folder, config, held, joined))

    def finished(self, position: int, result: dict[str, NDArray]) -> None:
        number, policy, shard = self.todo[position]
        config = self.configs[number]
        write_shard(
            shard_path(self.folders[number], policy, shard),
            result,
            config.shard_trials(policy, shard),
            config_hash(self.payloads[number], policy),
        )
        self.held.add(number, policy, shard, result)
        self.saved.append(position)
        self.bar.update(self.steps_of[number][policy, shard])
        self.bar.set_postfix_str(policy if len(self.configs) == 1 else f"{config.scenario['name']}: {policy}")
        self.left_of_policy[number, policy] -= 1
        if self.left_of_policy[number, policy] == 0 and self.on_policy is not None:
            joined = join_policy(self.folders[number], config, policy, self.held.pop_policy(number, policy))
            self.joined.setdefault(number, {})[policy] = joined
            self.on_policy(number, policy, joined)
        if self.left[number] == 0:
            self.run_done(number)

    @property
    def left(self) -> list[int]:
        """Each run's tasks not yet saved."""
        left = [0] * len(self.configs)
        for (number, _), count in self.left_of_policy.items():
            left[number] += count
        return left


def _say_resumed(configs: Sequence[RunConfig], folders: Sequence[Path], left: Sequence[int]) -> None:
    """Says, for each run some of whose tasks are already saved, how many."""
    for config, folder, todo in zip(configs, folders, left, strict=True):
        total = len(config.tasks())
        if total - todo > 0:
            tqdm.write(f"resumed: {total - todo} of {total} tasks already done in {folder}", file=sys.stderr)


def in_this_process(backend: str, workers: int) -> bool:
    """Whether a run's tasks run in the calling process (one local worker), not in worker
    processes or on Ray."""
    return backend == "local" and workers == 1


def _dispatch(
    tasks: list[backends.Task],
    finished: backends.Finished,
    workers: int,
    backend: str,
    address: str | None,
    threads: int | None,
    configs: Sequence[RunConfig] = (),
    starting: Callable[[], None] = lambda: None,
    on_device: bool = False,
) -> None:
    """Runs ``tasks`` on the backend: Ray (tasks of ``threads`` CPUs), this process (one
    worker, on ``threads`` numba threads, None: numba's own count), or ``workers // threads``
    local worker processes of ``threads`` threads each, the last tasks taking up the cores of
    those that ended where the kernels over threads of the runs ``configs`` are compiled already
    (one compiled in mid-task would cost more than the cores give). ``starting()`` is called
    as the tasks start: once they are submitted to the worker processes or to Ray, which then
    start without waiting for it (it may import numba here, as the tail's check does). Tasks
    ``on_device`` step on a device, so the tail's cores are not shared among them."""
    if backend == "ray":
        backends.run_ray(run_task, tasks, finished, address, threads or 1, started=starting)
    elif in_this_process(backend, workers):
        starting()
        with compiled.with_threads(threads):
            backends.run_inline(run_task, tasks, finished)
    else:

        def share_tail() -> bool:
            starting()
            return not on_device and not any(uncached(run_kernels(config, workers)) for config in configs)

        backends.run_processes(
            run_task, tasks, finished, workers // (threads or 1), threads or 1, share_tail=share_tail
        )


def _threads_for(
    configs: Sequence[RunConfig],
    todo: Sequence[tuple[int, str, int]],
    workers: int,
    backend: str,
    threads: int | None,
    on_device: bool = False,
) -> int | None:
    """The threads per worker: ``threads`` where given; None for one local worker (numba's own
    count in this process); one for tasks ``on_device`` (their steps run there, not on the
    threads the declared costs count); else :func:`choose_threads`, said where it is more than
    one."""
    if threads is not None or in_this_process(backend, workers) or not todo:
        return threads
    if on_device:
        return 1
    threads, seconds, one_each = choose_threads(configs, todo, workers)
    if threads > 1:
        processes = workers // threads
        pool = (
            f"{processes} workers of {threads} threads each"
            if processes > 1
            else f"1 worker of {threads} threads"
        )
        tqdm.write(
            f"{pool}: by the declared costs the tasks take about {duration(seconds)}, against "
            f"{duration(one_each)} on {workers} workers of one thread",
            file=sys.stderr,
        )
    return threads


#: A run slower than its estimate by this factor says so at its end (from this many seconds).
SLOW_FACTOR, SLOW_RUN_MIN_SECONDS = 2.0, 30.0


def _say_if_slow(wall: float, estimate: float) -> None:
    """Says, at a run's end, that it took more than :data:`SLOW_FACTOR` times its estimate."""
    if wall >= SLOW_RUN_MIN_SECONDS and wall > SLOW_FACTOR * estimate:
        tqdm.write(
            f"mimo-radar-bench: the tasks took {duration(wall)}, more than {SLOW_FACTOR:g} times their "
            f"estimate of {duration(estimate)} {estimated_where()}: allow for that in --max-hours",
            file=sys.stderr,
        )


def device_agents() -> list[str]:
    """The registered agents that act on a device's tensors (``Needs.device``)."""
    return [name for name in agents.available_agents() if agents.agent_class(name).needs.device]


#: How the device check's messages name the numpy path, in words both the API and the command
#: line read (the API's None is no flag).
_NO_DEVICE = (
    ("must be None, 'cpu', 'cuda' or 'cuda:N'", "must be 'cpu', 'cuda' or 'cuda:N', or no `device`"),
    ("device=None", "no `device`"),
    (" or None", " or no `device`"),
)


def check_device(device: Any) -> None:
    """Refuse a ``device`` torch does not have, or any device without torch, with a
    :class:`HarnessError` naming the argument."""
    from mimo_radar_env.core.arrays import device_namespace

    try:
        device_namespace(device)
    except ValueError as exc:
        message = str(exc).replace("device", "`device`", 1)
        for python, either in _NO_DEVICE:  # None is the API's; the command line leaves it out
            message = message.replace(python, either)
        raise HarnessError(message) from None


def _checked_runs(runs: Any) -> tuple[list[RunConfig], list[Path]]:
    """The configurations and folders of ``runs``; a ``TypeError`` where they are not
    (RunConfig, folder) pairs, before a folder is made."""
    if not isinstance(runs, Sequence) or not all(isinstance(p, tuple | list) and len(p) == 2 for p in runs):
        raise TypeError("runs must be a list of (RunConfig, folder) pairs")
    for config, out in runs:
        if not isinstance(config, RunConfig):
            raise TypeError(
                f"a run's config must be a RunConfig (make_config builds one), got {type(config).__name__}"
            )
        if not isinstance(out, str | os.PathLike):
            raise TypeError(f"a run's out must be a folder's path, got {type(out).__name__}")
    return [config for config, _ in runs], [_folder_path(out) for _, out in runs]


def _check_execution(
    backend: str,
    workers: int,
    address: str | None,
    folders: list[Path],
    device: Any = None,
    configs: Sequence[RunConfig] = (),
    threads: int | None = None,
    device_mode: str = "eager",
) -> None:
    """Refuses an unknown backend, a worker count that is not a whole number >= 1, threads that
    are not a whole number from 1 to the workers, an
    unreachable Ray address, two runs into one folder, and a device that is not there, with
    another backend than the local one, or with a policy of ``configs`` that acts on numpy only, and
    a form of the step (``device_mode``) that is unknown or without a device."""
    if backend not in ("local", "ray"):
        raise HarnessError(f"`backend` must be 'local' or 'ray', got {backend!r}")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise HarnessError(f"`workers` must be an integer >= 1, got {workers!r}")
    if threads is not None and (
        isinstance(threads, bool) or not isinstance(threads, int) or not 1 <= threads <= workers
    ):
        raise HarnessError(f"`threads` must be an integer from 1 to `workers` ({workers}), got {threads!r}")
    try:
        check_device_mode(device_mode, device)
    except ValueError as exc:
        raise HarnessError(
            str(exc).replace("device_mode", "`device_mode`", 1).replace("a device", "a `device`")
        ) from None
    if device is not None:
        if backend != "local":
            raise HarnessError(
                f"`device` {device!r} runs on the local backend: the tasks in this process, or in "
                f"`workers` processes sharing the device (got backend={backend!r})"
            )
        check_device(device)
        numpy_only = sorted(
            {
                p
                for c in configs
                for p in c.policies
                if not agents.agent_class(agents.split_policy(p)[0]).needs.device
            }
        )
        if numpy_only:
            raise HarnessError(
                f"`device` {device!r}: {', '.join(numpy_only)} act(s) on numpy arrays only; run them without "
                f"`device` (those that run on a device: {', '.join(device_agents())})"
            )
    if backend == "ray":
        try:
            backends.check_ray_address(address)
        except ValueError as exc:
            raise HarnessError(str(exc)) from exc
    if len({f.resolve() for f in folders}) != len(folders):
        raise HarnessError(f"two runs write into one folder: {[str(f) for f in folders]}")


def _queue(
    configs: list[RunConfig], folders: list[Path], max_tasks: int | None, held: _Held
) -> tuple[list[tuple[int, str, int]], float]:
    """The (run, policy, shard) tasks not yet saved, each run's longest first
    (:func:`longest_first`), run after run; the first ``max_tasks`` of them; and the sum of their
    estimated seconds. The shards already saved are checked, and ``held`` where it has room."""
    todo: list[tuple[int, str, int]] = []
    costs: dict[int, dict[tuple[str, int], float]] = {}
    for number, (config, out) in enumerate(zip(configs, folders, strict=True)):
        tasks = _tasks_to_run(out, config, tqdm.write, functools.partial(held.add, number))
        costs[number] = task_seconds(config) if tasks else {}
        todo += [(number, policy, shard) for policy, shard in longest_first(config, tasks, costs[number])]
    todo = todo if max_tasks is None else todo[:max_tasks]
    return todo, sum(costs[number][policy, shard] for number, policy, shard in todo)


def _progress_bar(
    configs: list[RunConfig],
    todo: list[tuple[int, str, int]],
    steps_of: list[dict[tuple[str, int], int]],
    progress: bool,
) -> tqdm:
    """The runs' progress in trial-steps, from what is already saved."""
    total = sum(sum(steps.values()) for steps in steps_of)
    bar = tqdm(
        total=total,
        initial=total - sum(steps_of[n][p, s] for n, p, s in todo),
        unit="trial-step",
        disable=not progress,
        smoothing=0.1,
        desc=configs[0].scenario["name"] if len(configs) == 1 else f"{len(configs)} runs",
    )
    return bar


def _say_compiling(
    bar: tqdm, configs: list[RunConfig], todo: list[tuple[int, str, int]], threads: int | None
) -> None:
    """Says on the progress bar when the tasks will compile numba kernels first."""
    if any(uncached(run_kernels(configs[n], threads)) for n in {n for n, _, _ in todo}):
        bar.set_postfix_str("compiling numba kernels (first run only; or once: mimo-radar-bench compile)")


def _read(out: Path, config: RunConfig, policy: str, shard: int) -> dict[str, NDArray]:
    path = shard_path(out, policy, shard)
    if not path.exists():
        raise HarnessError(f"shard {shard} of {policy!r} is missing in {out}; run again to complete it")
    try:
        return read_shard(path, config.shard_trials(policy, shard), config_hash(config.to_json(), policy))
    except ValueError as exc:
        raise HarnessError(f"shard {path} is not valid ({exc}); run again to recompute it") from exc


def load_per_trial(
    out: Path,
    config: RunConfig,
    held: Mapping[tuple[str, int], Mapping[str, NDArray]] | None = None,
    joined: Mapping[str, dict[str, NDArray]] | None = None,
) -> dict[str, dict[str, NDArray]]:
    """Every policy's shard fields joined (:func:`join_policy`); a policy in ``joined`` (joined
    already by the caller) is taken from there."""
    joined = joined or {}
    return {
        policy: joined[policy] if policy in joined else join_policy(out, config, policy, held)
        for policy in config.policies
    }


def join_policy(
    out: Path,
    config: RunConfig,
    policy: str,
    held: Mapping[tuple[str, int], Mapping[str, NDArray]] | None = None,
) -> dict[str, NDArray]:
    """One policy's shard fields joined in trial order: the per-trial arrays concatenated
    (trials first), the selection counts and compute times summed over shards (in shard
    order, so every backend gives the same numbers). A shard in ``held`` (its data, checked or
    written by the caller) is taken from there, the others read from ``out``."""
    held = held or {}
    parts = [
        held[policy, shard] if (policy, shard) in held else _read(Path(out), config, policy, shard)
        for shard in range(config.shards_of(policy))
    ]
    joined = {key: np.concatenate([part[key] for part in parts]) for key in TRIAL_FIELDS}
    for key in ("selections", "wall_s", "tracker_repairs"):
        joined[key] = functools.reduce(np.add, (part[key] for part in parts))
    joined[TRUTH_FIELD] = parts[0][TRUTH_FIELD]  # trial 0's truth, the same for every policy
    return joined
