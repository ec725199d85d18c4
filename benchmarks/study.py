"""The study engine: commands, studies, and the one loop that runs a study's runs.

A :class:`Study` is a :class:`~benchmarks.cli.Command` (a subcommand of ``mimo-radar-bench``,
listed in :data:`benchmarks.cli.COMMANDS`) that runs Monte-Carlo runs and judges or reports
them:

1. :meth:`Study.runs` lists its runs (scenario x policies x options -> folder);
2. :func:`configure` validates every run before anything is written (a bad policy, parameter or
   option fails here with one :class:`~benchmarks.errors.BenchError`);
3. :func:`execute` runs them all resumably on one set of workers, each into its folder, and
   writes a run's outputs (summary.json, curves.csv, table.md, figures) once its tasks are done;
4. :meth:`Study.judge` turns the finished runs into results (verdicts, targets), and
   :meth:`Study.report` into the text the command prints (and the files it writes).

Every study shares one :class:`~benchmarks.settings.Settings`.
"""

from __future__ import annotations

import argparse
import datetime
import importlib
import json
import os
import platform
import sys
import threading
import time
from collections.abc import Callable, Hashable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from mimo_radar_env import EnvOptions, Scenario

from . import harness
from .cli import Command
from .settings import DEFAULT_TRIALS, Settings, add_agent_param, add_run_arguments, scenario_for_version
from .uncertainty import MIN_INTERVAL_TRIALS


@dataclass(frozen=True)
class Run:
    """One run of a study: a scenario, its policies and options, into a folder.

    ``key`` names the run among the study's (e.g. ``(scenario, fusion)``); ``options`` None
    takes the settings' options; ``agent_params`` None takes the settings'.
    """

    key: Hashable
    scenario: str | Path | Scenario
    policies: tuple[str, ...]
    folder: Path
    options: EnvOptions | None = None
    agent_params: dict[str, dict[str, Any]] | None = None


@dataclass
class Finished:
    """A run whose outputs are written: its configuration, folder and summary.json, and where
    the study keeps them (``execute(..., keep_metrics=True)``) the policies'
    :class:`~benchmarks.metrics.TrialMetrics` its report was computed from."""

    run: Run
    config: harness.RunConfig
    summary: dict[str, Any] = field(repr=False)
    metrics: dict[str, Any] | None = field(default=None, repr=False, compare=False)

    @property
    def folder(self) -> Path:
        return self.run.folder


def configure(runs: Sequence[Run], settings: Settings) -> list[harness.RunConfig]:
    """Every run's configuration, validated; nothing is written (a bad run fails the study
    before its first run starts)."""
    keys = [run.key for run in runs]
    if len(set(keys)) != len(keys):
        raise harness.HarnessError(f"a study lists a run twice: {keys}")
    for run in runs:
        scenario_for_version(run.scenario, settings.env_version)
    return [
        harness.make_config(
            run.scenario,
            list(run.policies),
            settings.trials,
            settings.steps,
            settings.seed,
            # without --shard-size, a run being resumed keeps its own (it may have had other workers);
            # on a device, a policy's trials are one batch
            settings.shard_size
            or harness.recorded_shard_size(run.folder, run.policies)
            or (settings.trials if settings.device is not None else None),
            settings.agent_params if run.agent_params is None else run.agent_params,
            options=run.options or settings.options,
            # tasks at once on this machine (a Ray task runs on a node: one at a time is checked)
            workers=settings.workers if settings.backend == "local" else 1,
            say=lambda message: print(f"mimo-radar-bench: {message}", file=sys.stderr),
            # the time estimate is the CPU's (the agents' declared costs): not a device's
            max_hours=settings.max_hours if settings.device is None else None,
            parallel=settings.workers,
        )
        for run in runs
    ]


#: What a judge reads of one policy alone, computed as soon as that policy's tasks are saved:
#: ``prepare(config, policy, metrics)`` (:meth:`Study.prepare_policy`).
Prepare = Callable[[harness.RunConfig, str, Any], None]


