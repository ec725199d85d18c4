"""Outputs of a run: summary.json, curves.csv, table.md and the figures (docs/benchmark.md)."""

from __future__ import annotations

import csv
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

import agents
from benchmarks.metrics import EXTRA_METRICS, TrialMetrics
from mimo_radar_env import EnvOptions
from mimo_radar_env.envs.versions import paper_key

from . import uncertainty
from .harness import HarnessError, RunConfig, load_per_trial

#: The paper's ARMSE (m) per scenario and target, and ASR (%); its layout is unknown.
PAPER_ARMSE = {
    "paper-1": {
        "best": [0.9863],
        "mg-crb-cl": [1.1030],
        "ucb1": [1.3633],
        "epsilon-greedy": [1.2353],
        "fix1": [1.1284],
        "fix2": [1.9089],
    },
    "paper-2": {
        "best": [1.1242],
        "mg-crb-cl": [1.1721],
        "ucb1": [1.3159],
        "epsilon-greedy": [1.2230],
        "fix1": [1.1835],
        "fix2": [1.7010],
    },
    "paper-3": {
        "best": [0.7539, 0.7543],
        "mg-crb-cl": [0.7649, 0.7527],
        "ucb1": [0.9329, 0.7145],
        "epsilon-greedy": [0.7873, 0.7478],
        "fix1": [0.8575, 1.1237],
        "fix2": [1.2724, 1.5643],
    },
}
#: Table 4's "ARMSE of targets" column (Scenario 3, two targets), as the paper prints it.
PAPER_ARMSE_OF_TARGETS = {
    "paper-3": {
        "best": 0.7541,
        "mg-crb-cl": 0.7588,
        "ucb1": 0.8237,
        "epsilon-greedy": 0.7675,
        "fix1": 0.9906,
        "fix2": 1.4184,
    }
}


def paper_armse(scenario: str, policy: str) -> float | None:
    """The paper's ARMSE over targets of ``policy`` in paper scenario ``scenario`` (``paper-N``),
    as its tables print it (None where it reports none)."""
    values = PAPER_ARMSE.get(scenario, {}).get(policy)
    if values is None:
        return None
    return values[0] if len(values) == 1 else PAPER_ARMSE_OF_TARGETS[scenario][policy]


PAPER_ASR = {
    "paper-1": {"mg-crb-cl": 45.84, "epsilon-greedy": 14.56, "ucb1": 7.63},
    "paper-2": {"mg-crb-cl": 56.66, "epsilon-greedy": 20.51, "ucb1": 11.45},
    "paper-3": {"mg-crb-cl": 69.08, "epsilon-greedy": 31.56, "ucb1": 17.94},
}


def trial_metrics(config: RunConfig, per_trial: dict[str, dict[str, NDArray]]) -> dict[str, TrialMetrics]:
    """Every policy's :class:`~benchmarks.metrics.TrialMetrics`: the one source of every
    number the run reports."""
    return {policy: policy_metrics(config, per_trial[policy]) for policy in config.policies}


def policy_metrics(config: RunConfig, joined: dict[str, NDArray]) -> TrialMetrics:
    """One policy's :class:`~benchmarks.metrics.TrialMetrics` from its joined shard fields."""
    return TrialMetrics(joined, config.scenario_object.num_channels_per_step)


#: The table's value keys of a summary row, in order; each also has its ``ci`` and ``method``.
VALUE_KEYS = ("armse", "armse_per_target", "bound", "bound_per_target", "armse_over_bound")
VALUE_KEYS += ("asr", "final_regret", "mean_sinr_db")


