"""A new metric is one file: a metric defined and registered in this file alone is reported by a
run, in summary.json with its 95 % interval and in table.md, with no other edit."""

import json

import pytest

from benchmarks.harness import make_config, run
from benchmarks.metrics import EXTRA_METRICS, register_metric
from benchmarks.report import write_outputs


def late_regret(metrics, w):
    """The mean regret per step over the last half of the run (trial-weighted)."""
    half = metrics.steps // 2
    per_trial = (metrics.optimal - metrics.expected)[:, half:].mean(axis=1)
    return w @ per_trial


@pytest.fixture
def metric():
    register_metric("late_regret", late_regret)
    yield "late_regret"
    EXTRA_METRICS.pop("late_regret")


def test_a_registered_metric_is_reported_with_its_interval(metric, tmp_path):
    config = make_config("paper-1-v1", ["ucb1", "best"], trials=6, steps=12, say=lambda message: None)
    per_trial = run(config, tmp_path, progress=False)
    summary = write_outputs(config, per_trial, tmp_path, figures=False)
    for policy in ("ucb1", "best"):
        row = summary["policies"][policy]
        regret = per_trial[policy]["trial_optimal"] - per_trial[policy]["trial_expected"]
        assert row[metric] == pytest.approx(regret[:, 6:].mean(), rel=1e-12)
        low, high = row["ci"][metric]
        assert low <= row[metric] <= high
    assert abs(summary["policies"]["best"][metric]) < 1e-12 < summary["policies"]["ucb1"][metric]
    assert json.loads((tmp_path / "summary.json").read_text())["policies"]["ucb1"][metric] > 0
    header = (tmp_path / "table.md").read_text().splitlines()
    assert any(line.startswith("| policy |") and "| late_regret |" in line for line in header)


def test_a_metric_may_not_take_a_reported_name():
    with pytest.raises(ValueError, match="already reported"):
        register_metric("armse", late_regret)
    with pytest.raises(ValueError, match="identifier"):
        register_metric("late regret", late_regret)
    assert "armse" not in EXTRA_METRICS and "late regret" not in EXTRA_METRICS
