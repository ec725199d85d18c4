"""The paper's claims as testable statements, judged on a finished paper study.

Every claim is a list of comparisons; a comparison is a statistic of the policies' per-trial
values, evaluated on the same resampled trials for every policy it involves (paired), with a
claimed sign. From its 95 % bootstrap interval a comparison **holds** (significant in the
claimed direction), is **consistent** (not significant either way) or is **contradicted**
(significant against). A claim holds when all its comparisons hold, is contradicted when any
is contradicted, and is consistent otherwise. Windows are steps ``[start, stop)`` of the
paper's 1000-step horizon (time in seconds, ``Ts = 1 s``); a window the run did not reach is
"not evaluated".
"""

from __future__ import annotations

import argparse
import functools
import json
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from benchmarks.metrics import TrialMetrics
from mimo_radar_env import Scenario, env_version
from mimo_radar_env.envs.versions import SCENARIO_SETS, paper_key

from .. import uncertainty, verdicts
from ..cli import Command
from ..errors import BenchError
from ..harness import PAPER_POLICIES, RunConfig, load_per_trial
from ..report import PAPER_ARMSE, PAPER_ASR, paper_armse, trial_metrics
from ..settings import Settings, add_scenarios_argument, paper_numbers
from ..study import Finished, Run, Study, execute

PAPER_KEYS = ("paper-1", "paper-2", "paper-3")

LEARNING = ("mg-crb-cl", "ucb1", "epsilon-greedy")
FIXED = ("fix1", "fix2")
Window = tuple[int, int] | None


class Policies(dict):
    """The study's policies, ``{policy: TrialMetrics}``, and its scenario (for S1.1)."""

    def __init__(self, metrics: dict[str, TrialMetrics], scenario: Any = None) -> None:
        super().__init__(metrics)
        self.scenario = scenario
        self.cache: dict[str, Any] = {}  # exact, trial-free quantities of the scenario (S1.1)
        self.steps = next(iter(metrics.values())).steps
        self.num_trials = next(iter(metrics.values())).num_trials


#: The claims' metric names and the TrialMetrics method each reads.
METRICS = {"sinr_db": "mean_sinr_db", "regret": "regret", "armse": "armse", "asr": "asr"}


def _metric(p: Policies, metric: str, policy: str, w: NDArray, **kw: Any) -> NDArray:
    return getattr(p[policy], METRICS[metric])(w, **kw)


#: A metric of one policy that a statistic reads: ``(metric, policy, its keywords as items)``.
Part = tuple[str, str, tuple[tuple[str, Any], ...]]


@dataclass(frozen=True)
class Comparison:
    """``statistic(policies, w)`` claimed ``> 0`` (``sign=+1``) or ``< 0`` (``sign=-1``);
    ``parts``, where given, are the metrics of one policy each that the statistic combines
    (:func:`prepare` computes them before the other policies are done)."""

    text: str
    statistic: Callable[[Policies, NDArray], NDArray]
    sign: int
    policies: tuple[str, ...]
    reaches: int = 0  # the last step the statistic reads (0: any run)
    parts: tuple[Part, ...] = ()


def _parts(metric: str, policies: Sequence[str], **kw: Any) -> tuple[Part, ...]:
    return tuple((metric, policy, tuple(sorted(kw.items()))) for policy in policies)


@dataclass(frozen=True)
class Claim:
    id: str
    scenario: str
    text: str
    comparisons: tuple[Comparison, ...]
    paper: dict[str, Any] = field(default_factory=dict)


def _diff(metric: str, a: str, b: str, sign: int, window: Window = None, **kw: Any) -> Comparison:
    """``metric(a) - metric(b)`` claimed of sign ``sign``."""
    where = f" over {window[0]}-{window[1]} s" if window else ""
    target = f" of target {kw['target'] + 1}" if "target" in kw else ""
    op = ">" if sign > 0 else "<"

    extra = {"window": window} if window and metric in ("sinr_db", "armse") else {}

    def statistic(p: Policies, w: NDArray) -> NDArray:
        return _metric(p, metric, a, w, **extra, **kw) - _metric(p, metric, b, w, **extra, **kw)

    return Comparison(
        f"{metric}{target}{where}: {a} {op} {b}",
        statistic,
        sign,
        (a, b),
        window[1] if window else 0,
        _parts(metric, (a, b), **extra, **kw),
    )


