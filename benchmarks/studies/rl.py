"""The RL study: learned policies from several training seeds, beside the bandits and oracles.

``mimo-radar-bench rl --out DIR`` trains, on each v1 paper scenario and under ``--fusion`` or
each of ``--fusions`` (one pool of worker processes, resumably: a finished seed is kept):

* PPO under both rewards (eq17's SINR sum, ``sinr``, and the tracker's information gain,
  ``information``), :data:`PPO_SEEDS` seeds each;
* MaskablePPO and RecurrentPPO (sb3-contrib) under the information reward,
  :data:`CONTRIB_SEEDS` seeds each;

into ``DIR/train/<scenario>-<fusion>/<learner>-<reward>/seed-S``, each through the native
vector env; with ``--device``, the project's own torch-ppo under both rewards and, by default,
both fusions, :data:`DEVICE_PPO_SEEDS` seeds each. Then it runs every trained seed beside
MG-CRB-CL, best-tracking and tracking-ucb on the same trials (one harness run per scenario and
fusion, ``DIR/<scenario>-<fusion>``, resumable) and reports, in
``DIR/rl.md`` and ``DIR/rl.json``:

* each learner's ARMSE and final SINR regret across its seeds: the mean and the interquartile
  mean with 95 % bootstrap intervals over seeds (:func:`benchmarks.uncertainty.across_seeds`,
  rliable's statistics), beside the bandits' with their intervals over trials;
* each learner against best-tracking, tracking-ucb and MG-CRB-CL: the ARMSE difference paired on
  the same trials, averaged over seeds, with its interval over seeds;
* per fusion, over the scenarios, the IQM of each learner's ARMSE as a ratio to best-tracking's
  (stratified bootstrap: seeds resampled within each scenario);
* the learning curves (``DIR/curves_<scenario>-<fusion>.png``: return and ARMSE of the training
  episodes against timesteps, the mean over seeds and the seeds' range) and whether each has
  flattened: the relative change of the mean ARMSE between the last two fifths of training,
  within :data:`FLAT_CHANGE`;
* with ``--sweep``, the information-reward learner at each further budget against its own seeds
  at ``--timesteps`` (:func:`judge_sweep`).
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import math
import re
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
from .tracking import FUSIONS, chosen_fusions

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
#: The fewest points (rollouts in which an episode ended) a curve needs to be judged flat or not.
MIN_CURVE_POINTS = 5
RESULTS_FILE = "rl.json"
#: The key of the budget sweep's run among the study's.
SWEEP = "sweep"


def training_folder(
    out: str | Path, scenario: str, fusion: str, algo: str, reward: str, timesteps: int | None = None
) -> Path:
    """``OUT/train/<scenario>-<fusion>/<algo>-<reward>``; a budget sweep's trainings add
    ``-<timesteps>``."""
    name = f"{algo}-{reward}" if timesteps is None else f"{algo}-{reward}-{timesteps}"
    return Path(out) / "train" / f"{scenario}-{fusion}" / name


def learned_policy(folder: Path, algo: str, seed: int) -> str:
    """The harness policy of one trained seed in a training ``folder``: ``ALGO:PATH/model.zip``
    (torch-ppo's ``model.pt``)."""
    from agents.ppo import MODEL_FILE, TORCH_PPO, WEIGHTS_FILE

    from ..training import seed_folder

    file = WEIGHTS_FILE if algo == TORCH_PPO else MODEL_FILE
    return f"{algo}:{seed_folder(folder, seed) / file}"


@dataclasses.dataclass(frozen=True)
class Training:
    """One group of trainings: a learner, its reward and budget, in one scenario and fusion,
    ``seeds`` seeds, into ``folder``."""

    number: int
    scenario: str
    fusion: str
    algo: str
    reward: str
    seeds: int
    timesteps: int
    folder: Path

    def policies(self) -> list[str]:
        return [learned_policy(self.folder, self.algo, seed) for seed in range(self.seeds)]


class RLStudy(Study):
    name = "rl"
    default_trials = DEFAULT_TRIALS
    paper_study = True
    description = (
        "Train PPO (both rewards), MaskablePPO and RecurrentPPO (information reward) on the v1 paper "
        "scenarios over several seeds (OUT/train, resumable), run every seed beside MG-CRB-CL, "
        "best-tracking and tracking-ucb on the same trials (OUT/<scenario>-<fusion>), and report across-seed "
        "statistics and learning curves (OUT/rl.md, OUT/rl.json, OUT/curves_<scenario>-<fusion>.png). "
        "With --device, the learner is the project's own torch-ppo (both rewards and both fusions, 10 "
        "seeds by default), trained on that device, --device-workers at once; the evaluation runs on "
        "numpy with --workers. --sweep trains the information learner at further budgets."
    )

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        add_scenarios_argument(parser)
        parser.add_argument(
            "--fusions",
            default=None,
            help=f"fusions to train and evaluate under, each into its own folders (default: --fusion's; "
            f"with --device {','.join(FUSIONS)})",
        )
        parser.add_argument(
            "--timesteps",
            type=integer(1, high=10**10),
            default=None,
            help=f"environment steps per training (default {DEFAULT_TIMESTEPS:,}; with --device "
            f"{DEVICE_TIMESTEPS:,}, two episodes of each of the device entry's 4,096 trials)",
        )
        parser.add_argument(
            "--sweep",
            default=None,
            metavar="BUDGETS",
            help="also train the information-reward learner at these budgets (comma-separated "
            "timesteps, e.g. 5000000,20000000), in the first scenario and fusion, and compare them with "
            "its --timesteps seeds on the same trials (OUT/sweep-<scenario>-<fusion>-<budget>)",
        )
        parser.add_argument(
            "--hyperparams-key",
            default=None,
            help=f"the entry of the learners' hyperparameter files (default: the flat env id; with "
            f"--device, {DEVICE_HYPERPARAMS_KEY!r})",
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
            "--device-workers",
            type=integer(1, high=64),
            default=None,
            help="with --device: trainings at once, each in a process of its own, sharing the device "
            "(default 1: one after another in this process; --workers sets the evaluation's)",
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

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args)
        if args.device_workers is not None and not self.on_device:
            raise BenchError(
                "--device-workers needs --device; without one, --workers sets the trainings at once"
            )

    @property
    def training_workers(self) -> int:
        """The trainings at once: ``--device-workers`` (default 1) with ``--device``, else
        ``--workers``."""
        if not self.on_device:
            return self.settings.workers
        return self.args.device_workers or 1

    @property
    def hyperparams_key(self) -> str | None:
        """The learners' hyperparameter entry: ``--hyperparams-key``, or the device entry with
        ``--device``, or (None) each learner's default."""
        return self.args.hyperparams_key or (DEVICE_HYPERPARAMS_KEY if self.on_device else None)

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

    def fusions(self) -> list[str]:
        """``--fusions``; by default the settings' fusion, or with ``--device`` every fusion."""
        if self.args.fusions is not None:
            return chosen_fusions(self, self.args.fusions)
        return list(FUSIONS) if self.on_device else [self.settings.options.fusion]

    def groups(self) -> list[tuple[int, str, str]]:
        """``(number, scenario, fusion)`` of every scenario and fusion the study runs."""
        version = env_version(self.settings.env_version)
        return [
            (number, version.paper_scenario(number), fusion)
            for number in paper_numbers(self.args.scenarios)
            for fusion in self.fusions()
        ]

    def sweep(self) -> list[int]:
        """``--sweep``'s budgets, checked (each other than ``--timesteps``, each once)."""
        if self.args.sweep is None:
            return []
        try:
            budgets = [int(b) for b in self.args.sweep.split(",")]
        except ValueError:
            budgets = []
        if not budgets or any(b < 1 for b in budgets) or len(set(budgets)) != len(budgets):
            raise BenchError(f"--sweep must list positive timesteps, each once, got {self.args.sweep!r}")
        if self.timesteps in budgets:
            raise BenchError(f"--sweep lists --timesteps ({self.timesteps}): its seeds are the study's own")
        return budgets

    def sweep_learner(self) -> tuple[str, str, str]:
        """The learner a budget sweep trains: the study's information-reward one."""
        return next(entry for entry in self.learners() if entry[1] == "information")

    def trainings(self) -> list[Training]:
        """Every training group: the study's learners in every scenario and fusion."""
        return [self.training(group, learner) for group in self.groups() for learner in self.learners()]

    def sweep_trainings(self) -> list[Training]:
        """The budget sweep's training groups: the information-reward learner at each budget of
        ``--sweep``, in the first scenario and fusion."""
        return [self.training(self.groups()[0], self.sweep_learner(), budget) for budget in self.sweep()]

    def sweep_baseline(self) -> Training:
        """The training group every sweep budget is compared with: the swept learner at
        ``--timesteps`` in the first scenario and fusion."""
        return self.training(self.groups()[0], self.sweep_learner())

    def training(
        self, group: tuple[int, str, str], learner: tuple[str, str, str], budget: int | None = None
    ) -> Training:
        """The training group of a ``(number, scenario, fusion)`` and a learner, at the study's
        ``--timesteps`` or at a sweep's ``budget``."""
        number, scenario, fusion = group
        algo, reward, option = learner
        folder = training_folder(self.settings.out, scenario, fusion, algo, reward, budget)
        timesteps = self.timesteps if budget is None else budget
        return Training(number, scenario, fusion, algo, reward, self.seeds(option), timesteps, folder)

    def runs(self) -> list[Run]:
        """One evaluation per scenario and fusion, ``OUT/<scenario>-<fusion>``; with ``--sweep``,
        one more per budget in its scenario and fusion, ``OUT/sweep-<scenario>-<fusion>-<budget>``:
        best-tracking and the swept learner at ``--timesteps`` and at that budget."""
        out = Path(self.settings.out)
        trainings = self.trainings()
        runs = []
        for number, scenario, fusion in self.groups():
            learned = [
                p for t in trainings if (t.scenario, t.fusion) == (scenario, fusion) for p in t.policies()
            ]
            options = dataclasses.replace(self.settings.options, fusion=fusion)
            folder = out / f"{scenario}-{fusion}"
            runs.append(Run((number, fusion), scenario, (*COMPARED, *learned), folder, options))
        study = self.sweep_baseline()
        for swept in self.sweep_trainings():
            # best-tracking and the study's seeds beside each budget's: a budget added later is a
            # run of its own, and every budget is paired with the study's seeds on the same trials
            policies = ("best-tracking", *study.policies(), *swept.policies())
            # the paper study's parameters of the policies it runs (MG-CRB-CL's are not among them)
            params = {p: v for p, v in self.settings.agent_params.items() if p in policies}
            options = dataclasses.replace(self.settings.options, fusion=swept.fusion)
            folder = out / f"sweep-{swept.scenario}-{swept.fusion}-{swept.timesteps}"
            runs.append(Run((SWEEP, swept.timesteps), swept.scenario, policies, folder, options, params))
        return runs

    def train(self) -> None:
        """Every training of the study, resumably, :attr:`training_workers` at once."""
        from ..harness import RunInterrupted
        from ..training import train_jobs, training_job

        tasks = []
        key = self.hyperparams_key
        for t in (*self.trainings(), *self.sweep_trainings()):
            options = dataclasses.replace(self.settings.options, reward=t.reward, fusion=t.fusion)
            job = training_job(load_scenario(t.scenario), t.timesteps, t.algo, options, hyperparams_key=key)
            if self.args.n_envs is not None:
                job["n_envs"] = self.args.n_envs
            tasks += [(job, t.folder, seed) for seed in range(t.seeds)]
        try:
            train_jobs(
                tasks,
                self.training_workers,
                progress=self.settings.progress,
                device=self.settings.device,
                device_mode=self.settings.device_mode,
            )
        except (RunInterrupted, BenchError):  # a HarnessError keeps its flags for the command line
            raise
        except ValueError as exc:
            raise BenchError(str(exc)) from exc

    def estimate_training_seconds(self) -> float:
        """The wall time of the trainings still to do (a resumed study keeps its finished
        seeds), roughly: :func:`benchmarks.training.estimate_training_seconds` each,
        :attr:`training_workers` at once."""
        from ..training import META_FILE, estimate_training_seconds, load_hyperparams, seed_folder

        seconds = 0.0
        parallel: dict[str, int] = {}  # each learner's entry read once
        for t in (*self.trainings(), *self.sweep_trainings()):
            if t.algo not in parallel:
                entry = load_hyperparams(None, self.hyperparams_key, t.algo)
                parallel[t.algo] = self.args.n_envs or entry.get("n_envs", 8)
            for seed in range(t.seeds):
                meta = seed_folder(t.folder, seed) / META_FILE
                if not (meta.is_file() and "job" in json.loads(meta.read_text())):
                    seconds += estimate_training_seconds(
                        t.algo, t.timesteps, self.settings.device, parallel[t.algo], self.training_workers
                    )
        return seconds / self.training_workers

    def training_record(self) -> dict[str, Any]:
        """How the study's learners trained, from its first training's ``ppo.json``: where
        (``device``, None for numpy), the hyperparameter entry, parallel trials and timesteps."""
        from ..training import META_FILE, seed_folder

        meta = json.loads((seed_folder(self.trainings()[0].folder, 0) / META_FILE).read_text())
        return {
            "device": meta.get("device"),
            "device_mode": meta.get("device_mode", "eager"),
            "hyperparams_key": meta["job"].get("hyperparams_key"),
            "n_envs": meta["n_envs"],
            "timesteps": meta["timesteps"],
            "trained_timesteps": meta["trained_timesteps"],
        }

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

        from ..harness import HarnessError, output_folder
        from ..resources import duration
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
        output_folder(self.settings.out)
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
        learners = [(algo, reward) for algo, reward, _ in self.learners()]
        swept = {k[1]: f for k, f in finished.items() if k[0] == SWEEP}
        judged = judge_learners({k: f.summary for k, f in finished.items() if k[0] != SWEEP}, learners)
        if swept:
            judged["sweep"] = judge_sweep(swept, self.timesteps, self.sweep_trainings())
        return judged

    def report(self, finished: dict[Hashable, Finished], judged: dict[str, Any]) -> str:
        out = Path(self.settings.out)
        figures = {}
        for entry in judged["scenarios"]:
            group = [
                t for t in self.trainings() if (t.number, t.fusion) == (entry["scenario"], entry["fusion"])
            ]
            curves = {f"{t.algo}-{t.reward}": read_curves(t.folder) for t in group}
            entry["curves"] = {key: flattened(curve) for key, curve in curves.items()}
            figures[f"paper-{entry['scenario']}-{entry['fusion']}"] = curves
        if "sweep" in judged:
            folders = {t.timesteps: t.folder for t in (self.sweep_baseline(), *self.sweep_trainings())}
            for row in judged["sweep"]["budgets"]:
                row["curve"] = flattened(read_curves(folders[row["timesteps"]]))
        judged["training"] = self.training_record()
        judged |= training_times(out)
        (out / RESULTS_FILE).write_text(json.dumps(judged, indent=1, default=float) + "\n")
        text = rl_markdown(judged)
        (out / "rl.md").write_text(text)
        if self.settings.figures:
            from ..plots import plot_learning_curves

            for name, curves in drawable(figures).items():
                plot_learning_curves(curves, out / f"curves_{name}.png", name)
        return text


def drawable(figures: dict[str, dict[str, list[dict[str, np.ndarray]]]]) -> dict[str, Any]:
    """The figures with a point to draw: a figure of curves in which no training episode ended
    would have no line."""
    return {
        name: curves
        for name, curves in figures.items()
        if any(len(c["timesteps"]) for seeds in curves.values() for c in seeds)
    }


def learner_policies(rows: dict[str, Any], tag: str) -> list[str]:
    """The policies of ``rows`` trained into folders named ``tag`` (``ALGO-REWARD``, a sweep's
    ``ALGO-REWARD-TIMESTEPS``)."""
    return sorted(p for p in rows if f"/{tag}/" in p)


def judge_learners(summaries: dict[Any, dict[str, Any]], learners: list[tuple[str, str]]) -> dict[str, Any]:
    """Across-seed statistics of every learner in every scenario and fusion (``{(number,
    fusion): summary.json}``), their paired ARMSE differences against :data:`COMPARED`, and per
    fusion the IQM over scenarios of their ARMSE as a ratio to best-tracking's."""
    scenarios = []
    ratios: dict[str, dict[str, list[np.ndarray]]] = {}
    for (number, fusion), summary in summaries.items():
        rows = summary["policies"]
        entry: dict[str, Any] = {
            "scenario": number,
            "fusion": fusion,
            "trials": summary["trials"],
            "compared": {
                p: {m: {"value": rows[p][m], "ci": rows[p]["ci"][m]} for m in ("armse", "final_regret")}
                for p in COMPARED
            },
            "learners": {},
        }
        for algo, reward in learners:
            policies = learner_policies(rows, f"{algo}-{reward}")
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
                "minus": {other: _minus(summary, policies, other) for other in COMPARED},
            }
            ratios.setdefault(fusion, {}).setdefault(key, []).append(armse / rows["best-tracking"]["armse"])
        scenarios.append(entry)
    return {
        "scenarios": scenarios,
        "over_scenarios": {
            fusion: {key: across_seeds(groups, "iqm") for key, groups in by_learner.items()}
            for fusion, by_learner in ratios.items()
        },
    }


