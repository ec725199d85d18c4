"""Developer tools: speed and memory measurements, each printed as a ratio to a reference
measured in the same run. Not installed with the package (they need a source checkout):
``python -m benchmarks.speed.tracker_speed``, ``mimo-radar-bench perf`` from a checkout."""

from collections.abc import Sequence


def t_interval(values: Sequence[float]) -> tuple[float, float]:
    """The 95 % t interval of the mean of repeated timings (two or more; a spread of 0 gives the
    value itself)."""
    import numpy as np
    from scipy import stats

    values = np.asarray(values, dtype=float)
    spread = stats.sem(values)
    if spread == 0:
        return float(values.mean()), float(values.mean())
    low, high = stats.t.interval(0.95, len(values) - 1, values.mean(), spread)
    return float(low), float(high)
