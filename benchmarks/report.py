"""Outputs of a run: summary.json, curves.csv, table.md and the figures (docs/benchmark.md)."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import EnvOptions, metrics

from .harness import HarnessError, RunConfig

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


def summarize(config: RunConfig, totals: dict[str, dict[str, NDArray]]) -> dict[str, Any]:
    """The summary.json document (schema in docs/benchmark.md)."""
    scenario = config.scenario_object
    channels = scenario.num_channels_per_step
    tracked = config.options.tracking
    policies = {}
    for policy, total in totals.items():
        armse_all, per_target = (
            metrics.armse(total["squared_error"], config.trials) if tracked else (None, None)
        )
        policies[policy] = {
            "armse": armse_all,
            "armse_per_target": per_target,
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
    return {
        "scenario": scenario.name,
        "trials": config.trials,
        "steps": config.steps,
        "seed": config.seed,
        "env_options": config.env_options,
        "policies": policies,
    }


def curves(config: RunConfig, totals: dict[str, dict[str, NDArray]]) -> list[dict[str, Any]]:
    """Per-step rows: t, policy, mean SINR (dB), cumulative regret, ASR, RMSE over and per target."""
    scenario = config.scenario_object
    rows = []
    for policy, total in totals.items():
        sinr = metrics.mean_sinr_db_curve(total["expected"], config.trials, scenario.num_channels_per_step)
        regret = metrics.regret_curve(total["optimal"], total["expected"], config.trials)
        rmse = metrics.rmse_curve(total["squared_error"], config.trials)
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
            rows.append(row)
    return rows


def table_markdown(summary: dict[str, Any], num_targets: int) -> str:
    """The paper's Table 2/3/4 layout (ARMSE) plus ASR, final regret and mean SINR."""
    name = summary["scenario"]
    paper_armse = PAPER_ARMSE.get(name, {})
    paper_asr = PAPER_ASR.get(name, {})
    targets = [f"ARMSE T{k + 1} (m)" for k in range(num_targets)] if num_targets > 1 else []
    head = ["policy", "ARMSE (m)", *targets, "ASR (%)", "final regret", "mean SINR (dB)", "wall (s)"]
    if paper_armse:
        head += ["paper ARMSE (m)", "paper ASR (%)"]
    lines = [
        f"Scenario `{name}`, {summary['trials']} trials, {summary['steps']} steps, seed {summary['seed']}, "
        f"fusion `{summary['env_options']['fusion']}`" + _changed_options(summary["env_options"]),
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    for policy, row in summary["policies"].items():
        tracked = row["armse"] is not None
        cells = [policy, f"{row['armse']:.4f}" if tracked else "—"]
        if num_targets > 1:
            cells += [f"{v:.4f}" for v in row["armse_per_target"]] if tracked else ["—"] * num_targets
        cells += [
            f"{100 * row['asr']:.2f}",
            f"{row['final_regret']:.1f}",
            f"{row['mean_sinr_db']:.2f}",
            f"{row['wall_s']:.1f}",
        ]
        if paper_armse:
            ref = paper_armse.get(policy)
            cells.append(f"{np.mean(ref):.4f}" if ref else "—")
            cells.append(f"{paper_asr[policy]:.2f}" if policy in paper_asr else "—")
        lines.append("| " + " | ".join(cells) + " |")
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
    summary = summarize(config, totals)
    (out / "summary.json").write_text(json.dumps(summary, indent=2, allow_nan=False))
    rows = curves(config, totals)
    with open(out / "curves.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    scenario = config.scenario_object
    (out / "table.md").write_text(table_markdown(summary, scenario.num_targets))
    if figures:
        from .plots import plot_all

        plot_all(config, totals, out)
    return summary