def _ordering(metric: str, order: tuple[str, ...], **kw: Any) -> tuple[Comparison, ...]:
    """``order[0] < order[1] < ...`` as consecutive paired comparisons."""
    return tuple(_diff(metric, a, b, -1, **kw) for a, b in zip(order, order[1:], strict=False))


def _regret_at(a: str, b: str, sign: int, at: int) -> Comparison:
    op = ">" if sign > 0 else "<"
    return Comparison(
        f"regret at {at} s: {a} {op} {b}",
        lambda p, w: p[a].regret(w, at) - p[b].regret(w, at),
        sign,
        (a, b),
        at,
    )


def _change(policy: str, before: Window, after: Window, sign: int) -> Comparison:
    op = ">" if sign > 0 else "<"
    return Comparison(
        f"sinr_db of {policy}: {after[0]}-{after[1]} s {op} {before[0]}-{before[1]} s",
        lambda p, w: p[policy].mean_sinr_db(w, after) - p[policy].mean_sinr_db(w, before),
        sign,
        (policy,),
        after[1],
    )


def _versus_best_of(
    metric: str, policy: str, others: tuple[str, ...], sign: int, window: Window = None
) -> Comparison:
    """``metric(policy) - max(metric(others))`` (sign +1) or ``- min(...)`` (sign -1)."""
    extreme = np.max if sign > 0 else np.min
    word = "above all of" if sign > 0 else "below all of"
    extra = {"window": window} if window else {}

    def statistic(p: Policies, w: NDArray) -> NDArray:
        values = [_metric(p, metric, o, w, **extra) for o in others]
        return _metric(p, metric, policy, w, **extra) - extreme(values, axis=0)

    where = f" over {window[0]}-{window[1]} s" if window else ""
    return Comparison(
        f"{metric}{where}: {policy} {word} {list(others)}",
        statistic,
        sign,
        (policy, *others),
        window[1] if window else 0,
        _parts(metric, (policy, *others), **extra),
    )


