"""The one metrics implementation against formulas computed here by hand and directly."""

import numpy as np
import pytest

from benchmarks.metrics import TrialMetrics, trial_weights


def test_metrics_on_a_hand_made_case():
    # 2 trials, 3 steps, 2 targets, per trial
    squared = np.array([[1.0, 4.0], [9.0, 16.0], [0.0, 1.0]])
    m = TrialMetrics(
        {
            "trial_expected": np.array([[3.0, 5.0, 2.0], [3.0, 5.0, 2.0]]),
            "trial_optimal": np.array([[5.0, 5.0, 6.0], [5.0, 5.0, 6.0]]),
            "trial_squared_error": np.stack([squared, squared]),
            "trial_matches": np.array([[1, 1, 0], [1, 0, 0]]),
        },
        channels=6,
    )
    w = m.equal()
    per_target = [float(m.armse(w, target=k)) for k in range(2)]
    assert per_target == pytest.approx([(1 + 3 + 0) / 3, (2 + 4 + 1) / 3])
    assert float(m.armse(w)) == pytest.approx(np.mean(per_target))
    assert float(m.asr(w)) == pytest.approx(0.5)
    np.testing.assert_allclose(m.regret_curve(w), [2.0, 2.0, 6.0])
    one = TrialMetrics(
        {
            "trial_expected": np.array([[60.0, 60.0]]),
            "trial_optimal": np.array([[60.0, 60.0]]),
            "trial_matches": np.ones((1, 2)),
        },
        channels=6,
    )
    assert float(one.mean_sinr_db(one.equal())) == pytest.approx(10.0)


def _random_policy(rng, n=7, t=30, k=2):
    expected = rng.exponential(2.0, size=(n, t))
    return TrialMetrics(
        {
            "trial_expected": expected,
            "trial_optimal": expected + rng.exponential(1.0, size=(n, t)),
            "trial_squared_error": rng.exponential(4.0, size=(n, t, k)),
            "trial_bound_squared": rng.exponential(1.0, size=(n, t, k)),
            "trial_matches": rng.integers(0, 2, size=(n, t)),
        },
        channels=6,
    )


def test_every_metric_equals_its_formula_with_loops_at_any_weights():
    rng = np.random.default_rng(0)
    m = _random_policy(rng)
    n, t = m.num_trials, m.steps
    for w in (m.equal(), trial_weights(rng.integers(0, n, size=n), n)):
        assert w.sum() == pytest.approx(1.0)
        rmse = [
            [np.sqrt(sum(w[i] * m.squared[i, s, k] for i in range(n))) for s in range(t)] for k in range(2)
        ]
        assert float(m.armse(w)) == pytest.approx(np.mean([np.mean(r) for r in rmse]), rel=1e-12)
        assert float(m.armse(w, window=(5, 12), target=1)) == pytest.approx(np.mean(rmse[1][5:12]), rel=1e-12)
        bound = [
            [np.sqrt(sum(w[i] * m.bound_squared[i, s, k] for i in range(n))) for s in range(t)]
            for k in range(2)
        ]
        assert float(m.bound(w)) == pytest.approx(np.mean([np.mean(b) for b in bound]), rel=1e-12)
        assert float(m.armse_over_bound(w)) == pytest.approx(float(m.armse(w)) / float(m.bound(w)))
        regret = sum(w[i] * sum(m.optimal[i, s] - m.expected[i, s] for s in range(20)) for i in range(n))
        assert float(m.regret(w, at=20)) == pytest.approx(regret, rel=1e-12)
        assert float(m.final_regret(w)) == pytest.approx(float(m.regret_curve(w)[-1]), rel=1e-12)
        mean_mu = sum(w[i] * m.expected[i, 10:20].mean() for i in range(n))
        assert float(m.mean_sinr_db(w, window=(10, 20))) == pytest.approx(
            10 * np.log10(mean_mu / 6), rel=1e-12
        )
        assert float(m.asr(w)) == pytest.approx(sum(w[i] * m.matches[i].mean() for i in range(n)), rel=1e-12)
        np.testing.assert_allclose(m.asr_curve(w), w @ m.matches)


def test_weights_count_the_resampled_trials_and_batch():
    index = np.array([[0, 0, 2], [1, 2, 2]])
    np.testing.assert_allclose(trial_weights(index, 3), [[2 / 3, 0, 1 / 3], [0, 1 / 3, 2 / 3]])
    m = _random_policy(np.random.default_rng(1))
    batch = trial_weights(np.random.default_rng(2).integers(0, m.num_trials, (4, m.num_trials)), m.num_trials)
    np.testing.assert_allclose(m.armse(batch), [float(m.armse(w)) for w in batch], rtol=1e-12)


def test_the_metrics_of_some_trials_are_the_whole_runs_at_their_weights():
    """``of_trials(index)`` is a run of the trials ``index`` (repeats allowed): each metric at its
    equal weights is the whole run's at the weights that count them."""
    m = _random_policy(np.random.default_rng(3))
    index = np.array([4, 0, 4, 6, 2])
    part = m.of_trials(index)
    assert part.num_trials == 5 and part.tracked and part.bounded
    weights = trial_weights(index, m.num_trials)
    for name, metric in m.scalar_metrics().items():
        assert float(part.scalar_metrics()[name](part.equal())) == pytest.approx(
            float(metric(weights)), rel=1e-12
        )


def test_a_run_without_a_tracker_has_no_position_metrics():
    m = TrialMetrics(
        {
            "trial_expected": np.ones((2, 3)),
            "trial_optimal": np.ones((2, 3)),
            "trial_matches": np.ones((2, 3)),
            "trial_squared_error": np.full((2, 3, 1), np.nan),
            "trial_bound_squared": np.full((2, 3, 1), np.nan),
        },
        channels=1,
    )
    assert set(m.scalar_metrics()) == {"asr", "final_regret", "mean_sinr_db"} and m.per_target_metrics() == {}
    with pytest.raises(ValueError, match="no tracker"):
        m.armse(m.equal())
