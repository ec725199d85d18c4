"""The RL study: learned policies from several training seeds, beside the bandits and oracles.

``mimo-radar-bench rl --out DIR`` trains, on each v1 paper scenario (one pool of worker
processes, resumably: a finished seed is kept):

* PPO under both rewards (eq17's SINR sum, ``sinr``, and the tracker's information gain,
  ``information``), :data:`PPO_SEEDS` seeds each;
* MaskablePPO and RecurrentPPO (sb3-contrib) under the information reward,
  :data:`CONTRIB_SEEDS` seeds each;

into ``DIR/train/<scenario>/<learner>-<reward>/seed-S``, each through the native vector env.
Then it runs every trained seed beside MG-CRB-CL, best-tracking and tracking-ucb on the same
trials (one harness run per scenario, ``DIR/<scenario>``, resumable) and reports, in
``DIR/rl.md`` and ``DIR/rl.json``:

* each learner's ARMSE and final SINR regret across its seeds: the mean and the interquartile
  mean with 95 % bootstrap intervals over seeds (:func:`benchmarks.uncertainty.across_seeds`,
  rliable's statistics), beside the bandits' with their intervals over trials;
* each learner against best-tracking, tracking-ucb and MG-CRB-CL: the ARMSE difference paired on
  the same trials, averaged over seeds, with its interval over seeds;
* over the three scenarios, the IQM of each learner's ARMSE as a ratio to best-tracking's
  (stratified bootstrap: seeds resampled within each scenario);
* the learning curves (``DIR/curves_<scenario>.png``: return and ARMSE of the training
  episodes against timesteps, the mean over seeds and the seeds' range) and whether each has
  flattened: the relative change of the mean ARMSE between the last two fifths of training,
  within :data:`FLAT_CHANGE`.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
from collections.abc import Hashable
from pathlib import Path
from typing import Any

import numpy as np

from mimo_radar_env import env_version, load_scenario

from ..errors import BenchError
from ..report import format_estimate, paired_difference
from ..settings import Settings, add_scenarios_argument, integer, local_workers, paper_numbers
from ..study import Finished, Run, Study
from ..uncertainty import across_seeds

#: (learner, reward, seeds option) of the study's trainings.
TRAININGS = (
    ("ppo", "sinr", "ppo_seeds"),
    ("ppo", "information", "ppo_seeds"),
    ("maskable-ppo", "information", "contrib_seeds"),
    ("recurrent-ppo", "information", "contrib_seeds"),
)
#: With ``--device``: the project's own PPO on that device, under both rewards.
DEVICE_TRAININGS = (("torch-ppo", "sinr", "ppo_seeds"), ("torch-ppo", "information", "ppo_seeds"))
PPO_SEEDS = 5
#: Seeds per learner with ``--device``: at 3-5 seeds the percentile bootstrap over seeds covers
#: only about 71-84 % (:func:`benchmarks.uncertainty.seed_coverage`, docs/results-rl.md); at 10
#: it covers closer to its 95 %.
DEVICE_PPO_SEEDS = 10
CONTRIB_SEEDS = 3
#: Timesteps per training: the whole study (48 trainings and their evaluation) fits in about
#: two hours of a 2-core machine (docs/results-rl.md states the wall time measured).
DEFAULT_TIMESTEPS = 600_000
#: With ``--device``, the ``device`` hyperparameter entry (4,096 trials at once) and a budget of
#: two 1,000-step episodes per trial (600,000 steps would play 146 steps of each).
DEVICE_HYPERPARAMS_KEY = "device"
DEVICE_TIMESTEPS = 8_192_000
#: The policies every learned one is compared with, on the same trials.
COMPARED = ("mg-crb-cl", "best-tracking", "tracking-ucb")
#: The order of the paired-difference columns of the tables.
MINUS_ORDER = ("best-tracking", "tracking-ucb", "mg-crb-cl")
DEFAULT_TRIALS = 100
#: A learning curve has flattened when its mean ARMSE changes by at most this fraction between
#: the last two fifths of training.
FLAT_CHANGE = 0.02
RESULTS_FILE = "rl.json"


def training_folder(out: str | Path, scenario: str, algo: str, reward: str) -> Path:
    return Path(out) / "train" / scenario / f"{algo}-{reward}"


def learned_policy(out: str | Path, scenario: str, algo: str, reward: str, seed: int) -> str:
    """The harness policy of one trained seed: ``ALGO:PATH/model.zip`` (torch-ppo's ``model.pt``)."""
    from agents.ppo import MODEL_FILE, TORCH_PPO, WEIGHTS_FILE

    from ..training import seed_folder

    file = WEIGHTS_FILE if algo == TORCH_PPO else MODEL_FILE
    return f"{algo}:{seed_folder(training_folder(out, scenario, algo, reward), seed) / file}"


class RLStudy(Study):
    name = "rl"
    min_trials = 2
    default_trials = DEFAULT_TRIALS
    paper_study = True
    description = (
        "Train PPO (both rewards), MaskablePPO and RecurrentPPO (information reward) on the v1 paper "
        "scenarios over several seeds (OUT/train, resumable), run every seed beside MG-CRB-CL, "
        "best-tracking and tracking-ucb on the same trials (OUT/<scenario>), and report across-seed "
        "statistics and learning curves (OUT/rl.md, OUT/rl.json, OUT/curves_<scenario>.png). With "
        "--device, the learner is the project's own torch-ppo (both rewards, 10 seeds by default), "
        "trained on that device one seed after another; the evaluation runs on numpy with --workers."
    )

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        add_scenarios_argument(parser)
        parser.add_argument(
            "--timesteps",
            type=integer(1, high=10**10),
            default=None,
            help=f"environment steps per training (default {DEFAULT_TIMESTEPS:,}; with --device "
            f"{DEVICE_TIMESTEPS:,}, two episodes of each of the device entry's 4,096 trials)",
        )
        parser.add_argument(
            "--ppo-seeds",
            type=integer(1, high=100),
            default=None,
            help=f"training seeds of PPO, per reward (default {PPO_SEEDS}; with --device {DEVICE_PPO_SEEDS})",
        )
        parser.add_argument(
            "--n-envs",
            type=integer(1, high=1 << 20),
            default=None,
            help="parallel trials of each training env (default: the hyperparameter entry's: 8, or "
            "with --device 4,096)",
        )
        parser.add_argument(
            "--contrib-seeds",
            type=integer(1, high=100),
            default=CONTRIB_SEEDS,
            help=f"training seeds of MaskablePPO and RecurrentPPO (default {CONTRIB_SEEDS})",
        )

    @property
    def on_device(self) -> bool:
        return self.settings.device is not None

    def learners(self) -> tuple[tuple[str, str, str], ...]:
        """``(learner, reward, seeds option)`` of the study's trainings: the SB3 learners, or
        torch-ppo with ``--device``."""
        return DEVICE_TRAININGS if self.on_device else TRAININGS

    @property
    def timesteps(self) -> int:
        given = self.args.timesteps
        return given if given is not None else DEVICE_TIMESTEPS if self.on_device else DEFAULT_TIMESTEPS

    def seeds(self, option: str) -> int:
        """The seeds of a seeds option; ``--ppo-seeds`` defaults by where the study trains."""
        given = getattr(self.args, option)
        if given is not None:
            return given
        return DEVICE_PPO_SEEDS if self.on_device else PPO_SEEDS

    def trainings(self) -> list[tuple[str, str, str, int]]:
        """``(scenario, learner, reward, seeds)`` of every training group."""
        version = env_version(self.settings.env_version)
        return [
            (version.paper_scenario(number), algo, reward, self.seeds(seeds))
            for number in paper_numbers(self.args.scenarios)
            for algo, reward, seeds in self.learners()
        ]

    def runs(self) -> list[Run]:
        runs = []
        for number in paper_numbers(self.args.scenarios):
            scenario = env_version(self.settings.env_version).paper_scenario(number)
            learned = [
                learned_policy(self.settings.out, scenario, algo, reward, seed)
                for name, algo, reward, seeds in self.trainings()
                if name == scenario
                for seed in range(seeds)
            ]
            runs.append(Run(number, scenario, (*COMPARED, *learned), Path(self.settings.out) / scenario))
        return runs

    def train(self) -> None:
        """Every training of the study, resumably, ``--workers`` at once."""
        from ..harness import RunInterrupted
        from ..training import train_jobs, training_job

        tasks = []
        key = DEVICE_HYPERPARAMS_KEY if self.on_device else None
        for scenario, algo, reward, seeds in self.trainings():
            options = dataclasses.replace(self.settings.options, reward=reward)
            job = training_job(load_scenario(scenario), self.timesteps, algo, options, hyperparams_key=key)
            if self.args.n_envs is not None:
                job["n_envs"] = self.args.n_envs
            folder = training_folder(self.settings.out, scenario, algo, reward)
            tasks += [(job, folder, seed) for seed in range(seeds)]
        try:
            train_jobs(
                tasks, self.settings.workers, progress=self.settings.progress, device=self.settings.device
            )
        except RunInterrupted:
            raise
        except ValueError as exc:
            raise BenchError(str(exc)) from exc

    def estimate_training_seconds(self) -> float:
        """The wall time of the trainings still to do (a resumed study keeps its finished
        seeds), roughly: :func:`benchmarks.training.estimate_training_seconds` each, ``--workers``
        at once."""
        from ..training import META_FILE, estimate_training_seconds, seed_folder

        seconds = 0.0
        for scenario, algo, reward, seeds in self.trainings():
            folder = training_folder(self.settings.out, scenario, algo, reward)
            for seed in range(seeds):
                meta = seed_folder(folder, seed) / META_FILE
                if not (meta.is_file() and "job" in json.loads(meta.read_text())):
                    seconds += estimate_training_seconds(algo, self.timesteps, self.settings.device)
        return seconds if self.on_device else seconds / self.settings.workers

    def evaluation_settings(self) -> Settings:
        """The evaluation's settings: with ``--device``, numpy in local worker processes (every
        evaluated policy acts on numpy too, and a hundred trials launch-bind a device)."""
        if not self.on_device:
            return self.settings
        return dataclasses.replace(
            self.settings, device=None, device_mode="eager", workers=local_workers(self.args.workers)
        )

    def main(self) -> int:
        import sys
        import time

        from ..harness import HarnessError, duration
        from ..study import configure, execute, machine, write_timing

        start, load_before = time.perf_counter(), machine()
        if self.settings.backend != "local":
            raise BenchError("the RL study trains in local worker processes: use --backend local")
        # everything but the models is checked before hours of training
        configure(
            [dataclasses.replace(run, policies=COMPARED) for run in self.runs()], self.evaluation_settings()
        )
        seconds = self.estimate_training_seconds()
        if self.settings.max_hours is not None and seconds > 3600 * self.settings.max_hours:
            raise HarnessError(
                f"the study's trainings would take about {duration(seconds)}, more than --max-hours "
                f"{self.settings.max_hours:g}: use fewer --timesteps or seeds, or a larger --max-hours"
            )
        print(
            f"mimo-radar-bench: the trainings still to do take about {duration(seconds)} (finished kept)",
            file=sys.stderr,
        )
        self.train()
        trained = time.perf_counter()
        finished = execute(self.runs(), self.evaluation_settings())
        evaluated = time.perf_counter()
        text = self.report(finished, self.judge(finished))
        # the whole study in this invocation, training included (a resumed study counts what it ran)
        parts = {"training": trained - start, "evaluation": evaluated - trained}
        write_timing(self.settings.out, self.name, time.perf_counter() - start, load_before, parts)
        print(text)
        return 0

    def judge(self, finished: dict[Hashable, Finished]) -> dict[str, Any]:
        return judge_learners(
            {number: f.summary for number, f in finished.items()},
            [(algo, reward) for algo, reward, _ in self.learners()],
        )

    def report(self, finished: dict[Hashable, Finished], judged: dict[str, Any]) -> str:
        out = Path(self.settings.out)
        curves = {}
        for number, f in finished.items():
            scenario = f.run.scenario
            curves[number] = {
                f"{algo}-{reward}": read_curves(training_folder(out, str(scenario), algo, reward))
                for algo, reward, _ in self.learners()
            }
        judged["curves"] = {
            str(number): {key: flattened(curve) for key, curve in group.items()}
            for number, group in curves.items()
        }
        judged["training_worker_s"] = training_seconds(out)
        (out / RESULTS_FILE).write_text(json.dumps(judged, indent=1, default=float) + "\n")
        text = rl_markdown(judged)
        (out / "rl.md").write_text(text)
        if self.settings.figures:
            from ..plots import plot_learning_curves

            for number, group in curves.items():
                plot_learning_curves(group, out / f"curves_paper-{number}.png", f"paper-{number}")
        return text


def learner_policies(rows: dict[str, Any], algo: str, reward: str) -> list[str]:
    return sorted(p for p in rows if p.startswith(f"{algo}:") and f"/{algo}-{reward}/" in p)


def judge_learners(summaries: dict[Any, dict[str, Any]], learners: list[tuple[str, str]]) -> dict[str, Any]:
    """Across-seed statistics of every learner in every scenario (``{number: summary.json}``),
    their paired ARMSE differences against :data:`COMPARED`, and the IQM over scenarios of
    their ARMSE as a ratio to best-tracking's."""
    scenarios = []
    ratios: dict[str, list[np.ndarray]] = {}
    for number, summary in summaries.items():
        rows = summary["policies"]
        entry: dict[str, Any] = {
            "scenario": number,
            "trials": summary["trials"],
            "compared": {
                p: {m: {"value": rows[p][m], "ci": rows[p]["ci"][m]} for m in ("armse", "final_regret")}
                for p in COMPARED
            },
            "learners": {},
        }
        for algo, reward in learners:
            policies = learner_policies(rows, algo, reward)
            if not policies:
                continue
            armse = np.array([rows[p]["armse"] for p in policies])
            regret = np.array([rows[p]["final_regret"] for p in policies])
            key = f"{algo}-{reward}"
            entry["learners"][key] = {
                "seeds": len(policies),
                "armse_per_seed": armse.tolist(),
                "armse": {s: across_seeds([armse], s) for s in ("mean", "iqm")},
                "final_regret": {s: across_seeds([regret], s) for s in ("mean", "iqm")},
                "minus": {
                    other: across_seeds(
                        [
                            np.array(
                                [paired_difference(summary, p, other, "armse")["estimate"] for p in policies]
                            )
                        ],
                        "mean",
                    )
                    for other in COMPARED
                },
            }
            ratios.setdefault(key, []).append(armse / rows["best-tracking"]["armse"])
        scenarios.append(entry)
    return {
        "scenarios": scenarios,
        "over_scenarios": {key: across_seeds(groups, "iqm") for key, groups in ratios.items()},
    }


def training_seconds(out: Path) -> float:
    """The trainings' compute: the sum of every seed's training wall time (``ppo.json``'s
    ``train_wall_s``), whichever invocation of the study trained it."""
    from ..training import META_FILE

    metas = sorted(out.glob(f"train/*/*/seed-*/{META_FILE}"))
    return float(sum(json.loads(path.read_text())["train_wall_s"] for path in metas))


def read_curves(folder: Path) -> list[dict[str, np.ndarray]]:
    """The learning curve of every seed in ``folder`` (``seed-S/curve.csv``)."""
    from ..training import CURVE_FILE

    curves = []
    for path in sorted(folder.glob(f"seed-*/{CURVE_FILE}")):
        with path.open() as handle:
            rows = list(csv.DictReader(handle))
        curves.append({k: np.array([float(r[k]) for r in rows]) for k in ("timesteps", "return", "armse")})
    return curves


def flattened(curves: list[dict[str, np.ndarray]]) -> dict[str, Any]:
    """Whether the mean ARMSE over seeds has flattened: its relative change between the last two
    fifths of the rollouts (``None`` when the curves are too short to tell)."""
    length = min((len(c["armse"]) for c in curves), default=0)
    if length < 5:
        return {"change": None, "flat": None, "rollouts": length}
    mean = np.nanmean([c["armse"][:length] for c in curves], axis=0)
    fifth = length // 5
    last, before = np.nanmean(mean[-fifth:]), np.nanmean(mean[-2 * fifth : -fifth])
    change = float((last - before) / before)
    return {"change": change, "flat": abs(change) <= FLAT_CHANGE, "rollouts": length}


def rl_markdown(judged: dict[str, Any]) -> str:
    """The study's tables."""

    def seeds_cell(stat: dict[str, Any], fmt: str) -> str:
        return format_estimate(stat["value"], stat["ci"], fmt)

    lines = [
        "# The RL study",
        "",
        "Learned policies across their training seeds: the mean and the interquartile mean (IQM) over "
        "seeds with 95 % bootstrap intervals over seeds; the bandits and oracles with 95 % intervals over "
        "trials. Every policy ran on the same trials.",
    ]
    for entry in judged["scenarios"]:
        lines += [
            "",
            f"## paper-{entry['scenario']} ({entry['trials']} trials)",
            "",
            "| policy | seeds | ARMSE (m), mean | ARMSE (m), IQM | final regret, mean | "
            + " | ".join(f"- {other}" for other in MINUS_ORDER)
            + " |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for p, row in entry["compared"].items():
            armse = seeds_cell(row["armse"], "{:.3f}")
            regret = seeds_cell(row["final_regret"], "{:.0f}")
            lines.append(f"| `{p}` | - | {armse} | - | {regret} | - | - | - |")
        for key, row in entry["learners"].items():
            cells = [
                seeds_cell(row["armse"]["mean"], "{:.3f}"),
                seeds_cell(row["armse"]["iqm"], "{:.3f}"),
                seeds_cell(row["final_regret"]["mean"], "{:.0f}"),
                *(seeds_cell(row["minus"][other], "{:.3f}") for other in MINUS_ORDER),
            ]
            lines.append(f"| `{key}` | {row['seeds']} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "`- X`: the learner's ARMSE minus X's, paired on the same trials, averaged over seeds (interval over "
        "seeds); an interval below 0 means the learner tracks better than X.",
        "",
        "## Over the three scenarios",
        "",
        "| learner | IQM of ARMSE / best-tracking's ARMSE |",
        "|---|---|",
    ]
    for key, stat in judged["over_scenarios"].items():
        lines.append(f"| `{key}` | {seeds_cell(stat, '{:.3f}')} |")
    lines += ["", "Stratified bootstrap: each scenario's seeds resampled within it.", ""]
    if "curves" in judged:
        lines += [
            "## Learning curves",
            "",
            "| scenario | learner | change of the mean ARMSE, last two fifths | flat |",
        ]
        lines.append("|---|---|---|---|")
        for number, group in judged["curves"].items():
            for key, curve in group.items():
                change = "-" if curve["change"] is None else f"{100 * curve['change']:+.1f} %"
                flat = "-" if curve["flat"] is None else ("yes" if curve["flat"] else "no")
                lines.append(f"| paper-{number} | `{key}` | {change} | {flat} |")
    return "\n".join(lines) + "\n"
