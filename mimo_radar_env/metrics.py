"""The evaluation metrics (docs/model.md, section 11), from per-step sums over Monte-Carlo trials.

Every function takes sums over trials at each step (what a harness accumulates
shard by shard) and the number of trials.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def rmse_curve(squared_error_sum: NDArray[np.float64], trials: int) -> NDArray[np.float64]:
    """``RMSE_k(t) = sqrt(mean over trials of position error^2)``: (T, K) from (T, K) sums."""
    return np.sqrt(np.asarray(squared_error_sum) / trials)


def armse(squared_error_sum: NDArray[np.float64], trials: int) -> tuple[float, list[float]]:
    """ARMSE over targets weighted equally, and per target: means over t of ``RMSE_k(t)``."""
    per_target = rmse_curve(squared_error_sum, trials).mean(axis=0)
    return float(per_target.mean()), [float(v) for v in per_target]


def mean_sinr_db_curve(expected_sum: NDArray[np.float64], trials: int, channels: int) -> NDArray[np.float64]:
    """Average SINR in dB at t: ``10 log10(mean over trials of mu_t / (Ms Ns))``."""
    return 10.0 * np.log10(np.asarray(expected_sum) / (trials * channels))


def mean_sinr_db(expected_sum: NDArray[np.float64], trials: int, channels: int) -> float:
    """``10 log10`` of the mean over trials and steps of ``mu_t / (Ms Ns)``."""
    return float(10.0 * np.log10(np.sum(expected_sum) / (trials * channels * len(expected_sum))))


def regret_curve(
    optimal_sum: NDArray[np.float64], expected_sum: NDArray[np.float64], trials: int
) -> NDArray[np.float64]:
    """Cumulative regret ``sum_{s <= t} (mu*_s - mu_s)``, mean over trials (eq13)."""
    return np.cumsum((np.asarray(optimal_sum) - np.asarray(expected_sum)) / trials)


def asr(matches_sum: NDArray[np.float64], trials: int) -> float:
    """eq33: mean over trials and steps of ``1[A_t == A_Best,t]``, a fraction in [0, 1]."""
    return float(np.sum(matches_sum) / (trials * len(matches_sum)))