def paper_claims() -> tuple[Claim, ...]:
    """The claims of the paper's Section IV (scenarios ``paper-1``, ``-2``, ``-3``)."""
    s1, s2, s3 = "paper-1", "paper-2", "paper-3"
    armse_order = ("best", "mg-crb-cl", "fix1", "epsilon-greedy", "ucb1", "fix2")
    claims = [
        Claim(
            "S1.1",
            s1,
            "Best selects {TX1,TX2; RX1,RX2,RX3} over 0-380 s and {TX3,TX4; RX2,RX4,RX5} over "
            "590-1000 s (checked exactly on the noise-free track: the fraction of steps, at least "
            f"{BEST_WINDOW_FRACTION:.0%})",
            tuple(_best_window(window) for window, _ in BEST_WINDOWS),
        ),
        Claim(
            "S1.2",
            s1,
            "fix1 has the higher average SINR in the first half of the horizon, fix2 in the second",
            (
                _diff("sinr_db", "fix1", "fix2", +1, (0, 500)),
                _diff("sinr_db", "fix2", "fix1", +1, (500, 1000)),
            ),
        ),
        Claim(
            "S1.3",
            s1,
            "epsilon-greedy's average SINR is above both fixed policies' over the horizon",
            (_diff("sinr_db", "epsilon-greedy", "fix1", +1), _diff("sinr_db", "epsilon-greedy", "fix2", +1)),
        ),
        Claim(
            "S1.4",
            s1,
            "UCB1's average SINR is above the fixed policies' only early (0-400 s), not later",
            (
                _versus_best_of("sinr_db", "ucb1", FIXED, +1, (0, 400)),
                Comparison(
                    "sinr_db over 400-1000 s: ucb1 not above the better fixed policy",
                    lambda p, w: (
                        p["ucb1"].mean_sinr_db(w, (400, 1000))
                        - np.max([p[f].mean_sinr_db(w, (400, 1000)) for f in FIXED], axis=0)
                    ),
                    -1,
                    ("ucb1", *FIXED),
                    1000,
                ),
            ),
        ),
        Claim(
            "S1.5",
            s1,
            "MG-CRB-CL has the highest average SINR of the learning policies",
            (_diff("sinr_db", "mg-crb-cl", "ucb1", +1), _diff("sinr_db", "mg-crb-cl", "epsilon-greedy", +1)),
        ),
        Claim(
            "S1.6",
            s1,
            "MG-CRB-CL has the lowest final regret of the learning policies; the fixed policies the highest",
            (
                _diff("regret", "mg-crb-cl", "ucb1", -1),
                _diff("regret", "mg-crb-cl", "epsilon-greedy", -1),
                _versus_best_of("regret", "fix1", LEARNING, +1),
                _versus_best_of("regret", "fix2", LEARNING, +1),
            ),
        ),
        Claim(
            "S1.7",
            s1,
            "UCB1's regret is below epsilon-greedy's early and above it late (they cross, near 455 s)",
            (_regret_at("ucb1", "epsilon-greedy", -1, 300), _regret_at("ucb1", "epsilon-greedy", +1, 1000)),
        ),
        Claim(
            "S1.8",
            s1,
            "fix1 has the lowest RMSE only around 268-360 s; fix2 the highest most of the time, "
            "except around 500-590 s",
            (
                _versus_best_of(
                    "armse", "fix1", tuple(p for p in armse_order if p != "fix1"), -1, (268, 360)
                ),
                _versus_best_of("armse", "fix2", tuple(p for p in armse_order if p != "fix2"), +1, (0, 500)),
                _versus_best_of(
                    "armse", "fix2", tuple(p for p in armse_order if p != "fix2"), +1, (590, 1000)
                ),
            ),
        ),
        Claim(
            "S1.9",
            s1,
            "ARMSE: Best < MG-CRB-CL < fix1 < epsilon-greedy < UCB1 < fix2",
            _ordering("armse", armse_order),
            {"armse": PAPER_ARMSE[s1]},
        ),
        Claim(
            "S1.10",
            s1,
            "ASR: MG-CRB-CL > epsilon-greedy > UCB1, MG-CRB-CL at least 3x each",
            (
                _diff("asr", "mg-crb-cl", "epsilon-greedy", +1),
                _diff("asr", "epsilon-greedy", "ucb1", +1),
                Comparison(
                    "asr: mg-crb-cl > 3 x epsilon-greedy",
                    lambda p, w: p["mg-crb-cl"].asr(w) - 3 * p["epsilon-greedy"].asr(w),
                    +1,
                    ("mg-crb-cl", "epsilon-greedy"),
                ),
                Comparison(
                    "asr: mg-crb-cl > 3 x ucb1",
                    lambda p, w: p["mg-crb-cl"].asr(w) - 3 * p["ucb1"].asr(w),
                    +1,
                    ("mg-crb-cl", "ucb1"),
                ),
            ),
            {"asr": PAPER_ASR[s1]},
        ),
        Claim(
            "S2.1",
            s2,
            "epsilon-greedy's average SINR is above both fixed policies'; UCB1's SINR deteriorates "
            "after 420 s",
            (
                _diff("sinr_db", "epsilon-greedy", "fix1", +1),
                _diff("sinr_db", "epsilon-greedy", "fix2", +1),
                _change("ucb1", (0, 420), (420, 1000), -1),
            ),
        ),
        Claim(
            "S2.2",
            s2,
            "after the maneuver at 400 s every policy's SINR degrades except MG-CRB-CL's "
            "(100 s after against 100 s before)",
            tuple(_change(p, (300, 400), (400, 500), -1) for p in ("best", "ucb1", "epsilon-greedy", *FIXED))
            + (_change("mg-crb-cl", (300, 400), (400, 500), +1),),
        ),
        Claim(
            "S2.3",
            s2,
            "MG-CRB-CL has the lowest final regret of the learning policies",
            (_diff("regret", "mg-crb-cl", "ucb1", -1), _diff("regret", "mg-crb-cl", "epsilon-greedy", -1)),
        ),
        Claim(
            "S2.4",
            s2,
            "ARMSE: Best < MG-CRB-CL < fix1 < epsilon-greedy < UCB1 < fix2",
            _ordering("armse", armse_order),
            {"armse": PAPER_ARMSE[s2]},
        ),
        Claim(
            "S2.5",
            s2,
            "ASR: MG-CRB-CL > epsilon-greedy > UCB1",
            (_diff("asr", "mg-crb-cl", "epsilon-greedy", +1), _diff("asr", "epsilon-greedy", "ucb1", +1)),
            {"asr": PAPER_ASR[s2]},
        ),
        Claim(
            "S3.1",
            s3,
            "MG-CRB-CL has the highest weighted average SINR and the lowest final regret of the "
            "learning policies",
            (
                _diff("sinr_db", "mg-crb-cl", "ucb1", +1),
                _diff("sinr_db", "mg-crb-cl", "epsilon-greedy", +1),
                _diff("regret", "mg-crb-cl", "ucb1", -1),
                _diff("regret", "mg-crb-cl", "epsilon-greedy", -1),
            ),
        ),
        Claim(
            "S3.2",
            s3,
            "ARMSE over targets: Best < MG-CRB-CL < epsilon-greedy < UCB1 < fix1 < fix2",
            _ordering("armse", ("best", "mg-crb-cl", "epsilon-greedy", "ucb1", "fix1", "fix2")),
            {"armse": PAPER_ARMSE[s3]},
        ),
        Claim(
            "S3.3",
            s3,
            "ARMSE of target 1: MG-CRB-CL < epsilon-greedy < UCB1; UCB1 tracks target 2 better "
            "than MG-CRB-CL",
            (
                _diff("armse", "mg-crb-cl", "epsilon-greedy", -1, target=0),
                _diff("armse", "epsilon-greedy", "ucb1", -1, target=0),
                _diff("armse", "ucb1", "mg-crb-cl", -1, target=1),
            ),
            {"armse": PAPER_ARMSE[s3]},
        ),
        Claim(
            "S3.4",
            s3,
            "ASR: MG-CRB-CL > epsilon-greedy > UCB1",
            (_diff("asr", "mg-crb-cl", "epsilon-greedy", +1), _diff("asr", "epsilon-greedy", "ucb1", +1)),
            {"asr": PAPER_ASR[s3]},
        ),
    ]
    for scenario in (s1, s2, s3):
        claims.append(
            Claim(
                f"A.{scenario[-1]}",
                scenario,
                "MG-CRB-CL beats UCB1 on regret, average SINR and ARMSE",
                (
                    _diff("regret", "mg-crb-cl", "ucb1", -1),
                    _diff("sinr_db", "mg-crb-cl", "ucb1", +1),
                    _diff("armse", "mg-crb-cl", "ucb1", -1),
                ),
            )
        )
    return tuple(claims)


