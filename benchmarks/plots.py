"""Figures like the paper's: average SINR, regret and RMSE against time, selection maps, geometry."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from benchmarks.metrics import TrialMetrics
from mimo_radar_env.rendering import draw_scenario

from . import uncertainty
from .harness import RunConfig
from .shards import TRUTH_FIELD, policy_folder


def _figure(width: float = 7.0, height: float = 4.0):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=110)
    FigureCanvasAgg(fig)
    return fig


def palette(count: int) -> list[tuple[float, float, float]]:
    """``count`` distinct colours: matplotlib's tab10, or tab20's dark shades then its light
    ones beyond ten (so no two policies of a figure share a colour up to twenty)."""
    from matplotlib import colormaps

    if count <= 10:
        return list(colormaps["tab10"].colors[:count])
    pairs = colormaps["tab20"].colors
    return [pairs[2 * (i % 10) + i // 10 % 2] for i in range(count)]


def short_label(policy: str, width: int = 28) -> str:
    """A legend label: the policy, its middle elided when longer than ``width``."""
    return policy if len(policy) <= width else f"{policy[:10]}...{policy[-(width - 13) :]}"


def plot_all(
    config: RunConfig, per_trial: dict[str, dict[str, NDArray]], metrics: dict[str, TrialMetrics], out: Path
) -> list[Path]:
    """Write sinr.png, regret.png, rmse.png (each curve with its 95 % band over trials),
    selection_<policy>.png and geometry.png; every curve is a :class:`TrialMetrics` curve at equal
    weights, its band the same curve's bootstrap."""
    scenario = config.scenario_object
    written = _curve_figures(config, metrics, out)
    if config.options.tracking:
        written.append(_rmse_figure(config, metrics, out))
    written += _selection_figures(config, per_trial, metrics, out)
    fig = _figure(6.0, 6.0)
    draw_scenario(
        fig.add_subplot(),
        scenario,
        true_tracks=per_trial[config.policies[0]][TRUTH_FIELD],
        title=f"{scenario.name}: stations and the true tracks of trial 0",
    )
    written.append(_save(fig, out / "geometry.png"))
    return written


def _draw(ax: Any, config: RunConfig, curve: Any, m: TrialMetrics) -> Any:
    """A curve at equal weights, with its 95 % band over the trials (bootstrap)."""
    t = np.arange(1, config.steps + 1)
    line = ax.plot(t, curve(m.equal()), lw=1)[0]
    low, high = uncertainty.band(curve, config.trials, config.seed)
    ax.fill_between(t, low, high, color=line.get_color(), alpha=0.2, lw=0)
    return line


def _curve_figures(config: RunConfig, metrics: dict[str, TrialMetrics], out: Path) -> list[Path]:
    """sinr.png and regret.png: every policy's curve with its band."""
    written = []
    for name, curve_of, ylabel, title in (
        ("sinr", "sinr_db_curve", "average SINR (dB)", "average SINR, 95 % bands"),
        ("regret", "regret_curve", "cumulative SINR regret", "regret (eq13), 95 % bands"),
    ):
        fig = _figure()
        ax = fig.add_subplot()
        ax.set_prop_cycle(color=palette(len(metrics)))
        for policy, m in metrics.items():
            _draw(ax, config, getattr(m, curve_of), m).set_label(short_label(policy))
        ax.set(xlabel="time (s)", ylabel=ylabel, title=f"{config.scenario_object.name}: {title}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        written.append(_save(fig, out / f"{name}.png"))
    return written


def _rmse_figure(config: RunConfig, metrics: dict[str, TrialMetrics], out: Path) -> Path:
    """rmse.png: each target's RMSE curves with their bands, and the bound of each policy's own
    selections (dashed)."""
    scenario = config.scenario_object
    K = scenario.num_targets
    t = np.arange(1, config.steps + 1)
    fig = _figure(7.0, 3.0 * K)
    for k in range(K):
        ax = fig.add_subplot(K, 1, k + 1)
        ax.set_prop_cycle(color=palette(len(metrics)))
        for policy, m in metrics.items():
            line = _draw(ax, config, lambda w, m=m, k=k: m.rmse_curve(w, k), m)
            line.set_label(short_label(policy))
            if m.bounded:  # the floor the policy's own selections allow
                ax.plot(t, m.bound_curve(m.equal(), k), lw=0.8, ls="--", color=line.get_color())
        ax.set(
            xlabel="time (s)",
            ylabel="RMSE (m)",
            title=f"{scenario.name}, target {k + 1}: RMSE (95 % bands), bound (dashed)",
        )
        ax.set_yscale("log")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, out / "rmse.png")


def _selection_figures(
    config: RunConfig, per_trial: dict[str, dict[str, NDArray]], metrics: dict[str, TrialMetrics], out: Path
) -> list[Path]:
    """selection_<policy>.png: the fraction of trials selecting each station at each step."""
    scenario = config.scenario_object
    labels = [f"TX{m + 1}" for m in range(scenario.num_tx)] + [f"RX{n + 1}" for n in range(scenario.num_rx)]
    written = []
    for policy in metrics:
        fig = _figure(7.0, 0.25 * len(labels) + 1.5)
        ax = fig.add_subplot()
        image = ax.imshow(
            (per_trial[policy]["selections"] / config.trials).T,
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
    return written


def _save(fig, path: Path) -> Path:
    fig.savefig(path)
    return path


def plot_learning_curves(group: dict[str, list[dict[str, np.ndarray]]], path: Path, title: str) -> Path:
    """Return and ARMSE against timesteps for each learner: the mean over seeds and their range."""
    fig = _figure(10, 4)
    axes = fig.subplots(1, 2)
    for key, curves in group.items():
        length = min((len(c["timesteps"]) for c in curves), default=0)
        if length == 0:
            continue
        steps = curves[0]["timesteps"][:length]
        for ax, metric in zip(axes, ("return", "armse"), strict=True):
            values = np.array([c[metric][:length] for c in curves])
            (line,) = ax.plot(
                steps,
                np.nanmean(values, axis=0),
                label=f"{key} ({len(curves)} seed{'s' * (len(curves) > 1)})",
            )
            ax.fill_between(
                steps, np.nanmin(values, axis=0), np.nanmax(values, axis=0), alpha=0.2, color=line.get_color()
            )
    axes[0].set(xlabel="timesteps", ylabel="training episode return", title=f"{title}: return")
    axes[1].set(xlabel="timesteps", ylabel="training episode ARMSE (m)", title=f"{title}: ARMSE")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    return path