def load_statistics() -> None:
    """What a study's intervals import (scipy's statistics), loaded in a thread of its own."""
    importlib.import_module("scipy.stats")


def execute(
    runs: Sequence[Run], settings: Settings, keep_metrics: bool = False, prepare: Prepare | None = None
) -> dict[Hashable, Finished]:
    """Configure every run, then run them all (resumably) on one set of workers
    (:func:`~benchmarks.harness.run_many`), each into its folder, writing a run's outputs as
    soon as its last task is saved, while the workers go on with the next run's tasks.
    ``keep_metrics`` keeps each run's per-trial metrics in memory (:attr:`Finished.metrics`), for
    a judge that reads them all: it need not read the shards again. ``prepare`` is called with
    each policy's metrics as soon as its last task is saved."""
    configs = configure(runs, settings)
    from . import report, uncertainty

    # scipy's statistics, which the first interval needs, load in this process while the workers
    # start on the tasks rather than before the first task or after the last; every interval
    # waits for them, and so do tasks run in this process: they hold BLAS to one thread
    # (backends.one_blas_thread) through threadpoolctl, which walks the loaded libraries under
    # the dynamic loader's lock and, beside this thread loading one of scipy's while it holds
    # the GIL, would wait for it forever (the intervals of a policy whose tasks ended first hung
    # a run so)
    loading = threading.Thread(target=load_statistics, daemon=True, name="load-statistics")
    loading.start()
    if harness.in_this_process(settings.backend, settings.workers):
        loading.join()

    written: dict[int, Finished] = {}
    # each policy's metrics and intervals, computed as soon as its last shard is saved (while the
    # workers run the other tasks), not all after the run's last task
    early: dict[int, dict[str, tuple[Any, dict[str, Any]]]] = {}

    def policy_done(number: int, policy: str, joined: dict[str, Any]) -> None:
        loading.join()
        metrics = report.policy_metrics(configs[number], joined)
        early.setdefault(number, {})[policy] = (
            metrics,
            uncertainty.policy_estimates(metrics, configs[number].seed),
        )
        if prepare is not None:
            prepare(configs[number], policy, metrics)

    def write(number: int, per_trial: dict[str, dict[str, Any]]) -> None:
        loading.join()
        run, config = runs[number], configs[number]
        given = early.pop(number, {})
        metrics = {
            p: given[p][0] if p in given else report.policy_metrics(config, per_trial[p])
            for p in config.policies
        }
        summary = report.write_outputs(
            config,
            per_trial,
            run.folder,
            figures=settings.figures,
            pairs=settings.pairs,
            metrics=metrics,
            estimated={p: estimates for p, (_, estimates) in given.items()},
        )
        written[number] = Finished(run, config, summary, metrics if keep_metrics else None)

    harness.run_many(
        [(config, run.folder) for run, config in zip(runs, configs, strict=True)],
        progress=settings.progress,
        on_complete=write,
        on_policy=policy_done,
        **settings.execution(),
    )
    return {run.key: written[number] for number, run in enumerate(runs)}


