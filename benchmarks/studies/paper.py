"""``run`` (any scenario, any policies) and ``paper`` (the paper's six policies on a paper
scenario): one run each, printing its table."""

from __future__ import annotations

import argparse
from collections.abc import Hashable

from mimo_radar_env import env_version

from ..harness import PAPER_POLICIES
from .base import Finished, Run, Study


class _OneRun(Study):
    def report(self, finished: dict[Hashable, Finished], judged: object) -> str:
        (one,) = finished.values()
        return (one.folder / "table.md").read_text()


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
        policies = tuple(p.strip() for p in self.args.policies.split(",") if p.strip())
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
