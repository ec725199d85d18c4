"""The evaluation metrics (docs/model.md, section 11): one implementation, from per-trial arrays.

Every metric a run reports is a function of the per-trial arrays of one policy (float64,
trials first) and of *trial weights* ``w`` of shape ``(..., N)`` that sum to 1 over the
trials. The reported value is the metric at equal weights (:meth:`TrialMetrics.equal`); the
bootstrap of :mod:`benchmarks.uncertainty` evaluates the very same function on resampled
weights (how often each trial was drawn), so an estimate and its interval can never come
from two computations. Curves are the same functions before the average over steps.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
from numpy.typing import NDArray

#: Steps ``[start, stop)``; ``None`` is the whole run.
Window = tuple[int, int] | None
#: The per-trial arrays a run records for each policy (shard fields of the harness).
TRIAL_FIELDS = (
    "trial_expected",
    "trial_optimal",
    "trial_squared_error",
    "trial_bound_squared",
    "trial_matches",
)


#: Metrics of one's own, reported beside the built-in ones: ``name -> function(metrics, w)``
#: (:func:`register_metric`).
EXTRA_METRICS: dict[str, Callable[[TrialMetrics, NDArray], NDArray]] = {}


def register_metric(name: str, function: Callable[[TrialMetrics, NDArray], NDArray]) -> None:
    """Report ``function(metrics, w)`` as metric ``name`` in every run's summary, with its 95 %
    interval from the same bootstrap as the built-in metrics: a function of one policy's
    :class:`TrialMetrics` and of trial weights ``w`` (..., N) summing to 1 over the trials,
    giving one value per row of ``w``."""
    if not name.isidentifier():
        raise ValueError(f"a metric's name is an identifier (it is a key of summary.json), got {name!r}")
    if name in _BUILT_IN or (name in EXTRA_METRICS and EXTRA_METRICS[name] is not function):
        raise ValueError(f"a metric called {name!r} is already reported")
    EXTRA_METRICS[name] = function


class OfMean:
    """A metric that is a strictly increasing function of a mean over trials: ``outer(mean(w))``
    (mean SINR in dB, a logarithm of the mean SINR). It is evaluated as any metric; on a few trials
    :func:`benchmarks.uncertainty.estimates` gives it the interval of ``mean`` mapped through
    ``outer``, as the bootstrap-t of a mean is not a bootstrap of the metric's own resamples.
    ``slope``, the derivative of ``outer`` where given, studentizes the paired differences of two
    such metrics (:class:`DifferenceOfMeans`)."""

    def __init__(
        self,
        mean: Callable[[NDArray], NDArray],
        outer: Callable[[NDArray], NDArray],
        slope: Callable[[NDArray], NDArray] | None = None,
    ) -> None:
        self.mean = mean
        self.outer = outer
        self.slope = slope

    def __call__(self, w: NDArray) -> NDArray:
        return self.outer(self.mean(w))


class DifferenceOfMeans:
    """``a(w) - b(w)`` of two :class:`OfMean` metrics with slopes, paired on the same trials (a
    difference of mean SINRs in dB). On a few trials :func:`benchmarks.uncertainty.estimates`
    gives it a bootstrap-t interval whose standard error is the delta method's: that of the mean
    of each trial's ``a.slope(mean_a) x_a - b.slope(mean_b) x_b``, on every resample."""

    def __init__(self, a: OfMean, b: OfMean) -> None:
        for name, metric in (("a", a), ("b", b)):
            if not isinstance(metric, OfMean):
                raise TypeError(f"DifferenceOfMeans's {name} must be an OfMean, got {type(metric).__name__}")
            if metric.slope is None:
                raise ValueError(
                    f"DifferenceOfMeans's {name} must be an OfMean with a slope (the derivative of its outer)"
                )
        self.a, self.b = a, b

    def __call__(self, w: NDArray) -> NDArray:
        return self.a(w) - self.b(w)


def decibels(ratio: NDArray) -> NDArray:
    """``10 log10(ratio)``."""
    return 10.0 * np.log10(ratio)


def decibels_slope(ratio: NDArray) -> NDArray:
    """The derivative of :func:`decibels`: ``10 / (ln 10 ratio)``."""
    return 10.0 / (np.log(10.0) * ratio)