def _minus(summary: dict[str, Any], policies: list[str], other: str) -> dict[str, Any]:
    """The mean over seeds of each seed's ARMSE minus ``other``'s, paired on the same trials,
    with its interval over seeds."""
    differences = [paired_difference(summary, p, other, "armse")["estimate"] for p in policies]
    return across_seeds([np.array(differences)], "mean")


def judge_sweep(finished: dict[int, Finished], timesteps: int, swept: list[Training]) -> dict[str, Any]:
    """The budget sweep's runs (``{budget: run}``, each with the study's seeds beside the
    budget's): per budget (``timesteps``, the study's own, first), the learner's ARMSE across
    seeds, its paired difference from best-tracking and, seed by seed, from the same seed trained
    for ``timesteps`` (the longer training continues the shorter: same weights, same episodes)."""
    first = swept[0]
    tag = f"{first.algo}-{first.reward}"
    summaries = [finished[t.timesteps].summary for t in swept]
    budgets = [_budget_row(summaries[0], _per_seed(summaries[0]["policies"], tag), timesteps)]
    for t, summary in zip(swept, summaries, strict=True):
        rows = summary["policies"]
        longer, study = _per_seed(rows, f"{tag}-{t.timesteps}"), _per_seed(rows, tag)
        row = _budget_row(summary, longer, t.timesteps)
        common = sorted(set(longer) & set(study))
        differences = [rows[longer[s]]["armse"] - rows[study[s]]["armse"] for s in common]
        row["minus_study"] = across_seeds([np.array(differences)], "mean")
        budgets.append(row)
    return {
        "scenario": first.number,
        "fusion": first.fusion,
        "learner": tag,
        "trials": summaries[0]["trials"],
        "budgets": budgets,
    }


