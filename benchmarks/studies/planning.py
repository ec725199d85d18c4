"""The planning study: what looking ahead buys in tracking, where, and at what cost.

``mimo-radar-bench planning --out DIR`` runs, on each v1 paper scenario under both fusions and
on the first trials of the tracking study (same seed; trial ``i`` is seeded ``seed + i``, so
its :data:`DEFAULT_TRIALS` trials by default are the first of the tracking study's 200), into
``DIR/<scenario>-<fusion>`` (resumable):

* best-tracking and tracking-ucb (the one-step policies);
* the receding-horizon oracle ``plan-tracking:H`` (beam search) at each H of :data:`HORIZONS`,
  and its rollout and MCTS searches at :data:`SEARCH_HORIZON`;
* the learning planner ``plan-tracking-ucb:H`` at each H of :data:`LEARNER_HORIZONS`;
* optionally a trained PPO (``--ppo PATTERN``, as the tracking study's).

With ``--rl DIR`` (an RL study's output, same seed), the planners are also paired against each
of its learners, the mean over its seeds, on the trials both studies ran (trial ``i`` is seeded
``seed + i`` in both; :func:`cross_run_differences` checks that best-tracking's errors agree).

Beside them it computes the best achievable bound of the same trials
(:func:`mimo_radar_env.tracking.planning.best_achievable_bound`: the selection sequence with
the smallest time-averaged PCRB that a beam finds knowing the whole truth), averaged as the
runs average their bounds. It writes ``DIR/planning.md`` and ``DIR/planning.json``: ARMSE
against H, each policy's compute time per trial-step, the paired ARMSE differences against
best-tracking and tracking-ucb (and PPO), and every policy's ARMSE beside its own bound, the
best achievable bound and the oracles'.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Hashable
from pathlib import Path
from typing import Any

import numpy as np

from mimo_radar_env import MimoRadarSelectVectorEnv

from ..errors import BenchError
from ..report import format_estimate, paired_difference
from ..study import Finished, Run, Study
from .tracking import add_fusion_run_arguments, fusion_runs

HORIZONS = (1, 2, 5, 10)
SEARCH_HORIZON = 5
LEARNER_HORIZONS = (2, 5)
#: The beam of the best achievable bound (over the whole episode).
BOUND_WIDTH = 10
#: 50 trials keep the whole study (6 runs of 10 policies over 1000 steps) within about half an
#: hour of a 2-core machine: the rollout and MCTS searches score thousands of plans per trial
#: and step; the tracking study's 200 would take about four times as long.
DEFAULT_TRIALS = 50
RESULTS_FILE = "planning.json"
HORIZON_FIGURE = "horizons.png"


def planning_policies() -> tuple[str, ...]:
    return (
        "best-tracking",
        "tracking-ucb",
        *(f"plan-tracking:{h}" for h in HORIZONS),
        f"plan-tracking-rollout:{SEARCH_HORIZON}",
        f"plan-tracking-mcts:{SEARCH_HORIZON}",
        *(f"plan-tracking-ucb:{h}" for h in LEARNER_HORIZONS),
    )


class PlanningStudy(Study):
    name = "planning"
    default_trials = DEFAULT_TRIALS
    description = (
        f"Run {', '.join(planning_policies())} on the v1 paper scenarios under both fusions (into "
        "OUT/<scenario>-<fusion>, resumable), compute the best achievable bound of the same trials, "
        "and write OUT/planning.md and OUT/planning.json."
    )

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        add_fusion_run_arguments(parser)
        parser.add_argument(
            "--rl",
            default=None,
            metavar="DIR",
            help="an RL study's output (mimo-radar-bench rl --out DIR, same --seed): pair the planners "
            "against each of its learners on the trials both ran (the fusions it ran)",
        )

    def runs(self) -> list[Run]:
        if self.args.rl is not None and not Path(self.args.rl).is_dir():
            raise BenchError(
                f"--rl {self.args.rl!r} is not a folder: give an RL study's output (rl --out DIR)"
            )
        return fusion_runs(self, planning_policies())

    def judge(self, finished: dict[Hashable, Finished]) -> list[dict[str, Any]]:
        from .. import harness

        judged = []
        for key, f in finished.items():
            per_trial = harness.load_per_trial(f.folder, f.config)  # read once, for both below
            row = judge_run(key, f.summary, best_bound(f, self.settings.seed, per_trial))
            if self.args.rl:
                learners = against_learners(f, Path(self.args.rl), self.settings.seed, per_trial)
                if learners is not None:
                    row["learners"] = learners
            judged.append(row)
        return judged

    def report(self, finished: dict[Hashable, Finished], judged: list[dict[str, Any]]) -> str:
        out = Path(self.settings.out)
        (out / RESULTS_FILE).write_text(json.dumps(judged, indent=1) + "\n")
        text = planning_markdown(judged)
        (out / "planning.md").write_text(text)
        if self.settings.figures:
            plot_horizons(judged, out / HORIZON_FIGURE)
        return text


def best_bound(
    finished: Finished, seed: int, per_trial: dict[str, dict[str, np.ndarray]] | None = None
) -> dict[str, Any]:
    """The best achievable bound of a finished run's trials, averaged as its policies' bounds
    are (``TrialMetrics.bound``, with its interval over trials), and every policy's ARMSE as a
    ratio to it, paired on the trials (``armse_over_best``); ``per_trial``: the run's
    (:func:`~benchmarks.harness.load_per_trial`), read from its folder when not given."""
    from benchmarks.metrics import TrialMetrics
    from mimo_radar_env.tracking.planning import Planner, position_traces

    from .. import harness, uncertainty
    from ..report import trial_metrics

    config = finished.config
    scenario = config.scenario_object
    env = MimoRadarSelectVectorEnv(num_envs=config.trials, scenario=scenario, **config.env_options)
    env.reset(seed=seed)
    forecast = env.engine.bound_forecast().first(config.steps)
    sc = scenario
    planner = Planner(
        sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step, "beam", BOUND_WIDTH, fusion="centralized"
    )
    plan, _ = planner.plan(forecast)
    traces = position_traces(planner, forecast, plan)  # (N, T, K)
    zeros = np.zeros(traces.shape[:2])
    best = TrialMetrics(
        {
            "trial_expected": zeros,
            "trial_optimal": zeros,
            "trial_matches": zeros,
            "trial_squared_error": traces,
            "trial_bound_squared": traces,
        },
        sc.tx_per_step * sc.rx_per_step,
    )
    result = uncertainty.estimate(best.bound, config.trials, seed)
    if per_trial is None:
        per_trial = harness.load_per_trial(finished.folder, config)
    policies = trial_metrics(config, per_trial)
    ratios = {
        p: uncertainty.estimate(lambda w, m=m: m.armse(w) / best.bound(w), config.trials, seed)
        for p, m in policies.items()
    }
    return {"value": result["estimate"], "ci": result["ci"], "width": BOUND_WIDTH, "armse_over_best": ratios}


def _first_trials(per_trial: dict[str, np.ndarray], trials: int) -> dict[str, np.ndarray]:
    from benchmarks.metrics import TRIAL_FIELDS

    return {key: per_trial[key][:trials] for key in TRIAL_FIELDS}


def cross_run_differences(
    finished: Finished,
    folder: Path,
    references: dict[str, list[str]],
    seed: int,
    witness: str = "best-tracking",
    ours: dict[str, dict[str, np.ndarray]] | None = None,
) -> dict[str, Any]:
    """ARMSE differences of this run's planners (``plan-*``) against policies of another run
    (``folder``) on the trials both ran, paired trial by trial: ``{"trials", "minus": {planner:
    {name: estimate}}}``, each reference group ``references[name]`` (e.g. a learner's seeds)
    taken as the mean of its policies' ARMSE. The runs must share their trials: the same
    scenario, seed, steps and fusion, and ``witness``'s squared errors identical on the trials
    both ran (checked), so that trial ``i`` is the same truth, observed and tracked alike, in
    both. ``ours``: this run's per-trial data, read from its folder when not given."""
    from benchmarks.metrics import TrialMetrics

    from .. import harness, uncertainty
    from ..errors import BenchError

    try:
        other = harness.RunConfig(**json.loads((folder / harness.CONFIG_FILE).read_text()))
    except (OSError, json.JSONDecodeError, TypeError) as exc:
        raise BenchError(f"cannot read the run in {folder}: {exc}") from None
    mine = finished.config
    for name in ("scenario", "seed", "steps"):
        if getattr(other, name) != getattr(mine, name):
            raise BenchError(
                f"the run in {folder} has another {name} than {finished.folder}: they share no trials"
            )
    if other.env_options.get("fusion") != mine.env_options.get("fusion"):
        raise BenchError(f"the run in {folder} fuses otherwise than {finished.folder}")
    trials = min(other.trials, mine.trials)
    theirs = harness.load_per_trial(folder, other)
    if ours is None:
        ours = harness.load_per_trial(finished.folder, mine)
    if witness not in theirs or witness not in ours:
        raise BenchError(f"both runs must hold {witness!r} to check that they share their trials")
    if not np.array_equal(
        ours[witness]["trial_squared_error"][:trials], theirs[witness]["trial_squared_error"][:trials]
    ):
        raise BenchError(
            f"{witness!r}'s errors differ between {finished.folder} and {folder} on the same trial numbers: "
            "the runs do not share their trials"
        )
    channels = mine.scenario_object.num_channels_per_step

    def armse(per_trial: dict[str, dict[str, np.ndarray]], policy: str):
        return TrialMetrics(_first_trials(per_trial[policy], trials), channels).armse

    minus: dict[str, dict[str, Any]] = {}
    for planner in (p for p in mine.policies if p.startswith("plan-")):
        mine_armse = armse(ours, planner)
        minus[planner] = {}
        for name, policies in references.items():
            group = [armse(theirs, p) for p in policies]

            def difference(w: np.ndarray, a=mine_armse, group=group) -> np.ndarray:
                return a(w) - np.mean([g(w) for g in group], axis=0)

            minus[planner][name] = uncertainty.estimate(difference, trials, seed)
    return {"trials": trials, "minus": minus}


def against_learners(
    finished: Finished, rl_out: Path, seed: int, per_trial: dict[str, dict[str, np.ndarray]] | None = None
) -> dict[str, Any] | None:
    """The planners against each learner of an RL study (``mimo-radar-bench rl --out``), the
    mean over its seeds, on the trials both ran; None where the RL study has no run of this
    scenario and fusion."""
    from .. import harness
    from .rl import DEVICE_TRAININGS, TRAININGS, learner_policies

    folder = rl_out / f"{finished.run.scenario}-{finished.config.env_options['fusion']}"
    config_file = folder / harness.CONFIG_FILE
    if not config_file.is_file():
        return None
    policies = dict.fromkeys(json.loads(config_file.read_text())["policies"])
    tags = [f"{algo}-{reward}" for algo, reward, _ in (*TRAININGS, *DEVICE_TRAININGS)]
    references = {tag: learner_policies(policies, tag) for tag in tags if learner_policies(policies, tag)}
    result = cross_run_differences(finished, folder, references, seed, ours=per_trial)
    result["seeds"] = {name: len(p) for name, p in references.items()}
    return result


def judge_run(key: tuple[int, str], summary: dict[str, Any], bound: dict[str, Any]) -> dict[str, Any]:
    """One run's findings: every policy's ARMSE, bound and compute time per trial-step, the
    paired ARMSE differences against the one-step policies (and PPO), and the best bound."""
    number, fusion = key
    rows = summary["policies"]
    per_step = summary["trials"] * summary["steps"]
    references = ["best-tracking", "tracking-ucb", *(p for p in rows if p.startswith("ppo:"))]
    return {
        "scenario": number,
        "fusion": fusion,
        "trials": summary["trials"],
        "best_bound": {k: v for k, v in bound.items() if k != "armse_over_best"},
        "policies": {
            p: {
                "armse": {"value": r["armse"], "ci": r["ci"]["armse"]},
                "bound": {"value": r["bound"], "ci": r["ci"]["bound"]},
                "armse_over_best_bound": bound["armse_over_best"][p],
                "ms_per_trial_step": 1e3 * r["wall_s"] / per_step,
            }
            for p, r in rows.items()
        },
        "minus_best_tracking": {
            p: paired_difference(summary, p, "best-tracking", "armse") for p in rows if p != "best-tracking"
        },
        "minus": {
            p: {ref: paired_difference(summary, p, ref, "armse") for ref in references if ref != p}
            for p in rows
            if p.startswith("plan-")
        },
    }


def planning_markdown(judged: list[dict[str, Any]]) -> str:
    """The study's tables, one per run."""
    lines = [
        "# The planning study",
        "",
        "ARMSE and bound (m) with 95 % intervals over trials; `- X`: the policy's ARMSE minus X's on the "
        "same trials (an interval below 0: it tracks better than X); time per trial-step from the "
        "runs' compute time. The best achievable bound is the smallest time-averaged PCRB a beam of "
        f"width {BOUND_WIDTH} finds over the whole episode knowing the truth, averaged as the bounds are; "
        "ARMSE / best bound is paired on the trials.",
    ]
    for r in judged:
        best = format_estimate(r["best_bound"]["value"], r["best_bound"]["ci"], "{:.3f}")
        refs = sorted(
            {ref for diffs in r["minus"].values() for ref in diffs}, key=lambda x: (x.startswith("ppo"), x)
        )
        lines += [
            "",
            f"## paper-{r['scenario']}, {r['fusion']} ({r['trials']} trials)",
            "",
            f"Best achievable bound: {best} m.",
            "",
            "| policy | ARMSE | bound | ARMSE / best bound | ms / trial-step | "
            + " | ".join(f"- {ref}" for ref in refs)
            + " |",
            "|---|---|---|---|---|" + "---|" * len(refs),
        ]
        for p, row in r["policies"].items():
            ratio = row["armse_over_best_bound"]
            diffs = r["minus"].get(p, {})
            cells = [
                format_estimate(diffs[ref]["estimate"], diffs[ref]["ci"], "{:.3f}") if ref in diffs else "-"
                for ref in refs
            ]
            lines.append(
                f"| `{p}` | {format_estimate(row['armse']['value'], row['armse']['ci'], '{:.3f}')} | "
                f"{format_estimate(row['bound']['value'], row['bound']['ci'], '{:.3f}')} | "
                f"{format_estimate(ratio['estimate'], ratio['ci'], '{:.3f}')} | "
                f"{row['ms_per_trial_step']:.2f} | " + " | ".join(cells) + " |"
            )
        learners = r.get("learners")
        if learners:
            names = list(learners["seeds"])
            lines += [
                "",
                f"Against the RL study's learners (each the mean ARMSE of its seeds), paired on the first "
                f"{learners['trials']} trials, which both studies ran:",
                "",
                "| policy | " + " | ".join(f"- {n} ({learners['seeds'][n]} seeds)" for n in names) + " |",
                "|---|" + "---|" * len(names),
            ]
            for p, diffs in learners["minus"].items():
                cells = [format_estimate(diffs[n]["estimate"], diffs[n]["ci"], "{:.3f}") for n in names]
                lines.append(f"| `{p}` | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot_horizons(judged: list[dict[str, Any]], path: Path) -> None:
    """Looking ahead against H: each planner's ARMSE minus its one-step policy's, paired on the
    same trials with its 95 % interval (the oracle against best-tracking, solid; the learning
    planner against tracking-ucb, dashed), one line per scenario, one panel per fusion."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fusions = list(dict.fromkeys(r["fusion"] for r in judged))
    fig = Figure(figsize=(5 * len(fusions), 4))
    FigureCanvasAgg(fig)
    axes = np.atleast_1d(fig.subplots(1, len(fusions), sharey=True))
    for ax, fusion in zip(axes, fusions, strict=True):
        for r in (r for r in judged if r["fusion"] == fusion):
            for prefix, reference, style in (
                ("plan-tracking:", "best-tracking", "-"),
                ("plan-tracking-ucb:", "tracking-ucb", "--"),
            ):
                points = sorted(
                    (int(p.removeprefix(prefix)), d[reference])
                    for p, d in r["minus"].items()
                    if p.startswith(prefix)
                )
                if prefix == "plan-tracking-ucb:":
                    points = [(1, {"estimate": 0.0, "ci": [0.0, 0.0]}), *points]  # H = 1 is tracking-ucb
                if not points:
                    continue
                h = np.array([x for x, _ in points])
                value = np.array([d["estimate"] for _, d in points])
                low = value - np.array([d["ci"][0] for _, d in points])
                high = np.array([d["ci"][1] for _, d in points]) - value
                ax.errorbar(
                    h,
                    value,
                    yerr=[low, high],
                    linestyle=style,
                    marker="o",
                    capsize=3,
                    color=f"C{r['scenario'] - 1}",
                    label=f"paper-{r['scenario']}: {prefix.rstrip(':')} - {reference}",
                )
        ax.axhline(0.0, color="grey", linewidth=0.8)
        ax.set(xscale="log", xlabel="horizon H (steps)", title=f"{fusion} fusion")
        ax.set_xticks([1, 2, 5, 10], labels=["1", "2", "5", "10"])
    axes[0].set_ylabel("ARMSE minus the one-step policy's (m)")
    axes[0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
