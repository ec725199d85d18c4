"""95 % intervals over trials, by the bootstrap, for every number a run reports.

Each metric is a function of per-trial values, evaluated on a resample of the trials (a
weight per trial: how often the resample drew it). Intervals are ``scipy.stats.bootstrap``'s
BCa intervals with resamples of the trials (percentile intervals where BCa is undefined: a
metric constant over trials, such as Best's zero regret); comparisons between two policies resample the
*same* trials for both (paired), so the common truth and channel draws cancel. The per-step
bands of the figures are the same bootstrap applied to each step's value.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from itertools import combinations

import numpy as np
from numpy.typing import NDArray
from scipy import stats

CONFIDENCE = 0.95
RESAMPLES = 2000
BAND_RESAMPLES = 1000
METHOD = (
    f"BCa bootstrap over trials (scipy.stats.bootstrap, {RESAMPLES} resamples, {CONFIDENCE:.0%}); "
    "differences paired on the same trials; curve bands: percentile bootstrap per step "
    f"({BAND_RESAMPLES} resamples)"
)

Metric = Callable[[NDArray[np.float64]], NDArray[np.float64]]


class TrialMetrics:
    """The run's metrics as functions of trial weights ``w`` (..., N) that sum to 1.

    Parameters
    ----------
    per_trial : dict
        ``trial_expected``, ``trial_optimal`` (N, T), ``trial_squared_error`` (N, T, K),
        ``trial_matches`` (N, T) of one policy, and optionally ``trial_bound_squared``
        (N, T, K), the squared position bound of the selections made.
    channels : int
        ``Ms * Ns``.
    """

    def __init__(self, per_trial: dict[str, NDArray], channels: int) -> None:
        expected = per_trial["trial_expected"].astype(np.float64)
        optimal = per_trial["trial_optimal"].astype(np.float64)
        self.steps = expected.shape[1]
        self.mean_reward = expected.mean(axis=1)  # (N,)
        self.regret = (optimal - expected).sum(axis=1)
        self.regret_curve_per_trial = np.cumsum(optimal - expected, axis=1)  # (N, T)
        self.reward_curve_per_trial = expected
        self.match = per_trial["trial_matches"].astype(np.float64).mean(axis=1)
        self.squared = per_trial["trial_squared_error"].astype(np.float64)  # (N, T, K)
        self.tracked = bool(np.isfinite(self.squared).all())
        bound = per_trial.get("trial_bound_squared")
        self.bound_squared = bound.astype(np.float64) if bound is not None else None  # (N, T, K)
        self.bounded = self.tracked and self.bound_squared is not None and bool(np.isfinite(bound).all())
        self.channels = channels

    @property
    def num_trials(self) -> int:
        return len(self.regret)

    def final_regret(self, w: NDArray) -> NDArray:
        return w @ self.regret

    def asr(self, w: NDArray) -> NDArray:
        return w @ self.match

    def mean_sinr_db(self, w: NDArray) -> NDArray:
        return 10.0 * np.log10(w @ self.mean_reward / self.channels)

    def rmse_curve(self, w: NDArray, target: int) -> NDArray:
        return _root_mean_square(self.squared, w, target)  # (..., T)

    def armse_target(self, target: int) -> Metric:
        return lambda w: self.rmse_curve(w, target).mean(axis=-1)

    def armse(self, w: NDArray) -> NDArray:
        return _time_averaged(self.squared, w)

    def bound(self, w: NDArray) -> NDArray:
        """The time-averaged root-mean-square position bound over targets weighted equally
        (as ARMSE averages the RMSE): the floor the policy's selections set."""
        assert self.bound_squared is not None
        return _time_averaged(self.bound_squared, w)

    def armse_over_bound(self, w: NDArray) -> NDArray:
        return self.armse(w) / self.bound(w)

    def bound_metrics(self) -> dict[str, Metric]:
        """The bound and ARMSE / bound (with a tracker and recorded bounds; not paired)."""
        if not self.bounded:
            return {}
        return {"bound": self.bound, "armse_over_bound": self.armse_over_bound}

    def scalar_metrics(self) -> dict[str, Metric]:
        """The table's metrics (ARMSE only with a tracker)."""
        metrics: dict[str, Metric] = {
            "asr": self.asr,
            "final_regret": self.final_regret,
            "mean_sinr_db": self.mean_sinr_db,
        }
        if self.tracked:
            metrics["armse"] = self.armse
        return metrics


