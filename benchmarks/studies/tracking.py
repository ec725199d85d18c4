"""The tracking study: what selecting for tracking costs in SINR and gains in accuracy.

``mimo-radar-bench tracking --out DIR`` runs, on each paper scenario and under both fusions,
the SINR-driven policies beside the tracking-aware ones (``best-tracking``, ``tracking-ucb``
and points of its SINR/tracking trade-off, optionally a PPO trained on the information
reward), with common random numbers, into ``DIR/<scenario>-<fusion>``; then it judges the
targets below on paired differences with their 95 % intervals, writes ``DIR/targets.md`` and
``DIR/targets.json``, draws ``DIR/tradeoff_<scenario>.png`` (final SINR regret against ARMSE,
both fusions) and prints the targets. Runs resume like every run of the harness.

Targets (docs/results-tracking.md):

* ``best-tracking`` has a lower ARMSE than Best and every SINR-driven policy (the paper's
  six, :data:`~benchmarks.harness.PAPER_POLICIES`);
* ``tracking-ucb`` has a lower ARMSE than Best and MG-CRB-CL (its SINR regret stated beside
  MG-CRB-CL's);
* each tracking-aware policy costs at most twice MG-CRB-CL's compute time.

A "lower ARMSE" holds when the paired difference's 95 % interval lies below 0.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from collections.abc import Hashable
from pathlib import Path
from typing import Any

from mimo_radar_env import env_version
from mimo_radar_env.tracking import FUSIONS as FUSION_REGISTRY

from .. import verdicts
from ..errors import BenchError
from ..harness import PAPER_POLICIES
from ..report import format_estimate, paired_difference
from ..settings import add_scenarios_argument, comma_list, paper_numbers
from ..study import Finished, Run, Study

#: The points of tracking-ucb's trade-off (sinr_weight) the study runs besides the default 0.
TRADEOFF_WEIGHTS = (0.25, 0.5, 0.75)
TRACKING_POLICIES = (
    "best",
    "best-tracking",
    "mg-crb-cl",
    "tracking-ucb",
    *(f"tracking-ucb:{w}" for w in TRADEOFF_WEIGHTS),
    "ucb1",
    "epsilon-greedy",
    "fix1",
    "fix2",
    "random",
)
FUSIONS = tuple(FUSION_REGISTRY)
DEFAULT_TRIALS = 200
#: The most a tracking-aware policy may cost, as a multiple of MG-CRB-CL's compute time.
COST_LIMIT = 2.0
TARGETS_FILE = "targets.json"


def study_folder(out: str | Path, scenario: str, fusion: str) -> Path:
    return Path(out) / f"{scenario}-{fusion}"


def ppo_policy(pattern: str, number: int, fusion: str) -> str:
    """``ppo:PATH`` with ``{scenario}`` (1, 2, 3) and ``{fusion}`` filled into ``pattern``."""
    try:
        return "ppo:" + pattern.format(scenario=number, fusion=fusion)
    except (KeyError, IndexError, ValueError) as exc:
        raise BenchError(
            f"--ppo {pattern!r}: a pattern may hold {{scenario}} and {{fusion}} only "
            f"({type(exc).__name__}: {exc})"
        ) from None


def add_fusion_run_arguments(parser: argparse.ArgumentParser) -> None:
    """``--scenarios``, ``--fusions`` and ``--ppo``, which :func:`fusion_runs` reads."""
    add_scenarios_argument(parser)
    parser.add_argument(
        "--fusions",
        default=",".join(FUSIONS),
        help=f"fusions to run (default {','.join(FUSIONS)})",
    )
    parser.add_argument(
        "--ppo",
        default=None,
        metavar="PATTERN",
        help="also run a trained PPO: its model path with {scenario} and {fusion} filled in, e.g. "
        "runs/ppo-info/paper-{scenario}-{fusion}/model.zip",
    )


def chosen_fusions(study: Study, text: str) -> list[str]:
    """``--fusions``' list (``"average,centralized"``), checked; with ``--fusion`` given too,
    refused."""
    if hasattr(study.args, "fusion"):
        raise BenchError(f"the {study.name} study runs each of --fusions; --fusion does not apply")
    fusions = comma_list("--fusions", text)
    if not fusions or not set(fusions) <= set(FUSIONS) or len(set(fusions)) != len(fusions):
        raise BenchError(f"fusions must be among {list(FUSIONS)}, each once, got {text!r}")
    return fusions


def fusion_runs(study: Study, policies: tuple[str, ...]) -> list[Run]:
    """The runs of a study over paper scenarios (``--scenarios``) and fusions (``--fusions``):
    ``policies`` and, with ``--ppo PATTERN``, a trained PPO in each, into
    ``OUT/<scenario>-<fusion>``."""
    args, settings = study.args, study.settings
    fusions = chosen_fusions(study, args.fusions)
    version = env_version(settings.env_version)
    runs = []
    for number in paper_numbers(args.scenarios):
        name = version.paper_scenario(number)
        for fusion in fusions:
            ppo = [ppo_policy(args.ppo, number, fusion)] if args.ppo else []
            options = dataclasses.replace(settings.options, fusion=fusion)
            folder = study_folder(settings.out, name, fusion)
            runs.append(Run((number, fusion), name, (*policies, *ppo), folder, options))
    return runs


class TrackingStudy(Study):
    name = "tracking"
    description = (
        f"Run {', '.join(TRACKING_POLICIES)} on the paper scenarios under both fusions (into "
        "OUT/<scenario>-<fusion>, resumable); judge the targets on paired differences; write "
        "OUT/targets.md, OUT/targets.json and OUT/tradeoff_paper-N.png."
    )
    default_trials = DEFAULT_TRIALS
    paper_study = True

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        add_fusion_run_arguments(parser)

    def runs(self) -> list[Run]:
        return fusion_runs(self, TRACKING_POLICIES)

    def judge(self, finished: dict[Hashable, Finished]) -> list[dict[str, Any]]:
        return judge_targets({key: f.summary for key, f in finished.items()})

    def report(self, finished: dict[Hashable, Finished], judged: list[dict[str, Any]]) -> str:
        summaries = {key: f.summary for key, f in finished.items()}
        path = write_targets(judged, self.settings.out, summaries)
        if self.settings.figures:
            plot_tradeoff(summaries, self.settings.out)
        return path.read_text()


def paired(summary: dict[str, Any], a: str, b: str, metric: str) -> tuple[float, list[float]]:
    """``a - b`` of ``metric`` on the same trials and its 95 % interval, from a summary.json."""
    difference = paired_difference(summary, a, b, metric)
    return difference["estimate"], list(difference["ci"])


def _lower(summary: dict[str, Any], a: str, b: str) -> dict[str, Any]:
    """The target "``a`` has a lower ARMSE than ``b``", judged on the paired difference."""
    estimate, ci = paired(summary, a, b, "armse")
    verdict = verdicts.verdict(ci, -1)
    return {"a": a, "b": b, "difference": estimate, "ci": ci, "verdict": verdict, "holds": verdict == "holds"}


Summaries = dict[tuple[int, str], dict[str, Any]]


def judge_targets(summaries: Summaries) -> list[dict[str, Any]]:
    """Each study's targets (``{(scenario, fusion): summary.json}``): the paired ARMSE
    differences, the regrets and the cost ratios."""
    results = []
    for (number, fusion), summary in summaries.items():
        rows = summary["policies"]
        mg_wall = rows["mg-crb-cl"]["wall_s"]
        ppo = [p for p in rows if p.startswith("ppo:")]
        results.append(
            {
                "scenario": number,
                "fusion": fusion,
                "trials": summary["trials"],
                "best_tracking_lower": [_lower(summary, "best-tracking", p) for p in PAPER_POLICIES],
                "tracking_ucb_lower": [_lower(summary, "tracking-ucb", p) for p in ("best", "mg-crb-cl")],
                "ppo_lower": [_lower(summary, ppo[0], p) for p in ("best", "mg-crb-cl")] if ppo else [],
                "regret": {
                    p: {"value": rows[p]["final_regret"], "ci": rows[p]["ci"]["final_regret"]}
                    for p in ("mg-crb-cl", "tracking-ucb", *ppo)
                },
                "armse": {
                    p: {"value": rows[p]["armse"], "ci": rows[p]["ci"]["armse"]}
                    for p in ("best", "best-tracking", "mg-crb-cl", "tracking-ucb", *ppo)
                },
                "cost": {
                    p: {
                        "ratio": rows[p]["wall_s"] / mg_wall,
                        "holds": rows[p]["wall_s"] / mg_wall <= COST_LIMIT,
                    }
                    for p in ("best-tracking", "tracking-ucb")
                },
            }
        )
    return results


def _verdict(holds: bool) -> str:
    return verdicts.HOLDS if holds else "**fails**"


def _mark(verdict: str) -> str:
    """A target's verdict, in bold unless it holds."""
    return verdict if verdict == verdicts.HOLDS else f"**{verdict}**"