def _budget_row(summary: dict[str, Any], seeds: dict[int, str], timesteps: int) -> dict[str, Any]:
    """A budget's trained seeds (``{seed: policy}``, :func:`_per_seed`): their ARMSE across seeds
    and against best-tracking."""
    policies = list(seeds.values())
    armse = np.array([summary["policies"][p]["armse"] for p in policies])
    return {
        "timesteps": timesteps,
        "seeds": len(policies),
        "armse": {s: across_seeds([armse], s) for s in ("mean", "iqm")},
        "minus_best_tracking": _minus(summary, policies, "best-tracking"),
    }


def _per_seed(rows: dict[str, Any], tag: str) -> dict[int, str]:
    """``{seed: policy}`` of the trained seeds in training folders named ``tag``."""
    found = {}
    for policy in learner_policies(rows, tag):
        match = re.search(r"/seed-(\d+)/", policy)
        if match:
            found[int(match.group(1))] = policy
    return dict(sorted(found.items()))


def training_times(out: Path) -> dict[str, float]:
    """The study's trainings' time, from every seed's ``ppo.json`` whichever invocation trained
    it: ``training_worker_s``, the sum of their training wall times (``train_wall_s``), and
    ``training_busy_s``, the wall time in which at least one of them ran (the union of their
    ``[trained_from_unix_s, + train_wall_s]`` intervals, so the gap between an interrupted
    invocation and the one resuming it is not counted), left out where a training does not record
    when it ran (SB3's learners, torch-ppo before the record) or none is there."""
    from ..training import META_FILE

    metas = [json.loads(path.read_text()) for path in sorted(out.glob(f"train/*/*/seed-*/{META_FILE}"))]
    times = {"training_worker_s": float(sum(meta["train_wall_s"] for meta in metas))}
    if not metas or any("trained_from_unix_s" not in meta for meta in metas):
        return times
    busy, reached = 0.0, -math.inf
    for start, wall in sorted((meta["trained_from_unix_s"], meta["train_wall_s"]) for meta in metas):
        busy += max(0.0, start + wall - max(start, reached))
        reached = max(reached, start + wall)
    return times | {"training_busy_s": busy}


