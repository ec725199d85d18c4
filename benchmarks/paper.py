"""``run`` (any scenario, any policies) and ``paper`` (the paper's six policies on a paper
scenario): one run each, printing its table; :func:`run_policies` is ``run`` as a Python call
(``benchmarks.run``)."""

from __future__ import annotations

import argparse
import tempfile
from collections.abc import Hashable, Sequence
from pathlib import Path
from typing import Any

from agents import Agent
from mimo_radar_env import VERSIONS, EnvOptions, Scenario, env_version
from mimo_radar_env.envs.versions import check_scenario_version

from . import harness
from .harness import PAPER_POLICIES
from .settings import comma_list
from .study import Finished, Run, Study


class _OneRun(Study):
    min_trials = 1  # its table reports estimates alone on fewer trials than an interval needs

    def report(self, finished: dict[Hashable, Finished], judged: object) -> str:
        """table.md without how its intervals are computed (it is one file away), and where the
        run's files are, on the last line."""
        from .report import outputs_line, paired_markdown, table_markdown

        (one,) = finished.values()
        reference = one.config.policies[0] if self.settings.pairs == "reference" else None
        num_targets = one.config.scenario_object.num_targets
        table = table_markdown(one.summary, num_targets, intervals="short") + paired_markdown(
            one.summary, reference
        )
        return f"{table}\n{outputs_line(one.folder, self.settings.figures)}\n"


class RunStudy(_OneRun):
    name = "run"
    description = (
        "Run registered agents (ppo:PATH for a trained PPO model) on a scenario and print the table."
    )

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("--scenario", required=True, help="shipped name (paper-1...) or a YAML/TOML file")
        parser.add_argument(
            "--policies",
            required=True,
            help="comma-separated agents (see 'mimo-radar-bench agents') or ppo:PATH/model.zip",
        )

    def runs(self) -> list[Run]:
        policies = tuple(comma_list("--policies", self.args.policies))
        return [Run("run", self.args.scenario, policies, self.settings.out)]


class PaperStudy(_OneRun):
    name = "paper"
    description = (
        f"Run {', '.join(PAPER_POLICIES)} on a paper scenario with common random numbers and print the table."
    )
    paper_study = True

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument(
            "--scenario", type=int, choices=(1, 2, 3), required=True, help="paper scenario 1, 2 or 3"
        )

    def runs(self) -> list[Run]:
        scenario = env_version(self.settings.env_version).paper_scenario(self.args.scenario)
        return [Run("paper", scenario, PAPER_POLICIES, self.settings.out)]


def run_policies(
    scenario: str | Path | Scenario,
    policies: Sequence[str | type[Agent]],
    trials: int = 500,
    out: str | Path | None = None,
    steps: int | None = None,
    seed: int = 0,
    options: EnvOptions | dict[str, Any] | None = None,
    version: str = "v1",
    agent_params: dict[str, dict[str, Any]] | None = None,
    workers: int = 1,
    device: Any = None,
    progress: bool = True,
    figures: bool = False,
    device_mode: str = "eager",
) -> dict[str, Any]:
    """``mimo-radar-bench run`` as a Python call: the policies (registered names, ``module:Class``
    or :class:`agents.Agent` subclasses) on ``scenario``, on the same trials, resumably in ``out``
    (default: a new temporary folder). Returns summary.json's content: every policy's metrics
    with their 95 % intervals, the paired differences, and ``table`` (table.md's text) and
    ``out``. ``options`` is an :class:`~mimo_radar_env.EnvOptions` or a mapping over env
    ``version``'s defaults (v1's, as the command line's). ``device`` runs the tasks on torch there,
    the step in form ``device_mode`` (:func:`benchmarks.harness.run_many`)."""
    from . import report

    for flag, value in (("progress", progress), ("figures", figures)):
        if not isinstance(value, bool):
            raise harness.HarnessError(f"`{flag}` must be True or False, got {value!r}")
    # a string is refused by make_config, naming it (not read as a list of one-letter names)
    names = policies if isinstance(policies, str) else [harness.policy_name(p, workers) for p in policies]
    if not isinstance(options, EnvOptions):
        if version not in VERSIONS:
            raise harness.HarnessError(f"`version` must be one of {sorted(VERSIONS)}, got {version!r}")
        options = harness.check_options(options, version)
    try:
        check_scenario_version(scenario, version)
    except ValueError as exc:
        raise harness.HarnessError(str(exc)) from None
    shard = trials if device is not None else None
    config = harness.make_config(scenario, names, trials, steps, seed, shard, agent_params, options, workers)
    given = out if out is not None else tempfile.mkdtemp(prefix="mimo-radar-run-")  # run_many checks it
    harness.run_many([(config, given)], workers, progress=progress, device=device, device_mode=device_mode)
    folder = Path(given)
    summary = report.write_outputs(config, None, folder, figures=figures)
    return {**summary, "table": (folder / "table.md").read_text(), "out": str(folder)}
