"""One verdict rule: a claim, a tracking target and a calibration score judge alike."""

import numpy as np
import pytest

from benchmarks import uncertainty, verdicts
from benchmarks.metrics import TrialMetrics
from benchmarks.studies import calibration, claims, tracking


def test_the_rule_on_intervals():
    assert verdicts.verdict([-2.0, -1.0], -1) == "holds"
    assert verdicts.verdict([1.0, 2.0], -1) == "contradicted"
    assert verdicts.verdict([-1.0, 0.5], -1) == "consistent"
    assert verdicts.verdict([1.0, 2.0], +1) == "holds"
    assert verdicts.verdict([0.0, 2.0], +1) == "consistent"  # an interval that reaches 0
    with pytest.raises(ValueError, match="sign must be"):
        verdicts.verdict([1.0, 2.0], 0)
    assert verdicts.combine(["holds", "holds"]) == "holds"
    assert verdicts.combine(["holds", "not evaluated"]) == "consistent"
    assert verdicts.count(["holds", "contradicted", "holds"]) == {
        "holds": 2,
        "consistent": 0,
        "contradicted": 1,
    }
    assert verdicts.rank_key({"holds": 3, "consistent": 0, "contradicted": 1}) > verdicts.rank_key(
        {"holds": 3, "consistent": 1, "contradicted": 2}
    )


def _policy(squared):
    n, t, _ = squared.shape
    return TrialMetrics(
        {
            "trial_expected": np.ones((n, t)),
            "trial_optimal": np.full((n, t), 2.0),
            "trial_squared_error": squared,
            "trial_matches": np.zeros((n, t)),
        },
        channels=6,
    )


@pytest.mark.parametrize(
    ("factor", "expected"), [(0.8, "holds"), (0.999, "consistent"), (1.3, "contradicted")]
)
def test_a_claim_a_target_and_a_calibration_score_give_the_same_verdict(factor, expected):
    """ "a has a lower ARMSE than b" judged three ways on the same synthetic trials."""
    rng = np.random.default_rng(5)
    base = rng.exponential(4.0, size=(60, 30, 1))
    noise = rng.normal(1.0, 0.02, size=base.shape)
    metrics = {"a": _policy(base * factor * noise), "b": _policy(base)}
    # the claims' way: a comparison on the policies' per-trial metrics
    comparison = claims._diff("armse", "a", "b", -1)
    as_claim = claims.judge(comparison, claims.Policies(metrics), seed=0)
    # the tracking study's way: from a summary's paired differences
    summary = {"paired_differences": uncertainty.paired_differences(metrics, seed=0)}
    as_target = tracking._lower(summary, "a", "b")
    # the calibration's way: counting a scorecard's verdicts
    counts = calibration.scorecard_counts([{"verdict": as_claim["verdict"]}])
    assert as_claim["verdict"] == as_target["verdict"] == expected
    assert as_claim["ci"] == pytest.approx(as_target["ci"]) and counts[expected] == 1
    assert as_target["holds"] == (expected == "holds")