def trial_weights(index: NDArray, num_trials: int) -> NDArray[np.float64]:
    """Resampled trial indices ``(..., n)`` as weights ``(..., num_trials)`` that sum to 1
    (``arange(num_trials)`` gives the equal weights of the estimate)."""
    index = np.asarray(index)
    rows = index.reshape(-1, index.shape[-1])
    flat = (rows + num_trials * np.arange(rows.shape[0])[:, None]).ravel()  # row r's trials at r * N
    counts = np.bincount(flat, minlength=rows.shape[0] * num_trials).reshape(rows.shape[0], num_trials)
    return (counts / rows.shape[1]).reshape((*index.shape[:-1], num_trials))


class TrialMetrics:
    """One policy's metrics as functions of trial weights ``w`` (..., N).

    Parameters
    ----------
    per_trial : mapping
        ``trial_expected`` and ``trial_optimal`` (N, T): the mean reward ``mu_t`` of the
        selected and of the optimal super arm; ``trial_matches`` (N, T): 1 where the selection
        was the optimal one; optionally ``trial_squared_error`` and ``trial_bound_squared``
        (N, T, K): the squared position error of the tracks and the squared position bound of
        the selections made (NaN, or absent, without a tracker).
    channels : int
        ``Ms * Ns``, the channels probed per step.
    """

    def __init__(self, per_trial: Mapping[str, NDArray], channels: int) -> None:
        self.expected = np.asarray(per_trial["trial_expected"], np.float64)
        self.optimal = np.asarray(per_trial["trial_optimal"], np.float64)
        self.matches = np.asarray(per_trial["trial_matches"], np.float64)
        self.num_trials, self.steps = self.expected.shape
        self.channels = channels
        squared = per_trial.get("trial_squared_error")
        self.squared = None if squared is None else np.asarray(squared, np.float64)  # (N, T, K)
        self.tracked = self.squared is not None and bool(np.isfinite(self.squared).all())
        bound = per_trial.get("trial_bound_squared")
        self.bound_squared = None if bound is None else np.asarray(bound, np.float64)
        self.bounded = (
            self.tracked and self.bound_squared is not None and bool(np.isfinite(self.bound_squared).all())
        )
        self.num_targets = self.squared.shape[2] if self.squared is not None else 0
        self._regret_steps = np.cumsum(self.optimal - self.expected, axis=1)  # (N, T)
        # the time-averaged RMS of the last few weight arrays, by (array, span, target): a
        # bootstrap evaluates ARMSE, the bound, their ratio and every paired difference on the
        # same resampled weights (the same object: uncertainty's weights are shared)
        self._averages: dict[tuple[int, int | None, int | None, int], list[tuple[NDArray, NDArray]]] = {}

    def of_trials(self, index: NDArray[np.integer]) -> TrialMetrics:
        """The metrics of the trials ``index`` (repeats allowed): a run of ``len(index)`` trials."""
        fields = {
            "trial_expected": self.expected,
            "trial_optimal": self.optimal,
            "trial_matches": self.matches,
            "trial_squared_error": self.squared,
            "trial_bound_squared": self.bound_squared,
        }
        return TrialMetrics({k: v[index] for k, v in fields.items() if v is not None}, self.channels)

    # ------------------------------------------------------------ weights
    def equal(self) -> NDArray[np.float64]:
        """The equal trial weights at which every reported value is evaluated."""
        return trial_weights(np.arange(self.num_trials), self.num_trials)

    def _span(self, window: Window) -> slice:
        a, b = window or (0, self.steps)
        return slice(a, b)

    # ------------------------------------------------------------ SINR and regret
    def sinr_db_curve(self, w: NDArray) -> NDArray:
        """Average SINR (dB) at each step: ``10 log10(mean over trials of mu_t / (Ms Ns))``, (..., T)."""
        return decibels(w @ self.expected / self.channels)

    def mean_sinr(self, w: NDArray, window: Window = None) -> NDArray:
        """The mean over trials and the window's steps of ``mu_t / (Ms Ns)`` (linear)."""
        return w @ self.expected[:, self._span(window)].mean(axis=1) / self.channels

    def mean_sinr_db(self, w: NDArray, window: Window = None) -> NDArray:
        """:meth:`mean_sinr` in dB."""
        return decibels(self.mean_sinr(w, window))

    def regret_curve(self, w: NDArray) -> NDArray:
        """Cumulative regret ``sum_{s <= t} (mu*_s - mu_s)``, mean over trials (eq13), (..., T)."""
        return w @ self._regret_steps

    def regret(self, w: NDArray, at: int | None = None) -> NDArray:
        """The cumulative regret at step ``at`` (1-based; default the last)."""
        return w @ self._regret_steps[:, (at or self.steps) - 1]

    def final_regret(self, w: NDArray) -> NDArray:
        return self.regret(w)

    # ------------------------------------------------------------ selection
    def asr_curve(self, w: NDArray) -> NDArray:
        """The fraction of trials whose super arm is the optimal one at each step, (..., T)."""
        return w @ self.matches

    def asr(self, w: NDArray) -> NDArray:
        """eq33: the mean over trials and steps of ``1[A_t == A_Best,t]``, in [0, 1]."""
        return w @ self.matches.mean(axis=1)

    # ------------------------------------------------------------ tracking
    def rmse_curve(self, w: NDArray, target: int) -> NDArray:
        """``RMSE_k(t) = sqrt(mean over trials of the squared position error)``, (..., T)."""
        return _root_mean_square(self._tracked(self.squared), w, target)

    def armse(self, w: NDArray, window: Window = None, target: int | None = None) -> NDArray:
        """The mean over the window's steps of ``RMSE_k(t)``, averaged over targets with equal
        weights (or of one ``target``)."""
        return self._time_averaged(self._tracked(self.squared), w, self._span(window), target)

    def armse_target(self, target: int):
        """``w -> armse(w, target=target)``."""
        return lambda w: self.armse(w, target=target)

    def bound_curve(self, w: NDArray, target: int) -> NDArray:
        """The root-mean-square position bound of the selections made at each step, (..., T)."""
        return _root_mean_square(self._bounded(), w, target)

    def bound(self, w: NDArray, window: Window = None, target: int | None = None) -> NDArray:
        """The bound averaged as ARMSE averages the RMSE: the floor the selections set."""
        return self._time_averaged(self._bounded(), w, self._span(window), target)

    def bound_target(self, target: int):
        return lambda w: self.bound(w, target=target)

    def armse_over_bound(self, w: NDArray) -> NDArray:
        return self.armse(w) / self.bound(w)

    def _time_averaged(self, squared: NDArray, w: NDArray, span: slice, target: int | None) -> NDArray:
        """The mean over targets (or one) of the mean over the span's steps of the root mean
        square; each target's term is kept for the last :data:`REMEMBERED_WEIGHTS` weight arrays."""
        targets = range(squared.shape[2]) if target is None else [target]
        terms = []
        for k in targets:
            remembered = self._averages.setdefault((id(squared), span.start, span.stop, k), [])
            term = next((value for weights, value in remembered if weights is w), None)
            if term is None:
                term = _root_mean_square(squared, w, k, span).mean(axis=-1)
                remembered.insert(0, (w, term))
                del remembered[REMEMBERED_WEIGHTS:]
            terms.append(term)
        return np.mean(terms, axis=0)

    def _tracked(self, squared: NDArray | None) -> NDArray:
        if not self.tracked or squared is None:
            raise ValueError("this run has no tracker (tracking=False): it has no position error")
        return squared

    def _bounded(self) -> NDArray:
        if not self.bounded or self.bound_squared is None:
            raise ValueError("this run recorded no position bound")
        return self.bound_squared

    # ------------------------------------------------------------ the table
    def scalar_metrics(self) -> dict:
        """The table's metrics, ``{name: w -> value}`` (ARMSE only with a tracker; the bound and
        ARMSE / bound only where the bound was recorded), then the registered ones
        (:func:`register_metric`)."""
        metrics = {"asr": self.asr, "final_regret": self.final_regret}
        metrics["mean_sinr_db"] = OfMean(self.mean_sinr, decibels, decibels_slope)
        if self.tracked:
            metrics["armse"] = self.armse
        if self.bounded:
            metrics["bound"] = self.bound
            metrics["armse_over_bound"] = self.armse_over_bound
        for name, function in EXTRA_METRICS.items():
            metrics[name] = lambda w, function=function: function(self, w)
        return metrics

    def per_target_metrics(self) -> dict:
        """``{name: [w -> value of target k]}`` for ARMSE and the bound."""
        out = {}
        if self.tracked:
            out["armse_per_target"] = [self.armse_target(k) for k in range(self.num_targets)]
        if self.bounded:
            out["bound_per_target"] = [self.bound_target(k) for k in range(self.num_targets)]
        return out


_BUILT_IN = ("asr", "final_regret", "mean_sinr_db", "armse", "bound", "armse_over_bound")


def _root_mean_square(squared: NDArray, w: NDArray, target: int, span: slice = slice(None)) -> NDArray:
    """``sqrt`` of the trial-weighted mean of squared values (N, T, K) for one target over the
    span's steps: (..., steps)."""
    return np.sqrt(w @ squared[:, span, target])


#: How many weight arrays a policy's time-averaged RMS terms are kept for: a bootstrap's
#: resamples, its jackknife and the equal weights.
REMEMBERED_WEIGHTS = 4
