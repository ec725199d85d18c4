"""Intervals over trials: nominal coverage, paired differences, and what the outputs carry."""

import json

import numpy as np
import pytest
from scipy import stats

from benchmarks import uncertainty
from benchmarks.cli import main


def test_the_bootstrap_interval_covers_a_known_mean_at_its_nominal_rate():
    """200 simulated studies of 60 exponential trials (mean 2): the 95 % interval covers 2 in
    95 % of them, within the binomial test's tolerance."""
    rng = np.random.default_rng(0)
    covered = 0
    repetitions = 200
    for r in range(repetitions):
        x = rng.exponential(2.0, size=60)
        low, high = uncertainty.interval(lambda w, x=x: w @ x, len(x), seed=r)
        covered += low <= 2.0 <= high
    assert stats.binomtest(covered, repetitions, 0.95).pvalue > 0.01, covered


def _policy(expected, squared, optimal=None):
    n, t = expected.shape
    return uncertainty.TrialMetrics(
        {
            "trial_expected": expected,
            "trial_optimal": expected + 1.0 if optimal is None else optimal,
            "trial_squared_error": squared,
            "trial_matches": np.zeros((n, t), np.uint8),
        },
        channels=6,
    )


def test_paired_differences_are_judged_right_on_synthetic_policies():
    rng = np.random.default_rng(1)
    n, t = 80, 50
    base = rng.exponential(1.0, size=(n, t))  # trial-to-trial spread shared by both policies
    squared = rng.exponential(4.0, size=(n, t, 1))
    metrics = {
        "a": _policy(base, squared),
        "same": _policy(base + rng.normal(0, 1e-3, size=(n, t)), squared),  # insignificant
        "better": _policy(base * 1.02, squared * 0.98),  # a 2 % gain, paired
    }
    pairs = uncertainty.paired_differences(metrics)
    sinr = pairs["a - same"]["mean_sinr_db"]["ci"]
    assert sinr[0] < 0 < sinr[1]  # not significant
    gain = pairs["a - better"]
    assert gain["mean_sinr_db"]["ci"][1] < 0  # significant, in the known direction
    assert gain["mean_sinr_db"]["estimate"] == pytest.approx(-10 * np.log10(1.02), rel=1e-9)
    assert gain["armse"]["ci"][0] > 0  # a's error is larger: reversed sign, still significant
    # the pairing matters: unpaired intervals of the two means overlap
    low_a, high_a = uncertainty.interval(metrics["a"].mean_sinr_db, n)
    low_b, high_b = uncertainty.interval(metrics["better"].mean_sinr_db, n)
    assert low_b < high_a


def test_run_outputs_carry_intervals_that_hold_their_values(tmp_path):
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-3", "--policies", "ucb1,epsilon-greedy,best", "--trials", "12"]
    assert main([*argv, "--steps", "40", "--workers", "1", "--quiet", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert "BCa bootstrap" in summary["uncertainty"]
    for row in summary["policies"].values():
        for key in ("armse", "asr", "final_regret", "mean_sinr_db"):
            low, high = row["ci"][key]
            assert low - 1e-4 <= row[key] <= high + 1e-4, (key, row[key], low, high)
        assert len(row["ci"]["armse_per_target"]) == 2
    assert set(summary["paired_differences"]) == {
        "ucb1 - epsilon-greedy",
        "ucb1 - best",
        "epsilon-greedy - best",
    }
    best = summary["policies"]["best"]
    assert best["ci"]["final_regret"] == [0.0, 0.0]  # a constant: the percentile fallback
    table = (out / "table.md").read_text()
    assert "95 % interval" in table and "| ucb1 - best |" in table
    assert (out / "rmse.png").exists() and (out / "regret.png").exists()