def judge(comparison: Comparison, policies: Policies, seed: int = 0) -> dict[str, Any]:
    """The comparison's estimate, 95 % interval (and its method) and verdict."""
    return judge_all([comparison], policies, seed)[0]


def judge_all(comparisons: Sequence[Comparison], policies: Policies, seed: int = 0) -> list[dict[str, Any]]:
    """Each comparison judged as :func:`judge` judges it, those the run can evaluate from one
    bootstrap (the same numbers as one each)."""
    evaluable = {
        i: c
        for i, c in enumerate(comparisons)
        if c.reaches <= policies.steps and all(p in policies for p in c.policies)
    }
    statistics = {i: (lambda w, c=c: c.statistic(policies, w)) for i, c in evaluable.items()}
    estimated = uncertainty.estimates(statistics, policies.num_trials, seed)
    results = []
    for i, comparison in enumerate(comparisons):
        judged = estimated.get(i)
        if judged is None:
            results.append({"comparison": comparison.text, "verdict": verdicts.NOT_EVALUATED})
        elif judged["ci"] is None:  # too few trials: no interval, no verdict
            results.append(
                {
                    "comparison": comparison.text,
                    "estimate": judged["estimate"],
                    "verdict": verdicts.NOT_EVALUATED,
                }
            )
        else:
            verdict = verdicts.verdict(judged["ci"], comparison.sign)
            results.append({"comparison": comparison.text, **judged, "verdict": verdict})
    return results


def prepare(scenario: str, policy: str, metrics: TrialMetrics, seed: int = 0) -> None:
    """What the claims of ``scenario`` (``paper-N``) read of ``policy`` alone (the comparisons'
    :attr:`~Comparison.parts`), bootstrapped now, as the judge will with ``seed``: ``metrics``
    keeps their terms on those resamples (``TrialMetrics`` keeps them by weight array), so the
    judge, once every policy is done, finds them computed. The same numbers; the work is done
    while the workers run the other policies' tasks."""
    parts = {
        part
        for claim in paper_claims()
        if claim.scenario == scenario
        for comparison in claim.comparisons
        if comparison.reaches <= metrics.steps
        for part in comparison.parts
        if part[1] == policy and (part[0] != "armse" or metrics.tracked)  # else the judge says why
    }
    if parts and metrics.num_trials >= uncertainty.MIN_INTERVAL_TRIALS:
        parts_of = {part: functools.partial(_part, metrics, part) for part in sorted(parts)}
        uncertainty.estimates(parts_of, metrics.num_trials, seed)