class Study(Command):
    """A command that runs Monte-Carlo runs, then judges and reports them.

    Subclasses declare their own arguments in :meth:`add_study_arguments` (the shared ones
    are added for them), list their runs in :meth:`runs`, and write what they found in
    :meth:`report` (with :meth:`judge` where they judge statements).
    """

    when_stopped: ClassVar[str | None] = (
        "every task finished is kept in its run's folder: run the same command again to resume"
    )
    #: The default of ``--trials``.
    default_trials: ClassVar[int] = DEFAULT_TRIALS
    #: Whether agent parameters start from the env version's paper study.
    paper_study: ClassVar[bool] = False
    #: The fewest trials the study accepts: those of a 95 % interval, which every study judges
    #: (a run of policies, which reports estimates alone on fewer, takes 1).
    min_trials: ClassVar[int] = MIN_INTERVAL_TRIALS
    #: Whether :meth:`judge` reads the runs' per-trial metrics (:attr:`Finished.metrics`).
    keeps_metrics: ClassVar[bool] = False

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args)
        self.settings = Settings.from_args(args, paper_study=self.paper_study)

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        if cls.default_trials < cls.min_trials:
            raise TypeError(
                f"{cls.__name__}.default_trials {cls.default_trials} is below its min_trials {cls.min_trials}"
            )
        cls.add_study_arguments(parser)
        add_agent_param(parser, paper_study=cls.paper_study)
        add_run_arguments(parser, trials=cls.default_trials, min_trials=cls.min_trials)

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """The study's own arguments."""

    def runs(self) -> list[Run]:
        """The study's runs."""
        raise NotImplementedError

    def judge(self, finished: dict[Hashable, Finished]) -> Any:
        """Results judged on the finished runs (None: the study only reports)."""
        return None

    def prepare_policy(self, config: harness.RunConfig, policy: str, metrics: Any) -> None:
        """What :meth:`judge` reads of ``policy`` alone in the run of ``config``, computed from its
        :class:`~benchmarks.metrics.TrialMetrics` as soon as its tasks are saved, while the
        workers run the others (default: nothing)."""

    def report(self, finished: dict[Hashable, Finished], judged: Any) -> str:
        """Write the study's own outputs; the text the command prints."""
        raise NotImplementedError

    def main(self) -> int:
        start = time.perf_counter()
        load_before = machine()
        finished = execute(
            self.runs(), self.settings, keep_metrics=self.keeps_metrics, prepare=self.prepare_policy
        )
        text = self.report(finished, self.judge(finished))
        write_timing(self.settings.out, self.name, time.perf_counter() - start, load_before)
        print(text)
        return 0


TIMING_FILE = "timing.json"


def machine() -> dict[str, Any]:
    """What the timings were measured on: the platform, cores, Python and the load average, and
    where the system tells them (Linux), the processor, its physical cores (``cores`` counts
    hardware threads: two per core where SMT is on), the cores this process may run on and its
    cgroup's CPU quota in cores (None: no quota)."""
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "load_average_1min": round(os.getloadavg()[0], 2),
        **_processor(),
    }


def _processor(cpuinfo: str = "/proc/cpuinfo", quota: str = "/sys/fs/cgroup/cpu.max") -> dict[str, Any]:
    try:
        entries = [dict(_fields(block)) for block in Path(cpuinfo).read_text().split("\n\n") if block.strip()]
    except OSError:
        return {}
    cores = {(e.get("physical id", "0"), e["core id"]) for e in entries if "core id" in e}
    try:
        limit, period = Path(quota).read_text().split()
        quota_cores = None if limit == "max" else round(int(limit) / int(period), 2)
    except (OSError, ValueError):
        quota_cores = None
    return {
        "processor": entries[0].get("model name") if entries else None,
        "physical_cores": len(cores) or None,
        "usable_cores": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "cpu_quota_cores": quota_cores,
    }


def _fields(block: str) -> Iterator[tuple[str, str]]:
    for line in block.splitlines():
        key, colon, value = line.partition(":")
        if colon:
            yield key.strip(), value.strip()


def write_timing(
    out: Path, study: str, wall_s: float, before: dict[str, Any], parts: dict[str, float] | None = None
) -> Path:
    """``out/timing.json``: the study's wall time in this invocation (a resumed study counts only
    what it ran), the command and the machine, with its load before and after."""
    after = machine()
    record = {
        "study": study,
        "command": ["mimo-radar-bench", *sys.argv[1:]] if sys.argv else [],
        "wall_s": round(wall_s, 3),
        **({"parts_s": {k: round(v, 3) for k, v in parts.items()}} if parts else {}),
        "finished": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "machine": {**before, "load_average_1min_after": after["load_average_1min"]},
    }
    path = Path(out) / TIMING_FILE
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=2))
    return path
