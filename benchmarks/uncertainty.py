"""95 % intervals over trials, by the bootstrap, for every number a run reports.

A metric is a function of trial weights (:class:`benchmarks.metrics.TrialMetrics`): its
value is the function at equal weights, and its interval is ``scipy.stats.bootstrap`` over
resamples of the trials, each resample a vector of weights fed to the *same* function. The
method:

* **BCa** from :data:`BCA_MIN_TRIALS` to :data:`BCA_MAX_TRIALS` trials;
* **percentile** below that (BCa's acceleration is a jackknife over trials, unreliable on a
  handful of them; there at the level of Hesterberg's expanded percentile interval,
  :func:`confidence_level`, as one at 95 % is too narrow on a few trials), above it (the
  jackknife's ``n`` statistics of ``n - 1`` trials each would
  take ``n^2`` memory, 80 GB at 100,000 trials, and BCa's correction shrinks towards the
  percentile interval as trials grow; there resamples are also drawn in batches of at most
  :data:`BATCH_WEIGHTS` weights), where BCa is undefined, or where BCa's interval would exclude
  the value (a strongly skewed resampling distribution);
* **bias-corrected percentile** on fewer than :data:`FEW_TRIALS` trials, for a metric
  with a bias over trials (a root of a mean: ARMSE, the bound, their ratio): the percentile interval moved by
  twice the jackknife's estimate of the bias (:func:`jackknife_bias`), from around the
  resamples' centre (the value plus the bias) to around the value less the bias. ARMSE averages a
  root of a mean over trials at each of many steps: the bias stays while the spread averages
  down, so on a few trials its resamples lie below the value, and a percentile or BCa interval
  misses the ARMSE of many trials. A mean's jackknife bias is zero but for rounding
  (:data:`NO_BIAS`);
* **bootstrap-t** on fewer than :data:`FEW_TRIALS` trials, for a mean over trials (ASR, final
  regret, their paired differences; any metric whose every resample is the mean of its trials'
  own values, to rounding): each resample's ``t``, its distance from the value in its own
  standard errors, gives the interval at 95 % (:func:`_bootstrap_t`). An increasing function of
  a mean (:class:`~benchmarks.metrics.OfMean`: mean SINR in dB) gets its mean's bootstrap-t
  interval mapped through the function (:func:`_through_means`), and a paired difference of two
  such functions with slopes (:class:`~benchmarks.metrics.DifferenceOfMeans`: a difference of
  mean SINRs in dB) a bootstrap-t whose standard errors are the delta method's
  (:class:`_DeltaMethod`). A mean of a few skewed
  trials (a policy's final regret) is covered less often by percentile and BCa intervals, which
  do not widen for the spread a few trials fail to show. Where a quantile of ``t`` is infinite
  (resamples of trials of one value: a share of successes on a few trials) the percentile or
  BCa interval stands in;
* **constant**: a metric whose every resample gives the value (within floating-point
  rounding) is constant over trials, and its interval is the value itself (Best's zero regret,
  a fixed policy's regret under a shared truth).

Fewer than :data:`MIN_INTERVAL_TRIALS` trials give no interval. Each interval records its
method, and every interval contains its value: an end that misses the value is set to it,
silently where the miss is rounding alone (``<= ROUNDING`` of the resamples' spread), and
otherwise with the method ``percentile, extended to the value`` (or ``bias-corrected
percentile, ...``, ``bootstrap-t, ...``). Such a miss is a statistic whose resamples lie to one
side of it, or whose bias correction moved its interval past it: ARMSE of a few trials of
heavy-tailed errors, a root of a mean over trials at each step (they raised before).
Comparisons between two policies resample the *same* trials for both (paired), so the common
truth and channel draws cancel. The per-step bands of the figures are the percentile bootstrap
applied to each step's value, not bias-corrected: at one step a root's bias is a small part of
its spread; it is the average over many steps that shrinks the spread and leaves the bias.
"""

from __future__ import annotations

import functools
import time
import warnings
from collections.abc import Callable, Iterable, Mapping
from itertools import combinations
from typing import Any

import numpy as np
from numpy.typing import NDArray

from benchmarks.backends import one_blas_thread
from benchmarks.metrics import REMEMBERED_WEIGHTS, DifferenceOfMeans, OfMean, TrialMetrics, trial_weights