def read_curves(folder: Path) -> list[dict[str, np.ndarray]]:
    """The learning curve of every seed in ``folder`` (``seed-S/curve.csv``)."""
    from ..training import CURVE_FILE

    curves = []
    for path in sorted(folder.glob(f"seed-*/{CURVE_FILE}")):
        with path.open() as handle:
            rows = list(csv.DictReader(handle))
        curves.append({k: np.array([float(r[k]) for r in rows]) for k in ("timesteps", "return", "armse")})
    return curves


#: What a learning curve's points are, and why one of few is not judged.
CURVE_POINTS = (
    "A curve's points: the rollouts in which a training episode ended, the fewest over its seeds; "
    f"with fewer than {MIN_CURVE_POINTS} its flatness is not judged (`-`)."
)


def flattened(curves: list[dict[str, np.ndarray]]) -> dict[str, Any]:
    """Whether the mean ARMSE over seeds has flattened: its relative change between the last two
    fifths of the rollouts (``None`` when the curves are too short to tell)."""
    length = min((len(c["armse"]) for c in curves), default=0)
    if length < MIN_CURVE_POINTS:
        return {"change": None, "flat": None, "rollouts": length}
    mean = np.nanmean([c["armse"][:length] for c in curves], axis=0)
    fifth = length // 5
    last, before = np.nanmean(mean[-fifth:]), np.nanmean(mean[-2 * fifth : -fifth])
    change = float((last - before) / before)
    return {"change": change, "flat": abs(change) <= FLAT_CHANGE, "rollouts": length}