def _part(metrics: TrialMetrics, part: Part, w: NDArray) -> NDArray:
    metric, _, keywords = part
    return getattr(metrics, METRICS[metric])(w, **dict(keywords))


def evaluate(policies_by_scenario: dict[str, Policies], seed: int = 0) -> list[dict[str, Any]]:
    """Every claim whose scenario was run, judged (each scenario's comparisons from one bootstrap)."""
    claims = [claim for claim in paper_claims() if claim.scenario in policies_by_scenario]
    judged: dict[int, list[dict[str, Any]]] = {}
    for scenario, policies in policies_by_scenario.items():
        mine = [i for i, claim in enumerate(claims) if claim.scenario == scenario]
        flat = judge_all([c for i in mine for c in claims[i].comparisons], policies, seed)
        for i in mine:
            judged[i], flat = flat[: len(claims[i].comparisons)], flat[len(claims[i].comparisons) :]
    return [
        {
            "id": claim.id,
            "scenario": claim.scenario,
            "claim": claim.text,
            "verdict": verdicts.combine([j["verdict"] for j in judged[i]]),
            "comparisons": judged[i],
            "paper": claim.paper,
        }
        for i, claim in enumerate(claims)
    ]


def prepare_policy(config: RunConfig, policy: str, metrics: TrialMetrics) -> None:
    """:func:`prepare` for a paper study's run (a :data:`~benchmarks.study.Prepare`)."""
    prepare(paper_key(config.scenario["name"]), policy, metrics, config.seed)


def paper_runs(scenarios: Sequence[str | Scenario], out: Path) -> list[Run]:
    """The paper study (:data:`~benchmarks.harness.PAPER_POLICIES`) on each scenario (a name or
    a :class:`~mimo_radar_env.Scenario`), into ``out/<scenario name>``."""
    return [
        Run(name, scenario, PAPER_POLICIES, Path(out) / name)
        for scenario in scenarios
        for name in [scenario.name if isinstance(scenario, Scenario) else str(scenario)]
    ]


def scorecard(scenarios: Sequence[str | Scenario], out: Path, settings: Settings) -> list[dict[str, Any]]:
    """Run the paper studies of ``scenarios`` into ``out`` (resumably), judge the claims and
    write ``out/claims.md`` and ``out/claims.json``; the judged claims."""
    runs = paper_runs(scenarios, out)
    finished = execute(runs, settings, keep_metrics=True, prepare=prepare_policy).values()
    folders = [f.folder for f in finished]
    results = judge_studies(folders, settings.seed, {f.folder: f.metrics for f in finished})
    write_scorecard(
        results, out, describe_studies(folders), scorecard_title(folders), studies_trials(folders)
    )
    return results


class ClaimsStudy(Study):
    name = "claims"
    keeps_metrics = True  # judge() reads the runs' per-trial metrics
    description = (
        "Evaluate the paper's claims (docs/results-claims.md) on finished 'paper' runs, or run the paper "
        "studies first (into OUT/<scenario>, resumable). Writes OUT/claims.md and OUT/claims.json."
    )
    paper_study = True

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument(
            "runs", nargs="*", help="finished paper-study folders (default: run them into --out)"
        )
        add_scenarios_argument(parser)
        parser.add_argument(
            "--scenario-set",
            choices=sorted(SCENARIO_SETS),
            default=None,
            help="run the paper scenarios of a shipped scenario set (another station layout, "
            "same version) instead of the version's own: "
            + "; ".join(f"{s.name}: {s.summary}" for s in SCENARIO_SETS.values()),
        )

    def runs(self) -> list[Run]:
        if self.args.runs:
            return []
        source: Any = env_version(self.settings.env_version)
        if self.args.scenario_set:
            source = SCENARIO_SETS[self.args.scenario_set]
            if source.version != self.settings.env_version:
                raise BenchError(
                    f"scenario set {source.name!r} is made for env version {source.version}, "
                    f"not {self.settings.env_version}: add --env-version {source.version}"
                )
        names = [source.paper_scenario(n) for n in paper_numbers(self.args.scenarios)]
        return paper_runs(names, self.settings.out)

    def prepare_policy(self, config: RunConfig, policy: str, metrics: TrialMetrics) -> None:
        prepare_policy(config, policy, metrics)

    def judge(self, finished: dict[Hashable, Finished]) -> tuple[list[Path], list[dict[str, Any]]]:
        folders = [Path(r) for r in self.args.runs] or [f.folder for f in finished.values()]
        loaded = {f.folder: f.metrics for f in finished.values()}  # none where folders were given
        return folders, judge_studies(folders, self.settings.seed, loaded)

    def report(self, finished: dict[Hashable, Finished], judged: Any) -> str:
        folders, results = judged
        write_scorecard(
            results,
            self.settings.out,
            describe_studies(folders),
            scorecard_title(folders),
            studies_trials(folders),
        )
        return (self.settings.out / "claims.md").read_text()