CONFIDENCE = 0.95
#: The fewest trials a 95 % interval is given on. A bootstrap interval lies within the range of
#: the trials, which holds the median of a symmetric distribution with probability
#: ``1 - 2^(1 - n)``: under 95 % up to 5 trials (94 % at 5). Fewer trials give estimates alone.
MIN_INTERVAL_TRIALS = 6
RESAMPLES = 2000
BAND_RESAMPLES = 1000
#: Below this many trials intervals are percentile intervals, not BCa.
BCA_MIN_TRIALS = 20
#: Above this many trials too (a device's scorecards of 100,000 trials), with batched resamples.
BCA_MAX_TRIALS = 20_000
#: The most trial weights one batch of resamples holds above BCA_MAX_TRIALS (160 MB of float64).
BATCH_WEIGHTS = 20_000_000
#: Relative size (of the resamples' spread, or of the value where they do not spread) of a
#: miss that is floating-point rounding.
ROUNDING = 1e-9
#: Below this many trials a metric with a bias over trials gets the bias-corrected percentile
#: interval, and a mean over trials the bootstrap-t. On 6 to 20 trials the first covered ARMSE far
#: more often than the percentile and BCa intervals did (results/uncertainty/trial-coverage.json
#: now and at d2062b1), and in an ad hoc run more often than BCa on 30 trials and a little more on
#: 40; the second covers the means more often on 6 to 30 trials (that artefact now and at
#: 49095d1). Not from 40: the committed screens (calibrate-layout, which chose v1's layout, and
#: search-layouts) judge 40.
FEW_TRIALS = 40
#: A jackknife bias under this fraction of the resamples' spread is none (a mean's is rounding).
NO_BIAS = 1e-6
METHODS = {
    "BCa": "BCa",
    "percentile": "percentile",
    "extended": "percentile, extended to the value",
    "bias-corrected": "bias-corrected percentile",
    "bias-corrected, extended": "bias-corrected percentile, extended to the value",
    "bootstrap-t": "bootstrap-t",
    "bootstrap-t, extended": "bootstrap-t, extended to the value",
    "constant": "constant over trials",
}
#: The methods of intervals extended to their value.
EXTENDED = (METHODS["extended"], METHODS["bias-corrected, extended"], METHODS["bootstrap-t, extended"])
METHOD = (
    f"bootstrap over trials (scipy.stats.bootstrap, {RESAMPLES} resamples, {CONFIDENCE:.0%}): BCa from "
    f"{BCA_MIN_TRIALS} trials, percentile below or where BCa is undefined or would exclude the value "
    f"(and above {BCA_MAX_TRIALS:,} trials), "
    f"the value itself for a metric constant over trials; differences paired on the same trials; "
    f"curve bands: percentile bootstrap per step ({BAND_RESAMPLES} resamples)"
)

#: How intervals below BCA_MIN_TRIALS are widened (:func:`confidence_level`).
EXPANDED = (
    f"below {BCA_MIN_TRIALS} trials the percentile interval's level is Hesterberg's expansion for "
    "a few trials (its z is Student's t with n - 1 degrees of freedom times sqrt(n / (n - 1)))"
)
#: How intervals below FEW_TRIALS are computed (:func:`jackknife_bias`, :func:`_bootstrap_t`).
FEW = (
    f"below {FEW_TRIALS} trials a metric with a bias over trials (ARMSE, the bound and their "
    "ratio) has a bias-corrected percentile interval: the percentile "
    "interval moved by twice its jackknife bias; and a mean over trials (ASR, final regret, their "
    "paired differences) a bootstrap-t interval at 95 %, mean SINR in dB the bootstrap-t "
    "interval of the mean SINR, in dB, and a paired difference of mean SINRs in dB a bootstrap-t "
    "interval with the delta method's standard errors"
)
#: The methods below FEW_TRIALS besides the percentile or BCa interval (a coverage row's `method`).
FEW_METHODS = (
    "; bias-corrected percentile for a metric with a bias; bootstrap-t for a mean, for mean SINR in "
    "dB its mean's, and for a difference of mean SINRs in dB the delta method's"
)
#: What a table of fewer than MIN_INTERVAL_TRIALS trials says in place of its intervals.
NO_INTERVALS = (
    f"No intervals: a 95 % interval needs {MIN_INTERVAL_TRIALS} trials or more (a bootstrap interval "
    "lies within the range of the trials, which holds the median of a symmetric distribution with "
    "probability 1 - 2^(1 - n): 94 % at 5 trials)."
)

Metric = Callable[[NDArray[np.float64]], NDArray[np.float64]]


def method_of(num_trials: int) -> str:
    """How the intervals of a run of ``num_trials`` trials are computed (:data:`METHOD`, with
    :data:`EXPANDED` below :data:`BCA_MIN_TRIALS` trials and :data:`FEW` below
    :data:`FEW_TRIALS`)."""
    parts = [METHOD, EXPANDED if num_trials < BCA_MIN_TRIALS else ""]
    parts.append(FEW if num_trials < FEW_TRIALS else "")
    return "; ".join(part for part in parts if part)


#: The largest index array (elements) whose weights are kept: 2,000 resamples of 1,000 trials.
SHARED_INDEX_ELEMENTS = 2_000_000
#: The weights of the last few index arrays a bootstrap resampled (:func:`_shared_weights`).
_WEIGHTS: list[tuple[NDArray, int, NDArray]] = []


def _shared_weights(index: NDArray, num_trials: int) -> NDArray[np.float64]:
    """``trial_weights(index, num_trials)``, the same array object for an index equal to one of the
    last :data:`metrics.REMEMBERED_WEIGHTS` seen: every estimate of a run draws the same resamples
    (one seed), so the metrics evaluated on them can share their work (``TrialMetrics`` keeps
    terms by weight array)."""
    index = np.asarray(index)
    if index.size > SHARED_INDEX_ELEMENTS:  # large batches (many trials) are not kept
        return trial_weights(index, num_trials)
    for seen, n, weights in _WEIGHTS:
        if n == num_trials and seen.shape == index.shape and np.array_equal(seen, index):
            return weights
    weights = trial_weights(index, num_trials)
    _WEIGHTS.insert(0, (index.copy(), num_trials, weights))
    del _WEIGHTS[REMEMBERED_WEIGHTS:]
    return weights