def targets_markdown(results: list[dict[str, Any]]) -> str:
    """The targets as tables, one row per (scenario, fusion)."""
    trials = sorted({r["trials"] for r in results})
    lines = [
        "# Tracking-aware selection: the targets",
        "",
        f"{', '.join(map(str, trials))} trials per study; differences `A - B` in ARMSE (m) paired on the "
        "same trials with their 95 % intervals (bootstrap over trials); a target holds when the interval "
        "lies below 0.",
        "",
        "## best-tracking has a lower ARMSE than every SINR-driven policy",
        "",
        "| scenario | fusion | " + " | ".join(f"best-tracking - {p}" for p in PAPER_POLICIES) + " |",
        "|" + "---|" * (len(PAPER_POLICIES) + 2),
    ]
    for r in results:
        cells = [
            f"{format_estimate(c['difference'], c['ci'], '{:.3f}')} {_mark(c['verdict'])}"
            for c in r["best_tracking_lower"]
        ]
        lines.append(f"| paper-{r['scenario']} | {r['fusion']} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "## tracking-ucb has a lower ARMSE than Best and MG-CRB-CL; its SINR regret beside MG-CRB-CL's",
        "",
        "| scenario | fusion | tracking-ucb - best | tracking-ucb - mg-crb-cl | regret tracking-ucb "
        "| regret mg-crb-cl |",
        "|---|---|---|---|---|---|",
    ]
    for r in results:
        cells = [
            f"{format_estimate(c['difference'], c['ci'], '{:.3f}')} {_mark(c['verdict'])}"
            for c in r["tracking_ucb_lower"]
        ]
        cells += [
            format_estimate(r["regret"][p]["value"], r["regret"][p]["ci"], "{:.0f}")
            for p in ("tracking-ucb", "mg-crb-cl")
        ]
        lines.append(f"| paper-{r['scenario']} | {r['fusion']} | " + " | ".join(cells) + " |")
    if any(r["ppo_lower"] for r in results):
        lines += [
            "",
            "## PPO trained on the information reward (no target; beside the rest)",
            "",
            "| scenario | fusion | ppo - best | ppo - mg-crb-cl | regret ppo |",
            "|---|---|---|---|---|",
        ]
        for r in results:
            if not r["ppo_lower"]:
                continue
            ppo = r["ppo_lower"][0]["a"]
            cells = [f"{format_estimate(c['difference'], c['ci'], '{:.3f}')}" for c in r["ppo_lower"]]
            cells.append(format_estimate(r["regret"][ppo]["value"], r["regret"][ppo]["ci"], "{:.0f}"))
            lines.append(f"| paper-{r['scenario']} | {r['fusion']} | " + " | ".join(cells) + " |")
    lines += [
        "",
        f"## Cost: compute time as a multiple of MG-CRB-CL's (target <= {COST_LIMIT:g})",
        "",
        "| scenario | fusion | best-tracking | tracking-ucb |",
        "|---|---|---|---|",
    ]
    for r in results:
        cells = [
            f"{r['cost'][p]['ratio']:.2f} {_verdict(r['cost'][p]['holds'])}"
            for p in ("best-tracking", "tracking-ucb")
        ]
        lines.append(f"| paper-{r['scenario']} | {r['fusion']} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _same_policy(summary: dict[str, Any], policy: str) -> dict[str, Any]:
    """``policy``'s row of a summary; a PPO's model differs between fusions, so ``ppo:...`` is
    the summary's PPO row."""
    rows = summary["policies"]
    if policy.startswith("ppo:"):
        return next(row for name, row in rows.items() if name.startswith("ppo:"))
    return rows[policy]


def studies_markdown(all_summaries: Summaries) -> str:
    """Per scenario, every policy's ARMSE, bound, final regret and mean SINR under each fusion."""
    lines = ["## The studies", ""]
    for number in sorted({n for n, _ in all_summaries}):
        fusions = [f for n, f in all_summaries if n == number]
        summaries = {f: all_summaries[(number, f)] for f in fusions}
        head = ["policy"]
        for fusion in fusions:
            head += [f"ARMSE, {fusion} (m)", f"bound, {fusion} (m)", f"final regret, {fusion}"]
        head.append(f"mean SINR, {fusions[0]} (dB)")
        lines += [f"### paper-{number}", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for policy in summaries[fusions[0]]["policies"]:
            label = "ppo (information reward)" if policy.startswith("ppo:") else policy
            cells = [label]
            for fusion in fusions:
                row = _same_policy(summaries[fusion], policy)
                cells += [
                    format_estimate(row["armse"], row["ci"]["armse"], "{:.3f}"),
                    format_estimate(row["bound"], row["ci"]["bound"], "{:.3f}"),
                    format_estimate(row["final_regret"], row["ci"]["final_regret"], "{:.0f}"),
                ]
            row = summaries[fusions[0]]["policies"][policy]
            cells.append(format_estimate(row["mean_sinr_db"], row["ci"]["mean_sinr_db"], "{:.2f}"))
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def write_targets(results: list[dict[str, Any]], out: str | Path, summaries: Summaries | None = None) -> Path:
    """``out/targets.json`` and ``out/targets.md`` (with the studies' summary tables when
    their ``summaries`` are given)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / TARGETS_FILE).write_text(json.dumps(results, indent=2, allow_nan=False))
    path = out / "targets.md"
    path.write_text(targets_markdown(results) + ("\n" + studies_markdown(summaries) if summaries else ""))
    return path


def _error_bar(value: float, ci: list[float]) -> list[list[float]]:
    """Matplotlib's [[below], [above]] (every interval contains its value)."""
    return [[value - ci[0]], [ci[1] - value]]


def plot_tradeoff(summaries: Summaries, out: str | Path) -> list[Path]:
    """``tradeoff_paper-N.png``: final SINR regret against ARMSE for every policy, one panel per
    fusion, with 95 % intervals on both axes; tracking-ucb's trade-off points joined by a line."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..plots import palette

    written = []
    for number in sorted({n for n, _ in summaries}):
        fusions = [f for n, f in summaries if n == number]
        fig = Figure(figsize=(6.0 * len(fusions), 4.8), dpi=110)
        FigureCanvasAgg(fig)
        for i, fusion in enumerate(fusions):
            summary = summaries[(number, fusion)]
            ax = fig.add_subplot(1, len(fusions), i + 1)
            curve = []
            colours = palette(len(summary["policies"]))
            for j, (policy, row) in enumerate(summary["policies"].items()):
                x, y = row["final_regret"], row["armse"]
                xerr, yerr = _error_bar(x, row["ci"]["final_regret"]), _error_bar(y, row["ci"]["armse"])
                label = "ppo (information reward)" if policy.startswith("ppo:") else policy
                marker = "s" if policy in ("best-tracking", "tracking-ucb") else "o"
                ax.errorbar(
                    x,
                    y,
                    xerr=xerr,
                    yerr=yerr,
                    fmt=marker,
                    ms=4,
                    capsize=2,
                    lw=0.8,
                    label=label,
                    color=colours[j],
                )
                ax.annotate(
                    label.split(" ")[0], (x, y), fontsize=6, xytext=(3, 3), textcoords="offset points"
                )
                if policy == "tracking-ucb" or policy.startswith("tracking-ucb:"):
                    curve.append((x, y))
            if len(curve) > 1:
                xs, ys = zip(*sorted(curve), strict=True)
                ax.plot(xs, ys, color="0.5", lw=0.8, ls=":", zorder=0)
            ax.set(
                xlabel="final SINR regret (eq13)",
                ylabel="ARMSE (m)",
                title=f"{summary['scenario']}, fusion {fusion}: regret vs ARMSE, 95 % intervals",
            )
            ax.grid(alpha=0.3)
            ax.legend(fontsize=6)
        fig.tight_layout()
        path = Path(out) / f"tradeoff_paper-{number}.png"
        fig.savefig(path)
        written.append(path)
    return written