def judge_studies(
    folders: Sequence[str | Path],
    seed: int = 0,
    loaded: Mapping[Path, dict[str, TrialMetrics] | None] | None = None,
) -> list[dict[str, Any]]:
    """Every claim judged on finished paper studies (one folder per scenario); ``loaded`` holds
    the per-trial metrics of those already in memory, by folder (the others are read)."""
    studies = {}
    for folder in map(Path, folders):
        check_paper_run(folder)
        name, policies = load_study(folder, (loaded or {}).get(folder))
        if name not in PAPER_KEYS:
            raise BenchError(
                f"{folder} ran scenario {name!r}, not a paper scenario "
                f"({', '.join(PAPER_KEYS)} of any version)"
            )
        if name in studies:
            raise BenchError(f"two of the runs are studies of {name}: give one folder per paper scenario")
        studies[name] = policies
    return evaluate(studies, seed)


def check_paper_run(folder: Path) -> None:
    """Raise :class:`BenchError` unless ``folder`` holds a paper study the claims can be judged
    on: the paper's policies and the trials of an interval (``uncertainty.MIN_INTERVAL_TRIALS``) or
    more (a claim past a shorter run's last step is "not evaluated")."""
    path = folder / "config.json"
    if not path.is_file():
        raise BenchError(f"{folder} holds no finished run (no config.json)")
    try:
        config = json.loads(path.read_text())
        policies, trials = list(config["policies"]), int(config["trials"])
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise BenchError(f"{path} is not a run's configuration ({type(exc).__name__}: {exc})") from None
    missing = [p for p in PAPER_POLICIES if p not in policies]
    if missing:
        raise BenchError(
            f"{folder} ran {', '.join(policies)}; the claims need the paper study's policies "
            f"({', '.join(PAPER_POLICIES)}): run 'mimo-radar-bench paper' or 'claims --out DIR'"
        )
    if trials < uncertainty.MIN_INTERVAL_TRIALS:
        raise BenchError(
            f"{folder} ran {trials} trials; the claims' paired 95 % intervals need "
            f"{uncertainty.MIN_INTERVAL_TRIALS} or more"
        )


#: The fields of a judged claim that a scorecard must hold.
SCORECARD_FIELDS = ("id", "scenario", "claim", "verdict")


def load_scorecard(path: Path) -> list[dict[str, Any]]:
    """A ``claims.json`` scorecard, checked: a list of judged claims with :data:`SCORECARD_FIELDS`
    and known verdicts (:class:`BenchError` naming the file otherwise)."""
    try:
        results = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise BenchError(f"{path} is not a JSON scorecard ({exc})") from None
    if not isinstance(results, list) or not results:
        raise BenchError(f"{path} is not a scorecard: expected a list of judged claims")
    for i, result in enumerate(results):
        missing = [f for f in SCORECARD_FIELDS if not isinstance(result, dict) or f not in result]
        if missing:
            raise BenchError(f"{path}: claim {i} lacks {', '.join(missing)}; is this a claims.json?")
        known = (*verdicts.VERDICTS, verdicts.NOT_EVALUATED)
        if result["verdict"] not in known:
            raise BenchError(
                f"{path}: claim {result['id']} has verdict {result['verdict']!r}; known: {', '.join(known)}"
            )
    return results


def _configs(folders: Sequence[str | Path]) -> list[dict[str, Any]]:
    """The studies' config.json documents."""
    return [json.loads((Path(f) / "config.json").read_text()) for f in folders]


def studies_trials(folders: Sequence[str | Path]) -> int:
    """The trials of the studies judged (the first's: a scorecard judges studies of one size)."""
    return int(_configs(folders)[0]["trials"])