def _resampled_method(num_trials: int) -> str:
    """scipy's method for an interval over ``num_trials`` trials: BCa from :data:`BCA_MIN_TRIALS`
    to :data:`BCA_MAX_TRIALS` trials, percentile outside."""
    return "BCa" if BCA_MIN_TRIALS <= num_trials <= BCA_MAX_TRIALS else "percentile"


def confidence_level(num_trials: int) -> float:
    """The bootstrap's confidence level for a 95 % interval over ``num_trials`` trials: 95 % from
    :data:`BCA_MIN_TRIALS` on; below, that of Hesterberg's expanded percentile interval, whose
    ``z`` is Student's ``t`` with ``n - 1`` degrees of freedom times ``sqrt(n / (n - 1))`` (a
    percentile interval at 95 % is too narrow on a few trials: tests/benchmarks/test_uncertainty.py
    measures both on 6 and 10 normal trials)."""
    from scipy import stats

    if num_trials >= BCA_MIN_TRIALS:
        return CONFIDENCE
    z = np.sqrt(num_trials / (num_trials - 1)) * stats.t.ppf((1 + CONFIDENCE) / 2, num_trials - 1)
    return float(1 - 2 * stats.norm.sf(z))


def _bootstrap(metric: Metric, num_trials: int, resamples: int, method: str, seed: int) -> Any:
    """``scipy.stats.bootstrap`` over resampled trials of ``metric(weights) -> (...,) or (..., T)``."""
    from scipy import stats  # imported at the first interval: a study's set-up does without it

    def statistic(index: NDArray, axis: int = -1) -> NDArray:
        value = metric(_shared_weights(index, num_trials))
        return np.moveaxis(value, -1, 0) if value.ndim > np.ndim(index) - 1 else value

    batch = None if num_trials <= BCA_MAX_TRIALS else max(1, BATCH_WEIGHTS // num_trials)
    # over: scipy's standard error of the resamples, which is not read, of values near the float limit
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", stats.DegenerateDataWarning)
        return stats.bootstrap(
            (np.arange(num_trials),),
            statistic,
            vectorized=True,
            n_resamples=resamples,
            batch=batch,
            confidence_level=confidence_level(num_trials),
            method=method,
            random_state=np.random.default_rng(seed),
        )


def estimate(metric: Metric, num_trials: int, seed: int = 0) -> dict[str, Any]:
    """``{"estimate", "ci", "method"}``: the metric at equal weights and its 95 % interval
    (``ci`` None on fewer than :data:`MIN_INTERVAL_TRIALS` trials, which have none)."""
    return estimates({"": metric}, num_trials, seed)[""]


@one_blas_thread()
def estimates(metrics: Mapping[Any, Metric], num_trials: int, seed: int = 0) -> dict[Any, dict[str, Any]]:
    """:func:`estimate` of each of ``metrics``, by key, from one bootstrap of all of them: the
    same numbers as one call each (every call resamples the trials with ``seed``, and scipy
    treats each output of a vector-valued statistic on its own), drawn and set up once."""
    if num_trials < FEW_TRIALS and any(isinstance(metric, OfMean) for metric in metrics.values()):
        return _through_means(metrics, num_trials, seed)
    return _bootstrapped(metrics, num_trials, seed)


def _bootstrapped(metrics: Mapping[Any, Metric], num_trials: int, seed: int) -> dict[Any, dict[str, Any]]:
    """:func:`estimates`, each metric judged on its own resamples (an
    :class:`~benchmarks.metrics.OfMean` as any metric)."""
    keys = list(metrics)
    if not keys:
        return {}
    equal = _shared_weights(np.arange(num_trials), num_trials)
    values = [float(metrics[key](equal)) for key in keys]
    if num_trials < MIN_INTERVAL_TRIALS:
        none = {"ci": None, "method": f"none (fewer than {MIN_INTERVAL_TRIALS} trials)"}
        return {key: {"estimate": v, **none} for key, v in zip(keys, values, strict=True)}
    method = _resampled_method(num_trials)

    def stacked(weights: NDArray[np.float64]) -> NDArray[np.float64]:
        # (..., metrics), a view of a contiguous (metrics, ...) array: each metric's resamples stay
        # contiguous after _bootstrap moves the axis back, so scipy sums them in the same order
        return np.moveaxis(np.stack([metrics[key](weights) for key in keys]), 0, -1)

    few = num_trials < FEW_TRIALS
    value_array = np.array(values)
    if few:  # each trial's own value, and the resamples' means and standard errors of them
        with np.errstate(invalid="ignore", divide="ignore"):  # a trial alone may give no value
            singles = stacked(np.eye(num_trials))  # (n, metrics)
            delta = {
                i: _DeltaMethod(metric, num_trials)
                for i, metric in enumerate(metrics[key] for key in keys)
                if isinstance(metric, DifferenceOfMeans)
            }
            for i, d in delta.items():  # a trial's own value: its term of the delta method's mean
                singles[:, i] = d.linearized + value_array[i]
            finite = np.isfinite(singles).all(axis=0)
            centred = np.where(finite, singles - value_array, 0.0)  # variances lose no digits
        scales = _power_of_two_scale(centred)  # squares of values near 1e300 neither overflow
        scaled = centred / scales
        judged = stacked

        def stacked(weights: NDArray[np.float64]) -> NDArray[np.float64]:
            # a product per metric: the same bits whatever other metrics share the bootstrap
            shifts = np.stack([weights @ column for column in scaled.T])
            squares = np.stack([weights @ column**2 for column in scaled.T])
            errors = np.sqrt(np.maximum(squares - shifts**2, 0.0) / (num_trials - 1))  # (metrics, ...)
            column_of = (-1, *[1] * (shifts.ndim - 1))
            errors, shifts = errors * scales.reshape(column_of), shifts * scales.reshape(column_of)
            means = shifts + value_array.reshape(column_of)
            values_at = np.moveaxis(judged(weights), -1, 0)
            for i, d in delta.items():  # studentized by the delta method, resample by resample
                means[i], errors[i] = values_at[i], d.error(weights)
            parts = (values_at, means, errors)  # contiguous, as judged's
            return np.moveaxis(np.concatenate(parts), 0, -1)

    result = _bootstrap(stacked, num_trials, RESAMPLES, method, seed)
    count = len(keys)
    lows = np.atleast_1d(result.confidence_interval.low)[:count]
    highs = np.atleast_1d(result.confidence_interval.high)[:count]
    distributions = np.asarray(result.bootstrap_distribution, np.float64).reshape(
        count * (3 if few else 1), -1
    )
    biases = np.zeros(count)
    students: list[tuple[NDArray, NDArray, NDArray] | None] = [None] * count
    if few:
        biases = jackknife_bias(judged, value_array, num_trials)
        means, errors = distributions[count : 2 * count], distributions[2 * count :]
        for i in np.flatnonzero(finite):
            students[i] = (means[i], errors[i], centred[:, i])
        distributions = distributions[:count]
    alpha = (1 - confidence_level(num_trials)) / 2
    return {
        key: _interval(
            values[i], (lows[i], highs[i]), distributions[i], alpha, method, biases[i], students[i]
        )
        for i, key in enumerate(keys)
    }


class _DeltaMethod:
    """The delta method's standard error of a :class:`~benchmarks.metrics.DifferenceOfMeans`
    ``g(mean_a) - h(mean_b)`` over ``num_trials`` trials: that of the mean of each trial's
    ``g'(mean_a) x_a - h'(mean_b) x_b`` (``linearized``: at the equal weights, less its mean), with
    the slopes at the means of the weights given (:meth:`error`)."""

    def __init__(self, metric: DifferenceOfMeans, num_trials: int) -> None:
        self.metric, self.num_trials = metric, num_trials
        eye = np.eye(num_trials)
        trials = [np.asarray(m.mean(eye), np.float64) for m in (metric.a, metric.b)]  # x_a, x_b
        self.means = [float(x.mean()) for x in trials]
        centred = [x - m for x, m in zip(trials, self.means, strict=True)]
        slope_a, slope_b = metric.a.slope(self.means[0]), metric.b.slope(self.means[1])
        self.linearized = slope_a * centred[0] - slope_b * centred[1]
        # moments of values scaled to 1, as _bootstrapped takes them: the same bits, and finite
        self.scales = [float(_power_of_two_scale(c)) for c in centred]
        self.scaled = [c / scale for c, scale in zip(centred, self.scales, strict=True)]

    def error(self, weights: NDArray[np.float64]) -> NDArray[np.float64]:
        """The standard error at each resample's trial ``weights`` (..., n)."""
        (ca, cb), (ma, mb), (sa, sb) = self.scaled, self.means, self.scales
        shift_a, shift_b = weights @ ca, weights @ cb
        var_a = weights @ ca**2 - shift_a**2
        var_b = weights @ cb**2 - shift_b**2
        covariance = weights @ (ca * cb) - shift_a * shift_b
        slope_a = self.metric.a.slope(ma + shift_a * sa) * sa
        slope_b = self.metric.b.slope(mb + shift_b * sb) * sb
        variance = slope_a**2 * var_a + slope_b**2 * var_b - 2 * slope_a * slope_b * covariance
        return np.sqrt(np.maximum(variance, 0.0) / (self.num_trials - 1))


def _through_means(metrics: Mapping[Any, Metric], num_trials: int, seed: int) -> dict[Any, dict[str, Any]]:
    """:func:`estimates` on fewer than :data:`FEW_TRIALS` trials of metrics some of which are
    :class:`~benchmarks.metrics.OfMean`: each of those is judged beside its mean, and where the
    mean gets the bootstrap-t its interval is the mean's mapped through ``outer`` (increasing, so
    it holds the value). Elsewhere (a constant mean, an infinite ``t`` quantile, an end ``outer``
    does not map) it keeps its own. The other metrics' intervals are those they get alone."""
    means = {(OfMean, key): metric.mean for key, metric in metrics.items() if isinstance(metric, OfMean)}
    judged = _bootstrapped({**metrics, **means}, num_trials, seed)
    out = {key: judged[key] for key in metrics}
    for (_, key), mean in ((k, judged[k]) for k in means):
        if not mean["method"].startswith(METHODS["bootstrap-t"]):
            continue
        with np.errstate(invalid="ignore", divide="ignore"):
            low, high = (float(metrics[key].outer(np.float64(end))) for end in mean["ci"])
        if not (np.isnan(low) or np.isnan(high)):
            value = out[key]["estimate"]
            out[key] = {
                "estimate": value,
                "ci": [min(low, value), max(high, value)],
                "method": mean["method"],
            }
    return out


def _bootstrap_t(
    value: float, distribution: NDArray, spread: float, means: NDArray, errors: NDArray, singles: NDArray
) -> tuple[float, float] | None:
    """The bootstrap-t (studentized) 95 % interval of a metric that is a mean over trials, or None
    where it is not one or the interval is not finite. ``distribution``: the metric on each
    resample, ``spread`` their range; ``means`` and ``errors``: the mean of each resample's trials' own values
    (``singles``, less the value) and its standard error. The metric is a mean over trials where
    its every resample is that mean, to rounding. Each resample's ``t`` is its distance from the
    value in its own standard errors; the interval is the value less the ``t`` quantiles times the
    standard error of the trials (Efron and Tibshirani 1993, ch. 12.5). A resample of trials of
    one value has an infinite ``t`` (one of 2000 on 6 trials in about a quarter of studies): it
    is kept, and the interval is given up only where a quantile falls on such resamples."""
    if not np.isfinite(spread) or np.max(np.abs(distribution - means)) > ROUNDING * spread:
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(errors > 0, (distribution - value) / errors, np.sign(distribution - value) * np.inf)
        low_t, high_t = np.percentile(t, [100 * (1 - CONFIDENCE) / 2, 100 * (1 + CONFIDENCE) / 2])
    if not (np.isfinite(low_t) and np.isfinite(high_t)):
        return None
    scale = _power_of_two_scale(singles)
    error = float(np.std(singles / scale, ddof=1) * scale / np.sqrt(len(singles)))
    return value - float(high_t) * error, value - float(low_t) * error


def _power_of_two_scale(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per column of ``values`` (n, ...) (or for a vector), the power of two at its largest
    magnitude, 1 where it is 0: dividing by it keeps every bit (the variances of values far from
    1 are then the same bits as those of values near it, scaled) while their squares stay finite."""
    return np.ldexp(1.0, np.frexp(np.max(np.abs(values), axis=0))[1])


def jackknife_bias(metric: Metric, value: NDArray, num_trials: int) -> NDArray[np.float64]:
    """The jackknife's estimate of the bias of ``metric`` (``(n,) -> (..., metrics)``) over
    ``num_trials`` trials, whose value at equal weights is ``value``: ``n - 1`` times the mean of
    the ``n`` values with one trial left out, less the value (Quenouille's; Efron and Tibshirani
    1993, ch. 11). Zero for a mean, but for rounding."""
    kept = ~np.eye(num_trials, dtype=bool)
    index = np.broadcast_to(np.arange(num_trials), kept.shape)[kept].reshape(num_trials, -1)
    with np.errstate(invalid="ignore", divide="ignore"):  # a trial left out may leave no value
        return (num_trials - 1) * (metric(_shared_weights(index, num_trials)).mean(axis=0) - value)


def _interval(
    value: float,
    ci: tuple[float, float],
    distribution: NDArray,
    alpha: float,
    method: str,
    bias: float,
    student: tuple[NDArray, NDArray, NDArray] | None = None,
) -> dict[str, Any]:
    """One metric's estimate from its bootstrap (``ci`` by ``method``, the resamples'
    ``distribution``, each tail ``alpha``), its jackknife ``bias`` and, on a few trials, its
    resamples' means, standard errors and trials' own values (``student``, for
    :func:`_bootstrap_t`): constant, bootstrap-t, bias-corrected percentile, BCa, or percentile
    where BCa fails."""
    low, high = (float(end) for end in ci)
    spread = float(np.ptp(distribution)) if np.isfinite(distribution).all() else np.inf
    if spread <= ROUNDING * max(abs(value), np.finfo(float).tiny):
        return {"estimate": value, "ci": [value, value], "method": METHODS["constant"]}
    studentized = None if student is None else _bootstrap_t(value, distribution, spread, *student)
    corrected = abs(bias) > NO_BIAS * spread  # not where the bias or the spread is not finite
    bca_failed = method == "BCa" and not (np.isfinite(low) and np.isfinite(high) and low <= value <= high)
    if studentized is not None:
        method, (low, high) = "bootstrap-t", studentized
    elif corrected or bca_failed:
        # bias-corrected: centred on the value less the bias, not on the value plus it; else BCa is
        # undefined, or skewed past the value, and the percentile interval stands in
        method = "bias-corrected" if corrected else "percentile"
        shift = 2 * float(bias) if corrected else 0.0
        levels = [100 * alpha, 100 * (1 - alpha)]
        with np.errstate(invalid="ignore"):  # resamples of infinite value
            tails = np.percentile(distribution, levels)
        if not np.isnan(distribution).any():  # a tail between two infinite resamples is infinite
            tails = np.where(np.isnan(tails), np.percentile(distribution, levels, method="nearest"), tails)
        low, high = (float(q) - shift for q in tails)
    if max(low - value, value - high, 0.0) > ROUNDING * spread:
        method = f"{method}, extended" if method in ("bias-corrected", "bootstrap-t") else "extended"
    return {"estimate": value, "ci": [min(low, value), max(high, value)], "method": METHODS[method]}


def interval(metric: Metric, num_trials: int, seed: int = 0) -> tuple[float, float]:
    """The 95 % interval of ``metric`` over ``num_trials`` trials (see :func:`estimate`)."""
    ci = estimate(metric, num_trials, seed)["ci"]
    return (float("nan"), float("nan")) if ci is None else (ci[0], ci[1])


@one_blas_thread()
def band(curve: Metric, num_trials: int, seed: int = 0) -> tuple[NDArray, NDArray]:
    """Per-step 95 % band (percentile bootstrap) of a curve ``curve(w) -> (..., T)``; NaN on fewer
    than :data:`MIN_INTERVAL_TRIALS` trials."""
    if num_trials < MIN_INTERVAL_TRIALS:
        nan = np.full(curve(trial_weights(np.arange(num_trials), num_trials)).shape[-1], np.nan)
        return nan, nan
    result = _bootstrap(curve, num_trials, BAND_RESAMPLES, "percentile", seed)
    return result.confidence_interval.low, result.confidence_interval.high


def policy_estimates(metrics: TrialMetrics, seed: int = 0) -> dict[str, Any]:
    """Every table metric of one policy: ``{metric: {"estimate", "ci", "method"}}``, and
    ``{metric_per_target: [one such dict per target]}``."""
    n = metrics.num_trials
    scalar, per_target = metrics.scalar_metrics(), metrics.per_target_metrics()
    every: dict[Any, Metric] = dict(scalar)
    every.update({(name, k): fn for name, fns in per_target.items() for k, fn in enumerate(fns)})
    judged = estimates(every, n, seed)
    out: dict[str, Any] = {name: judged[name] for name in scalar}
    for name, fns in per_target.items():
        out[name] = [judged[name, k] for k in range(len(fns))]
    return out


#: The metrics policies are compared on in pairs (:func:`paired_differences`), and whose
#: coverage :func:`trial_coverage` measures: ARMSE (a root of a mean over trials at each step,
#: biased low on few trials) beside the means over trials.
COVERAGE_METRICS = ("armse", "asr", "final_regret", "mean_sinr_db")


def difference_metrics(all_metrics: Mapping[str, TrialMetrics]) -> dict[tuple[str, str], Metric]:
    """``{("A - B", metric): difference}`` for every pair of policies and every metric of
    :data:`COVERAGE_METRICS` both report: the paired difference of the two metrics on the same
    trial weights."""
    differences: dict[tuple[str, str], Metric] = {}
    for a, b in combinations(all_metrics, 2):
        fa_all, fb_all = all_metrics[a].scalar_metrics(), all_metrics[b].scalar_metrics()
        for name in COVERAGE_METRICS:
            if name not in fa_all or name not in fb_all:
                continue
            fa, fb = fa_all[name], fb_all[name]
            if all(isinstance(f, OfMean) and f.slope is not None for f in (fa, fb)):
                differences[f"{a} - {b}", name] = DifferenceOfMeans(fa, fb)
            else:
                differences[f"{a} - {b}", name] = functools.partial(_difference, fa, fb)
    return differences


def _difference(fa: Metric, fb: Metric, w: NDArray) -> NDArray:
    return fa(w) - fb(w)


def paired_differences(all_metrics: Mapping[str, TrialMetrics], seed: int = 0) -> dict[str, dict[str, dict]]:
    """``{"A - B": {metric: {"estimate", "ci", "method"}}}`` for every pair of policies, paired on
    trials."""
    differences = difference_metrics(all_metrics)
    out: dict[str, dict[str, dict]] = {f"{a} - {b}": {} for a, b in combinations(all_metrics, 2)}
    if not differences:
        return out
    judged = estimates(differences, next(iter(all_metrics.values())).num_trials, seed)
    for (pair, name), result in judged.items():
        out[pair][name] = result
    return out


# ------------------------------------------------------------------ across training seeds
#: How results of learned policies across training seeds are summarised, as rliable does
#: (Agarwal et al., 2021): the mean and the interquartile mean, with stratified bootstrap
#: intervals (the runs of each task resampled within that task).
SEED_METHOD = (
    f"across training seeds: mean and interquartile mean (IQM), {CONFIDENCE:.0%} stratified "
    f"percentile bootstrap over seeds within each scenario (scipy.stats.bootstrap, {RESAMPLES} "
    "resamples), as rliable computes them"
)


def iqm(values: NDArray[np.float64], axis: int = -1) -> NDArray[np.float64]:
    """The interquartile mean: the mean of the middle 50 % of ``values`` along ``axis``
    (``scipy.stats.trim_mean`` cutting 25 % at each end, as rliable's ``aggregate_iqm``)."""
    from scipy import stats

    return stats.trim_mean(values, 0.25, axis=axis)


SEED_STATISTICS: dict[str, Callable[..., NDArray[np.float64]]] = {
    "mean": lambda values, axis=-1: np.mean(values, axis=axis),
    "iqm": iqm,
}


def across_seeds(groups: list[NDArray[np.float64]], statistic: str = "iqm", seed: int = 0) -> dict[str, Any]:
    """``statistic`` (``"mean"`` or ``"iqm"``) of every score of ``groups`` pooled, with its
    stratified bootstrap interval: one group per task (scenario), one score per run (training
    seed) in it; each resample draws every group's runs from that group alone.

    ``scipy.stats.bootstrap`` with one sample per group and ``paired=False`` resamples each
    sample independently, which is the stratified bootstrap; a single run per group has no
    spread, and the interval is then the value itself."""
    if statistic not in SEED_STATISTICS:
        raise ValueError(f"statistic must be one of {list(SEED_STATISTICS)}, got {statistic!r}")
    groups = [np.asarray(g, dtype=np.float64).ravel() for g in groups]
    if not groups or any(g.size == 0 for g in groups):
        raise ValueError("every group needs at least one score")
    function = SEED_STATISTICS[statistic]
    value = float(function(np.concatenate(groups)))
    if all(g.size == 1 for g in groups) or all(np.ptp(g) == 0 for g in groups):
        return {
            "value": value,
            "ci": [value, value],
            "method": SEED_METHOD,
            "runs": int(sum(g.size for g in groups)),
        }

    def pooled(*samples: NDArray[np.float64], axis: int = -1) -> NDArray[np.float64]:
        return function(np.concatenate(samples, axis=axis), axis=axis)

    from scipy import stats

    result = stats.bootstrap(
        tuple(groups),
        pooled,
        n_resamples=RESAMPLES,
        confidence_level=CONFIDENCE,
        method="percentile",
        vectorized=True,
        paired=False,
        random_state=np.random.default_rng(seed),
    )
    low, high = float(result.confidence_interval.low), float(result.confidence_interval.high)
    return {
        "value": value,
        "ci": [min(low, value), max(high, value)],
        "method": SEED_METHOD,
        "runs": int(sum(g.size for g in groups)),
    }


def seed_coverage(
    counts: tuple[int, ...] = (3, 5, 10), groups: int = 1, repeats: int = 400, seed: int = 0
) -> dict[str, Any]:
    """How often :func:`across_seeds`' interval contains the population's mean and IQM, at each
    count of runs per group: ``repeats`` simulated studies per count, ``groups`` tasks of
    normal scores (unit spread, locations 0, 1, 2, ...), each study's interval against the
    statistic of a population of a million scores per task. The RL study's per-scenario rows
    are one group of 3 or 5 seeds; its over-scenario rows three groups."""
    rng = np.random.default_rng(seed)
    locations = np.arange(groups, dtype=np.float64)
    population = np.concatenate([rng.normal(loc, 1.0, 1_000_000) for loc in locations])
    truth = {name: float(function(population)) for name, function in SEED_STATISTICS.items()}
    rows = []
    for count in counts:
        covered = dict.fromkeys(SEED_STATISTICS, 0)
        for r in range(repeats):
            sample = [rng.normal(loc, 1.0, count) for loc in locations]
            for name in covered:
                low, high = across_seeds(sample, name, seed=r)["ci"]
                covered[name] += low <= truth[name] <= high
        rows.append({"runs_per_group": count, **{name: hits / repeats for name, hits in covered.items()}})
    return {"groups": groups, "repeats": repeats, "seed": seed, "method": SEED_METHOD, "coverage": rows}


def trial_coverage(
    population: Mapping[str, TrialMetrics],
    counts: tuple[int, ...] = (20, 50, 200),
    repeats: int = 200,
    seed: int = 0,
    say: Callable[[str], None] = lambda line: None,
) -> dict[str, Any]:
    """How often the interval of a run of ``n`` trials contains the population's value, for each
    of ``counts``, each policy's :data:`COVERAGE_METRICS` and each pair's paired differences of
    them (:func:`paired_differences`): the population is a run's trials (``population``, every
    policy on the same trials), each of ``repeats`` studies draws ``n`` of them with replacement
    (the same draw for every policy; each count's draws a stream of their own, so a count's row
    does not depend on the others) and judges its intervals as a run of ``n`` trials would
    (:func:`estimates`). A metric constant over the drawn trials is left out of that study's
    count, and ARMSE of a run without a tracker. Each row's ``extended`` counts the studies
    whose interval was extended to its value; its ``differences`` holds the same three counts
    for the paired differences, keyed ``"A - B.metric"``. ``say`` gets a line as each count is
    done."""
    size = next(iter(population.values())).num_trials
    truth = {  # ARMSE only where a tracker ran
        (p, k): float(m.scalar_metrics()[k](m.equal()))
        for p, m in population.items()
        for k in COVERAGE_METRICS
        if k in m.scalar_metrics()
    }
    equal = next(iter(population.values())).equal()
    truth_of_differences = {key: float(d(equal)) for key, d in difference_metrics(population).items()}
    truths = truth | truth_of_differences
    rows = []
    for n in counts:
        started = time.perf_counter()
        rng = np.random.default_rng([seed, n])
        counted = {key: [0, 0, 0] for key in truths}  # judged, covered, extended
        for r in range(repeats):
            drawn = rng.integers(0, size, n)
            runs = {policy: full.of_trials(drawn) for policy, full in population.items()}
            metrics = {(p, k): runs[p].scalar_metrics()[k] for p, k in truth} | difference_metrics(runs)
            # one bootstrap of them all: each metric's numbers are those it gets alone (estimates),
            # and a policy's ARMSE on a resample is computed once for it and its differences
            _tally(counted, estimates(metrics, n, seed=r), truths)
        rows.append(
            {
                "trials": n,
                "method": _resampled_method(n) + (FEW_METHODS if n < FEW_TRIALS else ""),
                "confidence_level": confidence_level(n),
                **_rates(counted, truth),
                "differences": _rates(counted, truth_of_differences),
            }
        )
        say(f"{n} trials: {repeats} studies in {time.perf_counter() - started:.0f} s")
    return {"population_trials": size, "repeats": repeats, "seed": seed, "rows": rows}


def _tally(
    counted: dict[tuple[str, str], list[int]], found: Mapping[tuple[str, str], dict], truth: Mapping
) -> None:
    """Counts each interval of ``found`` that is not a constant's: judged, covering its ``truth``,
    extended."""
    for key, judged in found.items():
        if judged["method"] != METHODS["constant"]:
            counted[key][0] += 1
            counted[key][1] += judged["ci"][0] <= truth[key] <= judged["ci"][1]
            counted[key][2] += judged["method"] in EXTENDED


def _rates(counted: dict[tuple[str, str], list[int]], keys: Iterable[tuple[str, str]]) -> dict[str, dict]:
    """A row's ``coverage``, ``studies`` and ``extended``, keyed ``"policy.metric"``, of the
    ``keys`` judged at least once."""
    kept = {key: f"{key[0]}.{key[1]}" for key in keys if counted[key][0]}
    return {
        "coverage": {name: counted[key][1] / counted[key][0] for key, name in kept.items()},
        "studies": {name: counted[key][0] for key, name in kept.items()},
        "extended": {name: counted[key][2] for key, name in kept.items()},
    }


def run_coverage(
    run: str, counts: tuple[int, ...], repeats: int, say: Callable[[str], None] = lambda line: None
) -> dict[str, Any]:
    """:func:`trial_coverage` with the trials of the run in folder ``run`` as the population."""
    import json
    from pathlib import Path

    from benchmarks.harness import RunConfig, load_per_trial

    config = RunConfig(**json.loads((Path(run) / "config.json").read_text()))
    channels = config.scenario_object.num_channels_per_step
    per_trial = load_per_trial(Path(run), config)
    population = {policy: TrialMetrics(joined, channels) for policy, joined in per_trial.items()}
    about = {"scenario": config.scenario["name"], "steps": config.steps, "seed": config.seed}
    about |= {"fusion": config.env_options.get("fusion"), "agent_params": config.agent_params}
    command = "python -m benchmarks.uncertainty --run DIR --counts "
    command += f"{','.join(map(str, counts))} --repeats {repeats}"
    return {"command": command, "run": about, **trial_coverage(population, counts, repeats, say=say)}


if __name__ == "__main__":
    # python -m benchmarks.uncertainty OUT.json: the across-seed coverage;
    # python -m benchmarks.uncertainty --run DIR --counts 20,50 --repeats 200 OUT.json: the
    # coverage of the intervals of runs of fewer trials, drawn from the run in DIR
    import argparse
    import json
    import sys
    from pathlib import Path

    from benchmarks.outputs import output_file, write_json
    from benchmarks.settings import integer, trial_count

    def counts(text: str) -> tuple[int, ...]:
        return tuple(trial_count(MIN_INTERVAL_TRIALS)(part) for part in text.split(","))

    parser = argparse.ArgumentParser(prog="python -m benchmarks.uncertainty")
    parser.add_argument("out", nargs="?", type=output_file, help="the JSON to write (and print)")
    parser.add_argument("--run", default=None, help="a run's folder: the coverage of runs drawn from it")
    parser.add_argument(
        "--counts", type=counts, default=None, help="trials of the runs drawn (default 20,50,200)"
    )
    parser.add_argument("--repeats", type=integer(1), default=None, help="runs drawn per count (default 200)")
    args = parser.parse_args()
    if args.run is not None and not (Path(args.run) / "config.json").is_file():
        parser.error(f"--run {args.run!r} is not a run's folder (no config.json)")
    if args.run is None and (args.counts is not None or args.repeats is not None):
        parser.error(
            "--counts and --repeats are the drawn runs' and need --run (without it: the across-seed coverage)"
        )
    if args.run is None:
        record = {"one_group": seed_coverage(groups=1), "three_groups": seed_coverage(groups=3)}
    else:
        say = functools.partial(print, file=sys.stderr)
        record = run_coverage(args.run, args.counts or (20, 50, 200), args.repeats or 200, say=say)
    write_json(args.out, record)
    print(json.dumps(record, indent=2))
