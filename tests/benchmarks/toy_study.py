"""A study defined in one module, as a user would write one: it adds ``toy`` to the command
line's registry (``mimo-radar-bench --import tests.benchmarks.toy_study toy``). It runs Best and a
random policy on two paper scenarios and judges "Best's regret is below the random policy's"
on each."""

from __future__ import annotations

import argparse
import json

from benchmarks import verdicts
from benchmarks.cli import register_command
from benchmarks.report import paired_difference
from benchmarks.study import Run, Study


class ToyStudy(Study):
    name = "toy"
    default_trials = 6

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("--scenarios", default="paper-1-v1,paper-3-v1", help="scenarios to run")

    def runs(self) -> list[Run]:
        names = self.args.scenarios.split(",")
        return [Run(n, n, ("best", "random"), self.settings.out / n) for n in names]

    def judge(self, finished):
        out = {}
        for name, run in finished.items():
            difference = paired_difference(run.summary, "best", "random", "final_regret")
            ci = list(difference["ci"])
            out[name] = {"estimate": difference["estimate"], "ci": ci, "verdict": verdicts.verdict(ci, -1)}
        return out

    def report(self, finished, judged) -> str:
        (self.settings.out / "toy.json").write_text(json.dumps(judged))
        return "\n".join(
            f"{name}: best - random regret {j['estimate']:.1f} {j['verdict']}" for name, j in judged.items()
        )


register_command("toy", f"{__name__}:ToyStudy", "a test-only study: Best against random")