def summarize(
    config: RunConfig,
    per_trial: dict[str, dict[str, NDArray]],
    metrics: dict[str, TrialMetrics] | None = None,
    estimated: Mapping[str, dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """The summary.json document (schema in docs/benchmark.md): each policy's metrics with
    their 95 % intervals and the method of each (``ci``, ``method``), its compute time, and
    every pair of policies' paired differences. ``estimated`` holds policies'
    :func:`uncertainty.policy_estimates` computed already (as the run went)."""
    metrics = metrics or trial_metrics(config, per_trial)
    estimated = estimated or {}
    policies = {}
    for policy, m in metrics.items():
        estimates = estimated[policy] if policy in estimated else uncertainty.policy_estimates(m, config.seed)
        row: dict[str, Any] = {key: None for key in VALUE_KEYS}
        ci: dict[str, Any] = {}
        method: dict[str, Any] = {}
        for key, value in estimates.items():
            parts = value if isinstance(value, list) else [value]
            for part in parts:
                if not np.isfinite(part["estimate"]):
                    raise HarnessError(
                        f"policy {policy!r}: {key} is not a finite number ({part['estimate']}); a "
                        "non-finite mean SINR or error means the scenario's SINR or tracks overflowed: "
                        "check its field values"
                    )
            row[key] = [p["estimate"] for p in value] if isinstance(value, list) else value["estimate"]
            ci[key] = [p["ci"] for p in value] if isinstance(value, list) else value["ci"]
            method[key] = [p["method"] for p in value] if isinstance(value, list) else value["method"]
        row["wall_s"] = float(per_trial[policy]["wall_s"])
        row["tracker_repairs"] = int(per_trial[policy]["tracker_repairs"])
        if config.trials >= uncertainty.MIN_INTERVAL_TRIALS:
            row["ci"], row["method"] = ci, method
        policies[policy] = row
    summary = {
        "scenario": config.scenario["name"],
        "trials": config.trials,
        "steps": config.steps,
        "seed": config.seed,
        "env_options": config.env_options,
        "agent_params": config.agent_params,
        "policies": policies,
    }
    if config.trials >= uncertainty.MIN_INTERVAL_TRIALS:
        summary["uncertainty"] = uncertainty.method_of(config.trials)
        summary["paired_differences"] = uncertainty.paired_differences(metrics, config.seed)
    return summary


def curves(config: RunConfig, metrics: dict[str, TrialMetrics]) -> list[dict[str, Any]]:
    """Per-step rows: t, policy, mean SINR (dB), cumulative regret, ASR, RMSE and bound over and
    per target (NaN without a tracker), all at equal trial weights."""
    rows = []
    for policy, m in metrics.items():
        w = m.equal()
        sinr, regret, match = m.sinr_db_curve(w), m.regret_curve(w), m.asr_curve(w)
        nan = np.full((config.steps, m.num_targets), np.nan)
        rmse = np.stack([m.rmse_curve(w, k) for k in range(m.num_targets)], axis=1) if m.tracked else nan
        bound = np.stack([m.bound_curve(w, k) for k in range(m.num_targets)], axis=1) if m.bounded else nan
        for t in range(config.steps):
            row = {
                "t": t + 1,
                "policy": policy,
                "mean_sinr_db": sinr[t],
                "cumulative_regret": regret[t],
                "asr": match[t],
                "rmse": rmse[t].mean(),
            }
            row.update({f"rmse_target{k + 1}": rmse[t, k] for k in range(m.num_targets)})
            row["bound"] = bound[t].mean()
            row.update({f"bound_target{k + 1}": bound[t, k] for k in range(m.num_targets)})
            rows.append(row)
    return rows


#: The paper's horizon (steps): its ARMSE and ASR are of whole 1000-step episodes.
PAPER_HORIZON = 1000
#: What every table's columns are, in one line (docs/benchmark.md, "Outputs", says more).
LEGEND = (
    "ARMSE: the position RMSE averaged over the steps and targets (m); bound: the same average of "
    "the posterior Cramer-Rao bound of the selections made (m); ASR: the share of steps on the "
    "optimal super arm (eq33, %); final regret: the expected SINR reward lost to the optimal super "
    "arm, summed over the steps (eq13); mean SINR of the probed channels (dB)."
)
#: How a cell marks its interval's method (BCa is unmarked).
METHOD_MARKS = {
    "percentile": "†",
    "percentile, extended to the value": "†",
    "constant over trials": "‡",
    "bias-corrected percentile": "§",
    "bias-corrected percentile, extended to the value": "§",
    "bootstrap-t": "¶",
    "bootstrap-t, extended to the value": "¶",
}


def method_legend(trials: int) -> str:
    """What the marks of a table of ``trials`` trials mean (:data:`METHOD_MARKS`)."""
    marks = ["† a percentile interval"]
    if trials < uncertainty.FEW_TRIALS:
        marks.append(
            "§ a bias-corrected percentile interval (a root of a mean over fewer than "
            f"{uncertainty.FEW_TRIALS} trials, which is biased: ARMSE, the bound)"
        )
        marks.append(
            f"¶ a bootstrap-t interval (a mean over fewer than {uncertainty.FEW_TRIALS} trials: ASR, "
            "final regret; mean SINR, whose dB are those of its mean's interval; Δ mean SINR, with "
            "the delta method's standard errors)"
        )
    marks.append("‡ constant over trials (the interval is the value)")
    return f"Marks: {', '.join(marks)}; unmarked: BCa."


METHOD_LEGEND = method_legend(uncertainty.FEW_TRIALS)


def _number(value: float, fmt: str) -> str:
    text = fmt.format(value)
    return text[1:] if text.startswith("-") and float(text) == 0 else text  # no "-0.0"


def format_estimate(
    value: float | None, ci: list[float] | None, fmt: str, scale: float = 1.0, method: str | None = None
) -> str:
    """``value [low, high]`` with the interval's method mark; ``—`` for a missing value."""
    if value is None:
        return "—"
    text = _number(scale * value, fmt)
    if ci is None:
        return text
    mark = METHOD_MARKS.get(method or "", "")
    return f"{text} [{_number(scale * ci[0], fmt)}, {_number(scale * ci[1], fmt)}]{mark}"


def format_cell(
    row: dict[str, Any], key: str, fmt: str, scale: float = 1.0, target: int | None = None
) -> str:
    """A summary row's ``key`` (of one target) with its interval and method mark."""
    value, ci, method = row.get(key), row.get("ci", {}).get(key), row.get("method", {}).get(key)
    if target is not None and value is not None:
        value = value[target]
        ci = ci[target] if ci is not None else None
        method = method[target] if method is not None else None
    return format_estimate(value, ci, fmt, scale, method)


def paper_study_parameters(scenario: str) -> dict[str, dict[str, Any]]:
    """The agent parameters of the paper study of the env version ``scenario`` belongs to: a row
    stands beside the paper's numbers only with those (v1's MG-CRB-CL is BPSO's standard rule)."""
    from mimo_radar_env.envs.versions import shipped_version

    from .settings import paper_study_params

    version = shipped_version(scenario)
    return {} if version is None else paper_study_params(version)


def comparable_to_the_paper(summary: dict[str, Any]) -> bool:
    """Whether the paper's numbers belong beside a run's: one of its scenarios, its horizon (and,
    row by row, its policy: :func:`paper_study_parameters`)."""
    return paper_key(summary["scenario"]) in PAPER_ARMSE and summary["steps"] == PAPER_HORIZON


def table_markdown(summary: dict[str, Any], num_targets: int, intervals: str = "full") -> str:
    """The paper's Table 2/3/4 layout (ARMSE) plus the bound (the time-averaged posterior
    Cramer-Rao bound of the selections made) and ARMSE / bound, ASR, final regret and mean SINR,
    with the paper's numbers when the run is comparable (:func:`comparable_to_the_paper`).
    ``intervals`` ``"full"`` says how the intervals are computed (table.md), ``"short"`` points
    there (the terminal)."""
    name = summary["scenario"]
    paper = comparable_to_the_paper(summary)
    papers_params = paper_study_parameters(name) if paper else {}
    paper_asr = PAPER_ASR.get(paper_key(name), {})
    targets = [f"ARMSE T{k + 1} (m)" for k in range(num_targets)] if num_targets > 1 else []
    head = ["policy", "ARMSE (m)", *targets, "bound (m)", "ARMSE / bound"]
    head += ["ASR (%)", "final regret", "mean SINR (dB)", *EXTRA_METRICS, "wall (s)"]
    if paper:
        head += ["paper ARMSE (m)", "paper ASR (%)"]
    how = "(how: table.md)" if intervals != "full" else f"({summary.get('uncertainty')})"
    how = f"Each cell: the value [its 95 % interval] {how}. {method_legend(summary['trials'])}"
    lines = [
        f"# {name}, fusion {summary['env_options']['fusion']}: {', '.join(summary['policies'])}",
        "",
        f"Scenario `{name}`, {summary['trials']} trials, {summary['steps']} steps, seed {summary['seed']}, "
        f"fusion `{summary['env_options']['fusion']}`" + _changed_options(summary["env_options"]),
        "",
        LEGEND,
        "",
        *([how, ""] if "uncertainty" in summary else [uncertainty.NO_INTERVALS, ""]),
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    for policy, row in summary["policies"].items():
        cells = [
            policy_label(policy, summary.get("agent_params", {}).get(policy)),
            format_cell(row, "armse", "{:.3f}"),
        ]
        if num_targets > 1:
            cells += [format_cell(row, "armse_per_target", "{:.3f}", target=k) for k in range(num_targets)]
        cells += [
            format_cell(row, "bound", "{:.3f}"),
            format_cell(row, "armse_over_bound", "{:.2f}"),
            format_cell(row, "asr", "{:.2f}", scale=100),
            format_cell(row, "final_regret", "{:.1f}"),
            format_cell(row, "mean_sinr_db", "{:.2f}"),
            *(format_cell(row, extra, "{:.4g}") for extra in EXTRA_METRICS),
            f"{row['wall_s']:.1f}",
        ]
        if paper and summary.get("agent_params", {}).get(policy, {}) == papers_params.get(policy, {}):
            ref = paper_armse(paper_key(name), policy)
            cells.append(f"{ref:.4f}" if ref is not None else "—")
            cells.append(f"{paper_asr[policy]:.2f}" if policy in paper_asr else "—")
        elif paper:  # the paper's policy under another reading of its parameters: not comparable
            cells += ["—", "—"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def format_judged(judged: dict[str, Any], fmt: str, scale: float = 1.0) -> str:
    """An ``{"estimate", "ci", "method"}`` (a paired difference) with its interval and mark."""
    return format_estimate(judged["estimate"], judged["ci"], fmt, scale, judged["method"])


def paired_difference(summary: dict[str, Any], a: str, b: str, metric: str) -> dict[str, Any]:
    """``a - b`` of ``metric`` on the same trials (``estimate``, ``ci``, ``method``) from a
    summary.json's paired differences, whichever order they were stored in."""
    pairs = summary["paired_differences"]
    if f"{a} - {b}" in pairs:
        return dict(pairs[f"{a} - {b}"][metric])
    d = pairs[f"{b} - {a}"][metric]
    return {"estimate": -d["estimate"], "ci": [-d["ci"][1], -d["ci"][0]], "method": d.get("method")}


def paired_markdown(summary: dict[str, Any], reference: str | None = None) -> str:
    """Paired differences ``A - B`` on the same trials, with their 95 % intervals: those of the
    ``reference`` policy against each other (``reference - B``), or every pair (None)."""
    pairs = summary.get("paired_differences")
    if not pairs:
        return ""
    if reference is not None:
        others = [p for p in summary["policies"] if p != reference]
        pairs = {f"{reference} - {b}": _pair(summary, reference, b) for b in others}
    names = [("armse", "Δ ARMSE (m)", "{:.3f}", 1), ("asr", "Δ ASR (pp)", "{:.2f}", 100)]
    names += [
        ("final_regret", "Δ final regret", "{:.1f}", 1),
        ("mean_sinr_db", "Δ mean SINR (dB)", "{:.2f}", 1),
    ]
    present = [n for n in names if any(n[0] in d for d in pairs.values())]
    which = "every pair" if reference is None else f"{reference} against each other policy"
    lines = [
        "",
        f"Paired differences `A - B` on the same trials ({which}), with their 95 % intervals as "
        "above; an interval that excludes 0 is a significant difference.",
        "",
        "| A - B | " + " | ".join(label for _, label, _, _ in present) + " |",
        "|" + "---|" * (len(present) + 1),
    ]
    for pair, values in pairs.items():
        cells = [
            format_judged(values[key], fmt, scale) if key in values else "—" for key, _, fmt, scale in present
        ]
        lines.append(f"| {pair} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def policy_label(policy: str, params: dict[str, Any] | None = None) -> str:
    """A table's name of a policy: its entry with every parameter the run gives it (``mg-crb-cl
    (solver_params.rule=set)``), so that a name means one thing in every table; a trained model by
    its folder (``ppo (ppo-paper1)``), not its whole path."""
    name, sep, argument = policy.partition(":")
    label = policy
    if sep and name in agents.learned_agents():
        label = f"{name} ({Path(argument).parent.name or Path(argument).name})"
    flat = _flatten(params or {})
    return f"{label} ({', '.join(f'{k}={v}' for k, v in flat.items())})" if flat else label


def _flatten(params: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in params.items():
        if isinstance(value, dict):
            out |= _flatten(value, f"{prefix}{key}.")
        else:
            out[f"{prefix}{key}"] = value
    return out


def _pair(summary: dict[str, Any], a: str, b: str) -> dict[str, Any]:
    """Every metric's ``a - b`` (:func:`paired_difference`)."""
    stored = summary["paired_differences"].get(f"{a} - {b}") or summary["paired_differences"][f"{b} - {a}"]
    return {metric: paired_difference(summary, a, b, metric) for metric in stored}


def outputs_line(out: Path, figures: bool) -> str:
    """The last line a run prints: where its files are."""
    files = ["table.md", "summary.json", "curves.csv"]
    pngs = sorted(p.name for p in out.glob("*.png")) if figures else []
    return f"outputs in {out}: " + ", ".join(files + ([f"{len(pngs)} figures (*.png)"] if pngs else []))


def _changed_options(options: dict[str, Any]) -> str:
    """``, filter_noise `estimated`...`` for the options (besides fusion) that differ from the defaults."""
    changed = EnvOptions(**options).changed()
    changed.pop("fusion", None)
    return "".join(f", {key} `{value}`" for key, value in changed.items())


def write_outputs(
    config: RunConfig,
    per_trial: dict[str, dict[str, NDArray]] | None,
    out: str | Path,
    figures: bool = True,
    pairs: str = "reference",
    metrics: dict[str, TrialMetrics] | None = None,
    estimated: Mapping[str, dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """Write summary.json, curves.csv, table.md and (optionally) the PNG figures into ``out``,
    from the run's per-trial arrays (read from ``out`` when ``per_trial`` is None) and their
    :func:`trial_metrics` (computed from them when ``metrics`` is None; ``estimated`` as in
    :func:`summarize`). table.md's
    paired differences are the first policy's against each other (``pairs`` ``"reference"``) or
    every pair (``"all"``); summary.json holds every pair."""
    out = Path(out)
    per_trial = per_trial if per_trial is not None else load_per_trial(out, config)
    metrics = metrics if metrics is not None else trial_metrics(config, per_trial)
    summary = summarize(config, per_trial, metrics, estimated)
    (out / "summary.json").write_text(json.dumps(summary, indent=2, allow_nan=False))
    rows = curves(config, metrics)
    with open(out / "curves.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    scenario = config.scenario_object
    reference = config.policies[0] if pairs == "reference" else None
    (out / "table.md").write_text(
        table_markdown(summary, scenario.num_targets) + paired_markdown(summary, reference)
    )
    if figures:
        from .plots import plot_all

        plot_all(config, per_trial, metrics, out)
    return summary
