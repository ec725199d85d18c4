"""What a training says as it goes and leaves behind: the learning curve (``curve.csv`` and its
figure) and the progress line of each rollout, for both trainers (SB3's through a callback,
torch-ppo directly)."""

from __future__ import annotations

import csv
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

#: A training's record (learner, scenario, options, budget, hyperparameters, wall time).
META_FILE = "ppo.json"
#: The learning curve of a training: per rollout, the mean return and ARMSE of its episodes.
CURVE_FILE = "curve.csv"
#: Its figure, beside it (written once an episode has ended).
CURVE_FIGURE = "curve.png"


class LearningCurve:
    """The learning curve of a training, and what it prints as it goes: after each rollout, the
    timesteps so far and the mean return and ARMSE (m) of the training episodes that ended in it
    (eq17's or the information reward summed over the episode, and the root of the mean over its
    steps and targets of the tracker's squared position error). Both trainers feed it: SB3's
    through :meth:`callback` (``NativeVecEnv``'s episode info), torch-ppo directly.

    With ``progress``, a line per rollout (at most one every ``every`` seconds, and the last):
    the steps trained of ``total``, the last rollout's return and ARMSE, steps per second and
    the time left at that rate."""

    FIELDS = ("timesteps", "episodes", "return", "armse")

    def __init__(self, total: int = 0, progress: bool = False, every: float = 5.0, name: str = "train-ppo"):
        self.rows: list[dict[str, float]] = []
        self._returns: list[float] = []
        self._armse: list[float] = []
        self.total, self.progress, self.every, self.name = total, progress, every, name
        self._start = time.perf_counter()
        self._printed = -math.inf

    def start(self, total: int) -> None:
        """The training starts now, for ``total`` steps (whole rollouts)."""
        self.total, self._start = total, time.perf_counter()

    def callback(self) -> Any:
        from stable_baselines3.common.callbacks import BaseCallback

        curve = self

        class _Callback(BaseCallback):
            def _on_step(self) -> bool:
                for info in self.locals.get("infos", []):
                    episode = info.get("episode")
                    if episode is not None:
                        curve.add_episodes([episode["r"]], [episode.get("armse", math.nan)])
                return True

            def _on_rollout_end(self) -> None:
                curve.close_rollout(self.num_timesteps)

        return _Callback()

    def add_episodes(self, returns: list[float], armse: list[float]) -> None:
        """Episodes that ended: their returns and ARMSE (NaN without the tracker)."""
        self._returns += map(float, returns)
        self._armse += map(float, armse)

    def close_rollout(self, timesteps: int) -> None:
        if self._returns:
            self.rows.append(
                {
                    "timesteps": timesteps,
                    "episodes": len(self._returns),
                    "return": sum(self._returns) / len(self._returns),
                    "armse": sum(self._armse) / len(self._armse),
                }
            )
        self._returns, self._armse = [], []
        now = time.perf_counter()
        if self.progress and (now - self._printed >= self.every or timesteps >= self.total):
            self._printed = now
            print(self.line(timesteps, now - self._start), flush=True)

    def line(self, timesteps: int, seconds: float) -> str:
        """``ppo: 14,336/20,480 steps (70 %) · return 4875.4 · ARMSE 2.44 m · 628 steps/s · 10 s
        left``; the return and ARMSE are those of the latest rollout in which an episode ended."""
        rate = timesteps / seconds if seconds > 0 else math.inf
        share = 100 * timesteps / max(self.total, 1)
        parts = [f"{self.name}: {timesteps:,}/{self.total:,} steps ({share:.0f} %)"]
        if self.rows:
            last = self.rows[-1]
            parts.append(f"return {last['return']:.1f}")
            if math.isfinite(last["armse"]):
                parts.append(f"ARMSE {last['armse']:.2f} m")
        parts.append(f"{rate:,.0f} steps/s")
        if timesteps < self.total and math.isfinite(rate):
            parts.append(f"{(self.total - timesteps) / rate:,.0f} s left")
        return " · ".join(parts)

    def write(self, path: Path, title: str = "") -> None:
        """The curve as ``path`` (CSV) and, when an episode ended, as a figure beside it
        (:data:`CURVE_FIGURE`: return and ARMSE against the steps trained)."""
        with path.open("w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=self.FIELDS)
            writer.writeheader()
            writer.writerows(self.rows)
        if self.rows:
            from .plots import plot_learning_curves

            curve = {
                key: np.array([row[key] for row in self.rows]) for key in ("timesteps", "return", "armse")
            }
            plot_learning_curves({self.name: [curve]}, path.with_name(CURVE_FIGURE), title or self.name)