def describe_studies(folders: Sequence[str | Path]) -> str:
    """One line on what the studies ran: scenarios, trials, seed, non-default options, agent
    parameters (from their ``config.json``)."""
    from mimo_radar_env import EnvOptions

    configs = _configs(folders)
    first = configs[0]
    options = EnvOptions(**first["env_options"]).changed()
    names = ", ".join(c["scenario"]["name"] for c in configs)
    text = f"Studies: {names}; {first['trials']} trials, {first['steps']} steps, seed {first['seed']}"
    text += "; env options " + (", ".join(f"{k}={v}" for k, v in options.items()) or "v0's defaults")
    text += f", fusion {first['env_options']['fusion']}"
    if first.get("agent_params"):
        text += f"; agent parameters {json.dumps(first['agent_params'])}"
    return text + "."


def scorecard_title(folders: Sequence[str | Path]) -> str:
    """A title that tells one scorecard from another: the scenarios, the options that differ
    from v0's, the agent parameters and the trials."""
    from mimo_radar_env import EnvOptions

    configs = _configs(folders)
    first = configs[0]
    changed = EnvOptions(**first["env_options"]).changed()
    changed["fusion"] = first["env_options"]["fusion"]
    parts = [", ".join(c["scenario"]["name"] for c in configs)]
    parts.append(", ".join(f"{k}={v}" for k, v in changed.items()))
    if first.get("agent_params"):
        parts.append(
            ", ".join(f"{a}.{k}={v}" for a, p in first["agent_params"].items() for k, v in p.items())
        )
    return f"The paper's claims: {'; '.join(parts)}; {first['trials']} trials"


def write_scorecard(
    results: list[dict[str, Any]],
    out: str | Path,
    about: str = "",
    title: str = "",
    trials: int | None = None,
) -> None:
    """``out/claims.json`` and ``out/claims.md`` (``about``: a line on the studies judged, of
    ``trials`` trials each)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "claims.json").write_text(json.dumps(results, indent=2, allow_nan=False))
    scenarios = sorted({r["scenario"] for r in results})
    title = title or f"The paper's claims ({', '.join(scenarios)})"
    (out / "claims.md").write_text(scorecard_markdown(results, title, about, trials))


def load_study(run_dir: str | Path, metrics: dict[str, TrialMetrics] | None = None) -> tuple[str, Policies]:
    """The paper scenario (``paper-N`` of any version) and the policies of a finished run (their
    per-trial ``metrics`` read from its shards unless given)."""
    run_dir = Path(run_dir)
    config = RunConfig(**json.loads((run_dir / "config.json").read_text()))
    if metrics is None:
        metrics = trial_metrics(config, load_per_trial(run_dir, config))
    return paper_key(config.scenario["name"]), Policies(metrics, config.scenario_object)


#: S1.1: the paper's Best selections (0-based) and their windows (steps).
BEST_WINDOWS = (((0, 380), ((0, 1), (0, 1, 2))), ((590, 1000), ((2, 3), (1, 3, 4))))
#: S1.1 holds when Best selects the paper's super arm in at least this fraction of each window.
BEST_WINDOW_FRACTION = 0.95


def noise_free_best(model: Any) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Best's TX and RX masks (T+1, M), (T+1, N) on the noise-free tracks of a :class:`RadarModel`."""
    from mimo_radar_env.core.superarm import best_super_arm

    weights = model.nominal_channel_weights()
    tx, rx, _ = best_super_arm(weights, model.scenario.tx_per_step, model.scenario.rx_per_step)
    return tx, rx


def best_selection_windows(scenario: Any) -> dict[str, float]:
    """S1.1, exactly: the fraction of steps of each window whose optimal super arm on the
    noise-free track is the one the paper describes."""
    from mimo_radar_env import RadarModel

    tx, rx = noise_free_best(RadarModel.from_scenario(scenario))
    out = {}
    for (a, b), (want_tx, want_rx) in BEST_WINDOWS:
        b = min(b, len(tx) - 1)
        want_t, want_r = np.zeros(tx.shape[1], bool), np.zeros(rx.shape[1], bool)
        want_t[list(want_tx)], want_r[list(want_rx)] = True, True
        hit = np.all(tx[a:b] == want_t, axis=1) & np.all(rx[a:b] == want_r, axis=1)
        out[f"{a}-{b} s"] = float(hit.mean()) if b > a else float("nan")
    return out


