"""Outputs of a run: summary.json, curves.csv, table.md and the figures (docs/benchmark.md)."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import EnvOptions, metrics
from mimo_radar_env.envs.options import paper_key

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
PAPER_ASR = {
    "paper-1": {"mg-crb-cl": 45.84, "epsilon-greedy": 14.56, "ucb1": 7.63},
    "paper-2": {"mg-crb-cl": 56.66, "epsilon-greedy": 20.51, "ucb1": 11.45},
    "paper-3": {"mg-crb-cl": 69.08, "epsilon-greedy": 31.56, "ucb1": 17.94},
}


def summarize(
    config: RunConfig,
    totals: dict[str, dict[str, NDArray]],
    per_trial: dict[str, dict[str, NDArray]] | None = None,
) -> dict[str, Any]:
    """The summary.json document (schema in docs/benchmark.md); with ``per_trial`` (the run's
    per-trial arrays) every metric gets its 95 % interval and every pair of policies its paired
    differences."""
    scenario = config.scenario_object
    channels = scenario.num_channels_per_step
    tracked = config.options.tracking
    policies = {}
    for policy, total in totals.items():
        armse_all, per_target = (
            metrics.armse(total["squared_error"], config.trials) if tracked else (None, None)
        )
        bound_all, bound_per_target = (
            metrics.armse(total["bound_squared"], config.trials)
            if tracked and "bound_squared" in total
            else (None, None)
        )
        policies[policy] = {
            "armse": armse_all,
            "armse_per_target": per_target,
            "bound": bound_all,
            "bound_per_target": bound_per_target,
            "armse_over_bound": armse_all / bound_all if bound_all else None,
            "asr": metrics.asr(total["matches"], config.trials),
            "final_regret": float(
                metrics.regret_curve(total["optimal"], total["expected"], config.trials)[-1]
            ),
            "mean_sinr_db": metrics.mean_sinr_db(total["expected"], config.trials, channels),
            "wall_s": float(total["wall_s"]),
        }
    for policy, row in policies.items():
        for key, value in row.items():
            values = value if isinstance(value, list) else [value]
            if any(v is not None and not np.isfinite(v) for v in values):
                raise HarnessError(
                    f"policy {policy!r}: {key} is not a finite number ({value}); a non-finite mean SINR "
                    "or error means the scenario's SINR or tracks overflowed: check its field values"
                )
    summary = {
        "scenario": scenario.name,
        "trials": config.trials,
        "steps": config.steps,
        "seed": config.seed,
        "env_options": config.env_options,
        "policies": policies,
    }
    if per_trial is not None and config.trials >= 2:  # an interval needs two trials or more
        trial_metrics = {p: uncertainty.TrialMetrics(per_trial[p], channels) for p in totals}
        for policy, row in policies.items():
            row["ci"] = uncertainty.policy_intervals(trial_metrics[policy], config.seed)
        summary["uncertainty"] = uncertainty.METHOD
        summary["paired_differences"] = uncertainty.paired_differences(trial_metrics, config.seed)
    return summary


def curves(config: RunConfig, totals: dict[str, dict[str, NDArray]]) -> list[dict[str, Any]]:
    """Per-step rows: t, policy, mean SINR (dB), cumulative regret, ASR, RMSE over and per target."""
    scenario = config.scenario_object
    rows = []
    for policy, total in totals.items():
        sinr = metrics.mean_sinr_db_curve(total["expected"], config.trials, scenario.num_channels_per_step)
        regret = metrics.regret_curve(total["optimal"], total["expected"], config.trials)
        rmse = metrics.rmse_curve(total["squared_error"], config.trials)
        bound = metrics.rmse_curve(total["bound_squared"], config.trials)
        match = total["matches"] / config.trials
        for t in range(config.steps):
            row = {
                "t": t + 1,
                "policy": policy,
                "mean_sinr_db": sinr[t],
                "cumulative_regret": regret[t],
                "asr": match[t],
                "rmse": rmse[t].mean(),
            }
            row.update({f"rmse_target{k + 1}": rmse[t, k] for k in range(rmse.shape[1])})
            row["bound"] = bound[t].mean()
            row.update({f"bound_target{k + 1}": bound[t, k] for k in range(bound.shape[1])})
            rows.append(row)
    return rows


def table_markdown(summary: dict[str, Any], num_targets: int) -> str:
    """The paper's Table 2/3/4 layout (ARMSE) plus the bound (the time-averaged posterior
    Cramer-Rao bound of the selections made) and ARMSE / bound, ASR, final regret and mean SINR."""
    name = summary["scenario"]
    paper_armse = PAPER_ARMSE.get(paper_key(name), {})
    paper_asr = PAPER_ASR.get(paper_key(name), {})
    targets = [f"ARMSE T{k + 1} (m)" for k in range(num_targets)] if num_targets > 1 else []
    head = ["policy", "ARMSE (m)", *targets, "bound (m)", "ARMSE / bound"]
    head += ["ASR (%)", "final regret", "mean SINR (dB)", "wall (s)"]
    if paper_armse:
        head += ["paper ARMSE (m)", "paper ASR (%)"]
    lines = [
        f"# {name}: {', '.join(summary['policies'])}",
        "",
        f"Scenario `{name}`, {summary['trials']} trials, {summary['steps']} steps, seed {summary['seed']}, "
        f"fusion `{summary['env_options']['fusion']}`" + _changed_options(summary["env_options"]),
        "",
        *(
            [f"Each cell: the value [its 95 % interval] ({summary['uncertainty']}).", ""]
            if "uncertainty" in summary
            else []
        ),
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    for policy, row in summary["policies"].items():
        tracked = row["armse"] is not None
        ci = row.get("ci", {})
        cells = [policy, _with_ci(row["armse"], ci.get("armse"), "{:.3f}") if tracked else "—"]
        if num_targets > 1:
            per_target = ci.get("armse_per_target", [None] * num_targets)
            cells += (
                [_with_ci(v, c, "{:.3f}") for v, c in zip(row["armse_per_target"], per_target, strict=True)]
                if tracked
                else ["—"] * num_targets
            )
        bounded = row.get("bound") is not None
        cells += [
            _with_ci(row["bound"], ci.get("bound"), "{:.3f}") if bounded else "—",
            _with_ci(row["armse_over_bound"], ci.get("armse_over_bound"), "{:.2f}") if bounded else "—",
            _with_ci(row["asr"], ci.get("asr"), "{:.2f}", scale=100),
            _with_ci(row["final_regret"], ci.get("final_regret"), "{:.1f}"),
            _with_ci(row["mean_sinr_db"], ci.get("mean_sinr_db"), "{:.2f}"),
            f"{row['wall_s']:.1f}",
        ]
        if paper_armse:
            ref = paper_armse.get(policy)
            cells.append(f"{np.mean(ref):.4f}" if ref else "—")
            cells.append(f"{paper_asr[policy]:.2f}" if policy in paper_asr else "—")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _number(value: float, fmt: str) -> str:
    text = fmt.format(value)
    return text[1:] if text.startswith("-") and float(text) == 0 else text  # no "-0.0"


def _with_ci(value: float, ci: list[float] | None, fmt: str, scale: float = 1.0) -> str:
    text = _number(scale * value, fmt)
    if ci is None:
        return text
    return f"{text} [{_number(scale * ci[0], fmt)}, {_number(scale * ci[1], fmt)}]"


def paired_markdown(summary: dict[str, Any]) -> str:
    """Paired differences ``A - B`` on the same trials, with their 95 % intervals."""
    pairs = summary.get("paired_differences")
    if not pairs:
        return ""
    names = [("armse", "Δ ARMSE (m)", "{:.3f}", 1), ("asr", "Δ ASR (pp)", "{:.2f}", 100)]
    names += [
        ("final_regret", "Δ final regret", "{:.1f}", 1),
        ("mean_sinr_db", "Δ mean SINR (dB)", "{:.2f}", 1),
    ]
    present = [n for n in names if any(n[0] in d for d in pairs.values())]
    lines = [
        "",
        "Paired differences `A - B` on the same trials, with their 95 % intervals "
        f"({summary['uncertainty']}); an interval that excludes 0 is a significant difference.",
        "",
        "| A - B | " + " | ".join(label for _, label, _, _ in present) + " |",
        "|" + "---|" * (len(present) + 1),
    ]
    for pair, values in pairs.items():
        cells = [
            _with_ci(values[key]["estimate"], values[key]["ci"], fmt, scale) if key in values else "—"
            for key, _, fmt, scale in present
        ]
        lines.append(f"| {pair} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _changed_options(options: dict[str, Any]) -> str:
    """``, filter_noise `estimated`...`` for the options (besides fusion) that differ from the defaults."""
    changed = EnvOptions(**options).changed()
    changed.pop("fusion", None)
    return "".join(f", {key} `{value}`" for key, value in changed.items())


def write_outputs(
    config: RunConfig, totals: dict[str, dict[str, NDArray]], out: str | Path, figures: bool = True
) -> dict[str, Any]:
    """Write summary.json, curves.csv, table.md and (optionally) the PNG figures into ``out``."""
    out = Path(out)
    summary = summarize(config, totals, load_per_trial(out, config))
    (out / "summary.json").write_text(json.dumps(summary, indent=2, allow_nan=False))
    rows = curves(config, totals)
    with open(out / "curves.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    scenario = config.scenario_object
    (out / "table.md").write_text(table_markdown(summary, scenario.num_targets) + paired_markdown(summary))
    if figures:
        from .plots import plot_all

        plot_all(config, totals, out)
    return summary