def rl_markdown(judged: dict[str, Any]) -> str:
    """The study's tables."""
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
            f"## paper-{entry['scenario']}, {entry['fusion']} fusion ({entry['trials']} trials)",
            "",
            "| policy | seeds | ARMSE (m), mean | ARMSE (m), IQM | final regret, mean | "
            + " | ".join(f"- {other}" for other in MINUS_ORDER)
            + " |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for p, row in entry["compared"].items():
            armse = _cell(row["armse"], "{:.3f}")
            regret = _cell(row["final_regret"], "{:.0f}")
            lines.append(f"| `{p}` | - | {armse} | - | {regret} | - | - | - |")
        for key, row in entry["learners"].items():
            cells = [
                _cell(row["armse"]["mean"], "{:.3f}"),
                _cell(row["armse"]["iqm"], "{:.3f}"),
                _cell(row["final_regret"]["mean"], "{:.0f}"),
                *(_cell(row["minus"][other], "{:.3f}") for other in MINUS_ORDER),
            ]
            lines.append(f"| `{key}` | {row['seeds']} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "`- X`: the learner's ARMSE minus X's, paired on the same trials, averaged over seeds (interval over "
        "seeds); an interval below 0 means the learner tracks better than X.",
        "",
        "## Over the scenarios",
        "",
        "| fusion | learner | IQM of ARMSE / best-tracking's ARMSE |",
        "|---|---|---|",
    ]
    for fusion, by_learner in judged["over_scenarios"].items():
        lines += [f"| {fusion} | `{key}` | {_cell(stat, '{:.3f}')} |" for key, stat in by_learner.items()]
    lines += ["", "Stratified bootstrap: each scenario's seeds resampled within it.", ""]
    curves = [(entry, key, c) for entry in judged["scenarios"] for key, c in entry.get("curves", {}).items()]
    if curves:
        lines += [
            "## Learning curves",
            "",
            "| scenario | fusion | learner | points | change of the mean ARMSE, last two fifths | flat |",
            "|---|---|---|---|---|---|",
        ]
        lines += [
            f"| paper-{entry['scenario']} | {entry['fusion']} | `{key}` | {c['rollouts']} | {_change(c)} | "
            f"{_flat(c)} |"
            for entry, key, c in curves
        ]
        lines += ["", CURVE_POINTS, ""]
    if "sweep" in judged:
        lines += _sweep_markdown(judged["sweep"])
    return "\n".join(lines) + "\n"


def _sweep_markdown(sweep: dict[str, Any]) -> list[str]:
    study = sweep["budgets"][0]["timesteps"]
    lines = [
        f"## Budget sweep: `{sweep['learner']}`, paper-{sweep['scenario']}, {sweep['fusion']} fusion "
        f"({sweep['trials']} trials)",
        "",
        f"| timesteps | seeds | ARMSE (m), mean | ARMSE (m), IQM | - best-tracking | - at {study:,} | "
        "curve points | change of the mean ARMSE, last two fifths | flat |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for row in sweep["budgets"]:
        against = _cell(row["minus_study"], "{:.3f}") if "minus_study" in row else "-"
        curve = row.get("curve", {"change": None, "flat": None})
        lines.append(
            f"| {row['timesteps']:,} | {row['seeds']} | {_cell(row['armse']['mean'], '{:.3f}')} | "
            f"{_cell(row['armse']['iqm'], '{:.3f}')} | {_cell(row['minus_best_tracking'], '{:.3f}')} | "
            f"{against} | {curve.get('rollouts', '-')} | {_change(curve)} | {_flat(curve)} |"
        )
    lines += [
        "",
        f"`- at {study:,}`: each seed's ARMSE minus the same seed's trained for {study:,} steps, on the "
        "same trials, averaged over seeds (interval over seeds). " + CURVE_POINTS,
        "",
    ]
    return lines


def _cell(stat: dict[str, Any], fmt: str) -> str:
    return format_estimate(stat["value"], stat["ci"], fmt)


def _change(curve: dict[str, Any]) -> str:
    return "-" if curve["change"] is None else f"{100 * curve['change']:+.1f} %"


def _flat(curve: dict[str, Any]) -> str:
    return "-" if curve["flat"] is None else ("yes" if curve["flat"] else "no")