def _best_window(window: tuple[int, int]) -> Comparison:
    """S1.1 in one window: the fraction of its steps whose noise-free optimal super arm is the
    paper's, minus :data:`BEST_WINDOW_FRACTION`, claimed ``> 0``; exact (constant over trials)."""
    key = f"{window[0]}-{window[1]} s"

    def statistic(p: Policies, w: NDArray) -> NDArray:
        if "best_windows" not in p.cache:
            p.cache["best_windows"] = best_selection_windows(p.scenario)
        return np.full(np.shape(w)[:-1], p.cache["best_windows"][key] - BEST_WINDOW_FRACTION)

    return Comparison(
        f"fraction of {key} with the paper's selection, minus {BEST_WINDOW_FRACTION}", statistic, +1, ()
    )


def comparison_markdown(scorecards: dict[str, list[dict[str, Any]]], claim_text: bool = True) -> str:
    """One row per claim, one verdict column per scorecard (``{label: results}``), then the
    counts; ``claim_text`` adds the column of what the paper says."""
    labels = list(scorecards)
    by_id: dict[str, dict[str, Any]] = {}
    for label, results in scorecards.items():
        for r in results:
            row = by_id.setdefault(r["id"], {"scenario": r["scenario"], "claim": r["claim"]})
            row[label] = r["verdict"]
    fixed = ["claim", "scenario", *(["the paper says"] if claim_text else [])]
    lines = ["| " + " | ".join(fixed + labels) + " |", "|" + "---|" * (len(fixed) + len(labels))]
    for claim_id, row in by_id.items():
        cells = [claim_id, row["scenario"], *([row["claim"]] if claim_text else [])]
        lines.append("| " + " | ".join(cells + [row.get(label, "—") for label in labels]) + " |")
    counts = {label: verdicts.count(r["verdict"] for r in scorecards[label]) for label in labels}
    blank = "| " * (len(fixed) - 1)
    for verdict in verdicts.VERDICTS:
        lines.append(
            f"| **{verdict}** {blank}| " + " | ".join(str(counts[lb][verdict]) for lb in labels) + " |"
        )
    return "\n".join(lines) + "\n"


def scorecard_markdown(
    results: list[dict[str, Any]], title: str, about: str = "", trials: int | None = None
) -> str:
    lines = [f"# {title}", ""] + ([about, ""] if about else [])
    method = uncertainty.METHOD if trials is None else uncertainty.method_of(trials)
    lines += [f"Verdicts from paired 95 % intervals ({method}).", ""]
    counts = verdicts.count(r["verdict"] for r in results)
    lines += [", ".join(f"{k}: {v}" for k, v in counts.items()), ""]
    lines += [
        "| claim | scenario | verdict | the paper says | measured (A - B, 95 % interval) "
        "| the paper's numbers |",
        "|---|---|---|---|---|---|",
    ]
    for r in results:
        measured = "; ".join(
            f"{c['comparison']}: {c['estimate']:.3g} [{c['ci'][0]:.3g}, {c['ci'][1]:.3g}] {c['verdict']}"
            if "estimate" in c
            else f"{c['comparison']}: not evaluated"
            for c in r["comparisons"]
        )
        paper = "; ".join(
            f"{metric} "
            + ", ".join(
                f"{p} {paper_armse(r['scenario'], p) if metric == 'armse' else np.mean(v):.4g}"
                for p, v in values.items()
            )
            for metric, values in r["paper"].items()
        )
        cells = [r["id"], r["scenario"], f"**{r['verdict']}**", r["claim"], measured, paper or "—"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


class CompareClaims(Command):
    """One row per claim, one verdict column per scorecard."""

    name = "compare-claims"

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument(
            "scorecards",
            nargs="+",
            metavar="LABEL=PATH",
            help="a label and a claims.json written by 'claims' or 'calibrate-layout' (or its folder)",
        )

    def main(self) -> int:
        paths: dict[str, Path] = {}
        for item in self.args.scorecards:
            label, sep, where = item.partition("=")
            path = Path(where) / "claims.json" if Path(where).is_dir() else Path(where)
            if not sep or not label:
                raise BenchError(f"scorecards are given as LABEL=PATH, got {item!r}")
            if label in paths:
                raise BenchError(f"two scorecards are labelled {label!r}; give each its own label")
            if not path.is_file():
                raise BenchError(f"{where} is neither a scorecard (.json) nor a folder holding claims.json")
            paths[label] = path
        scorecards = {label: load_scorecard(path) for label, path in paths.items()}
        print(comparison_markdown(scorecards), end="")
        return 0
