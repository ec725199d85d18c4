"""Figures like the paper's: average SINR, regret and RMSE against time, selection maps, geometry."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import metrics
from mimo_radar_env.rendering import draw_scenario

from .harness import RunConfig, load_first_trial_truth
from .shards import policy_folder


def _figure(width: float = 7.0, height: float = 4.0):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=110)
    FigureCanvasAgg(fig)
    return fig


def plot_all(config: RunConfig, totals: dict[str, dict[str, NDArray]], out: Path) -> list[Path]:
    """Write sinr.png, regret.png, rmse.png, selection_<policy>.png and geometry.png."""
    scenario = config.scenario_object
    t = np.arange(1, config.steps + 1)
    written = []

    fig = _figure()
    ax = fig.add_subplot()
    for policy, total in totals.items():
        curve = metrics.mean_sinr_db_curve(total["expected"], config.trials, scenario.num_channels_per_step)
        ax.plot(t, curve, label=policy, lw=1)
    ax.set(xlabel="time (s)", ylabel="average SINR (dB)", title=f"{scenario.name}: average SINR")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    written.append(_save(fig, out / "sinr.png"))

    fig = _figure()
    ax = fig.add_subplot()
    for policy, total in totals.items():
        ax.plot(
            t, metrics.regret_curve(total["optimal"], total["expected"], config.trials), label=policy, lw=1
        )
    ax.set(xlabel="time (s)", ylabel="cumulative SINR regret", title=f"{scenario.name}: regret (eq13)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    written.append(_save(fig, out / "regret.png"))

    K = scenario.num_targets
    fig = _figure(7.0, 3.0 * K) if config.options.tracking else None
    for k in range(K if fig is not None else 0):
        ax = fig.add_subplot(K, 1, k + 1)
        for policy, total in totals.items():
            ax.plot(t, metrics.rmse_curve(total["squared_error"], config.trials)[:, k], label=policy, lw=1)
        ax.set(xlabel="time (s)", ylabel="RMSE (m)", title=f"{scenario.name}: position RMSE, target {k + 1}")
        ax.set_yscale("log")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    if fig is not None:
        fig.tight_layout()
        written.append(_save(fig, out / "rmse.png"))

    labels = [f"TX{m + 1}" for m in range(scenario.num_tx)] + [f"RX{n + 1}" for n in range(scenario.num_rx)]
    for policy, total in totals.items():
        fig = _figure(7.0, 0.25 * len(labels) + 1.5)
        ax = fig.add_subplot()
        image = ax.imshow(
            (total["selections"] / config.trials).T,
            aspect="auto",
            interpolation="nearest",
            cmap="viridis",
            vmin=0,
            vmax=1,
            extent=(0.5, config.steps + 0.5, len(labels) - 0.5, -0.5),
        )
        ax.set_yticks(range(len(labels)), labels, fontsize=7)
        ax.set(
            xlabel="time (s)", title=f"{scenario.name}: {policy}, fraction of trials selecting each station"
        )
        fig.colorbar(image, ax=ax)
        written.append(_save(fig, out / f"selection_{policy_folder(policy)}.png"))

    fig = _figure(6.0, 6.0)
    draw_scenario(
        fig.add_subplot(),
        scenario,
        true_tracks=load_first_trial_truth(out, config),
        title=f"{scenario.name}: stations and the true tracks of trial 0",
    )
    written.append(_save(fig, out / "geometry.png"))
    return written


def _save(fig, path: Path) -> Path:
    fig.savefig(path)
    return path
