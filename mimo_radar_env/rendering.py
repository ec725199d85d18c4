"""Matplotlib drawing of a scenario: region, stations, tracks and the selected channels."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .scenarios import Scenario


def draw_scenario(
    ax: Any,
    scenario: Scenario,
    true_tracks: NDArray[np.float64] | None = None,
    estimated_tracks: NDArray[np.float64] | None = None,
    selection: NDArray[np.int8] | None = None,
    title: str | None = None,
) -> None:
    """Draw on a matplotlib axis.

    Parameters
    ----------
    true_tracks, estimated_tracks : arrays (steps, K, 2) in metres, optional
    selection : array (M + N,), optional
        The last action; its channels are drawn from each selected transmitter
        to each target and on to each selected receiver.
    """
    km = 1e-3
    tx, rx = scenario.tx_positions * km, scenario.rx_positions * km
    ax.scatter(tx[:, 0], tx[:, 1], marker="^", s=80, c="tab:red", label="TX", zorder=3)
    ax.scatter(rx[:, 0], rx[:, 1], marker="s", s=60, c="tab:blue", label="RX", zorder=3)
    for i, (x, y) in enumerate(tx):
        ax.annotate(f"TX{i + 1}", (x, y), textcoords="offset points", xytext=(4, 4), fontsize=8)
    for i, (x, y) in enumerate(rx):
        ax.annotate(f"RX{i + 1}", (x, y), textcoords="offset points", xytext=(4, -10), fontsize=8)
    if true_tracks is not None and len(true_tracks):
        tracks = true_tracks * km
        for k in range(tracks.shape[1]):
            ax.plot(tracks[:, k, 0], tracks[:, k, 1], "r--", lw=1.2, label="truth" if k == 0 else None)
            ax.plot(tracks[0, k, 0], tracks[0, k, 1], "ro", ms=5)
            ax.annotate(f"T{k + 1}", tracks[-1, k], textcoords="offset points", xytext=(4, 4), fontsize=8)
    if estimated_tracks is not None and len(estimated_tracks):
        est = estimated_tracks * km
        for k in range(est.shape[1]):
            ax.plot(est[:, k, 0], est[:, k, 1], "k-", lw=0.8, alpha=0.7, label="track" if k == 0 else None)
    if selection is not None and true_tracks is not None and len(true_tracks):
        num_tx = scenario.num_tx
        chosen_tx = np.flatnonzero(selection[:num_tx])
        chosen_rx = np.flatnonzero(selection[num_tx:])
        for position in true_tracks[-1] * km:
            for m in chosen_tx:
                ax.plot([tx[m, 0], position[0]], [tx[m, 1], position[1]], c="tab:red", lw=0.6, alpha=0.6)
            for n in chosen_rx:
                ax.plot([position[0], rx[n, 0]], [position[1], rx[n, 1]], c="tab:blue", lw=0.6, alpha=0.6)
    points = [tx, rx] + (
        [true_tracks.reshape(-1, 2) * km] if true_tracks is not None and len(true_tracks) else []
    )
    allp = np.concatenate(points)
    low, high = allp.min(axis=0), allp.max(axis=0)
    pad = 0.05 * max(float(np.max(high - low)), 1.0)
    ax.set_xlim(low[0] - pad, high[0] + pad)
    ax.set_ylim(low[1] - pad, high[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (km)")
    ax.set_ylabel("y (km)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=7)
    if title:
        ax.set_title(title)


def figure_to_rgb(fig: Any) -> NDArray[np.uint8]:
    """Render a matplotlib figure into an (H, W, 3) uint8 array."""
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