def _root_mean_square(squared: NDArray, w: NDArray, target: int) -> NDArray:
    """``sqrt`` of the trial-weighted mean of squared values (N, T, K) for one target: (..., T)."""
    return np.sqrt(w @ squared[:, :, target])


def _time_averaged(squared: NDArray, w: NDArray) -> NDArray:
    """The mean over targets of the mean over steps of the root mean square: ARMSE's shape."""
    targets = range(squared.shape[2])
    return np.mean([_root_mean_square(squared, w, k).mean(axis=-1) for k in targets], axis=0)


def _weights(index: NDArray, num_trials: int) -> NDArray[np.float64]:
    """Resampled trial indices (..., n) as weights (..., N) summing to 1."""
    index = np.asarray(index)
    rows = index.reshape(-1, index.shape[-1])
    weights = np.zeros((rows.shape[0], num_trials))
    np.add.at(weights, (np.arange(rows.shape[0])[:, None], rows), 1.0)
    return (weights / rows.shape[1]).reshape((*index.shape[:-1], num_trials))


def _bootstrap(
    metric: Callable[[NDArray], NDArray], num_trials: int, resamples: int, method: str, seed: int
) -> tuple[NDArray, NDArray]:
    """``scipy.stats.bootstrap`` over resampled trials of ``metric(weights) -> (...,) or (..., T)``."""

    def statistic(index: NDArray, axis: int = -1) -> NDArray:
        value = metric(_weights(index, num_trials))
        return np.moveaxis(value, -1, 0) if value.ndim > np.ndim(index) - 1 else value

    with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", stats.DegenerateDataWarning)
        result = stats.bootstrap(
            (np.arange(num_trials),),
            statistic,
            vectorized=True,
            n_resamples=resamples,
            confidence_level=CONFIDENCE,
            method=method,
            random_state=np.random.default_rng(seed),
        )
    return result.confidence_interval.low, result.confidence_interval.high


def interval(metric: Metric, num_trials: int, seed: int = 0, method: str = "BCa") -> tuple[float, float]:
    """The 95 % bootstrap interval of ``metric`` over ``num_trials`` trials (BCa; percentile where
    BCa is undefined)."""
    if num_trials < 2:
        return float("nan"), float("nan")
    low, high = _bootstrap(metric, num_trials, RESAMPLES, method, seed)
    if not (np.isfinite(low) and np.isfinite(high)):  # BCa is undefined for a constant statistic
        low, high = _bootstrap(metric, num_trials, RESAMPLES, "percentile", seed)
    return float(low), float(high)


def band(curve: Callable[[NDArray], NDArray], num_trials: int, seed: int = 0) -> tuple[NDArray, NDArray]:
    """Per-step 95 % band (percentile bootstrap) of a curve ``curve(w) -> (..., T)``."""
    if num_trials < 2:
        nan = np.full(curve(np.full(num_trials, 1.0 / num_trials)).shape[-1], np.nan)
        return nan, nan
    return _bootstrap(curve, num_trials, BAND_RESAMPLES, "percentile", seed)


def policy_intervals(metrics: TrialMetrics, seed: int = 0) -> dict[str, list[float]]:
    """``{metric: [low, high]}`` for the table's metrics (with the bound's), and
    ``armse_per_target``."""
    every = metrics.scalar_metrics() | metrics.bound_metrics()
    out = {name: list(interval(fn, metrics.num_trials, seed)) for name, fn in every.items()}
    if metrics.tracked:
        out["armse_per_target"] = [
            list(interval(metrics.armse_target(k), metrics.num_trials, seed))
            for k in range(metrics.squared.shape[2])
        ]
    return out


def paired_differences(all_metrics: dict[str, TrialMetrics], seed: int = 0) -> dict[str, dict[str, dict]]:
    """``{"A - B": {metric: {"estimate", "ci"}}}`` for every pair of policies, paired on trials."""
    out: dict[str, dict[str, dict]] = {}
    for a, b in combinations(all_metrics, 2):
        ma, mb = all_metrics[a], all_metrics[b]
        n = ma.num_trials
        ones = np.full(n, 1.0 / n)
        pair = {}
        for name, fa in ma.scalar_metrics().items():
            fb = mb.scalar_metrics().get(name)
            if fb is None:
                continue

            def difference(w: NDArray, fa: Metric = fa, fb: Metric = fb) -> NDArray:
                return fa(w) - fb(w)

            pair[name] = {
                "estimate": float(difference(ones)),
                "ci": list(interval(difference, n, seed)),
            }
        out[f"{a} - {b}"] = pair
    return out
