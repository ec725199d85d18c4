"""Intervals over trials: nominal coverage, paired differences, and what the outputs carry."""

import functools
import json

import numpy as np
import pytest
from scipy import stats

from benchmarks import report, uncertainty
from benchmarks.cli import main
from benchmarks.metrics import DifferenceOfMeans, OfMean, trial_weights


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


@pytest.mark.parametrize(
    ("draw", "trials", "method", "level"),
    [("normal", 6, "percentile", 0.95), ("normal", 10, "percentile", 0.95)]
    + [("exponential", 10, "percentile", None), ("exponential", 20, "BCa", None)],
)
def test_on_a_few_trials_the_bootstrap_t_covers_a_mean_at_its_nominal_rate(draw, trials, method, level):
    """400 simulated studies of a few normal trials (mean 2) or exponential ones (mean 1; skewed,
    as a policy's final regret is): a mean's interval, the bootstrap-t, covers the mean in 95 % of
    them, within the binomial test's tolerance, where an interval of the same resamples covers
    significantly less: on normal trials the percentile interval at 95 %; on exponential ones the
    interval a mean got before the bootstrap-t (percentile at the expanded level below 20
    trials, BCa from 20)."""
    rng = np.random.default_rng(trials)
    mean = 2.0 if draw == "normal" else 1.0
    covered, other, repetitions = 0, 0, 400
    for r in range(repetitions):
        x = rng.normal(mean, 1.0, trials) if draw == "normal" else rng.exponential(mean, trials)
        judged = uncertainty.estimate(lambda w, x=x: w @ x, trials, seed=r)
        assert judged["method"] == "bootstrap-t"
        covered += judged["ci"][0] <= mean <= judged["ci"][1]
        resampled = stats.bootstrap(
            (x,),
            np.mean,
            n_resamples=uncertainty.RESAMPLES,
            method=method,
            confidence_level=level or uncertainty.confidence_level(trials),
            random_state=np.random.default_rng(r),
        ).confidence_interval
        other += resampled.low <= mean <= resampled.high
    assert stats.binomtest(covered, repetitions, 0.95).pvalue > 0.01, covered
    assert stats.binomtest(other, repetitions, 0.95, alternative="less").pvalue < 0.01, other


def test_on_a_few_trials_a_logarithm_of_a_mean_is_covered_through_its_means_bootstrap_t():
    """400 simulated studies of 30 exponential trials (mean 1): the log of their mean, declared a
    function of it (``OfMean``, as mean SINR in dB is), gets its mean's bootstrap-t interval
    mapped through the log, which covers log 1 = 0 in 95 % of them, within the binomial test's
    tolerance; judged as any biased metric (the bias-corrected percentile interval it got
    before) it is covered significantly less."""
    trials, repetitions = 30, 400
    rng = np.random.default_rng(trials)
    covered, before = 0, 0
    for r in range(repetitions):
        x = rng.exponential(1.0, trials)
        judged = uncertainty.estimate(OfMean(lambda w, x=x: w @ x, np.log), trials, seed=r)
        assert judged["method"] == "bootstrap-t"
        covered += judged["ci"][0] <= 0.0 <= judged["ci"][1]
        plain = uncertainty.estimate(lambda w, x=x: np.log(w @ x), trials, seed=r)
        assert plain["method"] == "bias-corrected percentile"
        before += plain["ci"][0] <= 0.0 <= plain["ci"][1]
    assert stats.binomtest(covered, repetitions, 0.95).pvalue > 0.01, covered
    assert stats.binomtest(before, repetitions, 0.95, alternative="less").pvalue < 0.01, before


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("trials", [10, 30, 60])
def test_a_means_interval_near_the_float_limits_is_the_same_interval_scaled(trials):
    """Trials of values near 1e270 or 1e-270 (a power of two times those of 1) get, with no
    warning, the interval of the values of 1 scaled, bit for bit, below 40 trials (the bootstrap-t's
    variances are taken of values scaled to 1); from 40, BCa's sums of cubes overflow inside scipy
    and the percentile interval of the same resamples stands in, scaled too."""
    x = np.random.default_rng(trials).exponential(1.0, trials)
    plain = uncertainty.estimate(lambda w: w @ x, trials, seed=2)
    for exponent in (900, -900):
        values = np.ldexp(x, exponent)
        scaled = uncertainty.estimate(lambda w, values=values: w @ values, trials, seed=2)
        ci = [np.ldexp(end, -exponent) for end in scaled["ci"]]
        if trials < uncertainty.FEW_TRIALS:
            assert scaled["method"] == plain["method"] == "bootstrap-t" and ci == plain["ci"]
        else:
            assert scaled["method"] == "percentile" and ci[0] <= np.mean(x) <= ci[1]
            alone = stats.bootstrap(
                (x,),
                np.mean,
                n_resamples=uncertainty.RESAMPLES,
                method="percentile",
                random_state=np.random.default_rng(2),
            ).confidence_interval
            assert ci == pytest.approx([alone.low, alone.high], rel=1e-12)


def _log_of_mean(x):
    return OfMean(lambda w: w @ x, np.log, np.reciprocal)


def test_on_a_few_trials_a_difference_of_logarithms_of_means_is_covered_by_the_delta_methods_t():
    """400 simulated studies of 30 paired trials (two exponentials of means 1/2 and 1 times a factor
    they share): the log of the ratio of their means, declared a difference of two ``OfMean`` with
    slopes (as a paired difference of mean SINRs in dB is), gets the delta method's bootstrap-t,
    which covers log(1/2) in 95 % of them, within the binomial test's tolerance; judged as any
    biased metric (the bias-corrected percentile interval it got before) it is covered
    significantly less (bias-corrected, or BCa where its bias is nil)."""
    trials, repetitions = 30, 400
    rng = np.random.default_rng(11)
    covered, before, truth = 0, 0, np.log(0.5)
    for r in range(repetitions):
        shared = rng.exponential(1.0, trials)
        x, y = shared * rng.exponential(0.5, trials), shared * rng.exponential(1.0, trials)
        judged = uncertainty.estimate(DifferenceOfMeans(_log_of_mean(x), _log_of_mean(y)), trials, seed=r)
        assert judged["method"].startswith("bootstrap-t")
        covered += judged["ci"][0] <= truth <= judged["ci"][1]
        plain = uncertainty.estimate(lambda w, x=x, y=y: np.log(w @ x) - np.log(w @ y), trials, seed=r)
        assert not plain["method"].startswith("bootstrap-t")  # bias-corrected, or BCa where no bias
        before += plain["ci"][0] <= truth <= plain["ci"][1]
    assert stats.binomtest(covered, repetitions, 0.95).pvalue > 0.01, covered
    assert stats.binomtest(before, repetitions, 0.95, alternative="less").pvalue < 0.01, before


@pytest.mark.filterwarnings("error")
def test_a_difference_of_logarithms_of_means_near_the_float_limits_has_the_interval_of_values_near_1():
    """The delta method's moments are taken of values scaled to 1 too: trials near 2^900 or 2^-900
    give, with no warning, the interval of the same trials near 1 (the logs differ by rounding)."""
    rng = np.random.default_rng(3)
    x, y = rng.exponential(1.0, 12), rng.exponential(2.0, 12)
    plain = uncertainty.estimate(DifferenceOfMeans(_log_of_mean(x), _log_of_mean(y)), 12, seed=1)
    for exponent in (900, -900):
        a, b = np.ldexp(x, exponent), np.ldexp(y, exponent)
        far = uncertainty.estimate(DifferenceOfMeans(_log_of_mean(a), _log_of_mean(b)), 12, seed=1)
        assert far["method"] == plain["method"] == "bootstrap-t"
        assert far["ci"] == pytest.approx(plain["ci"], rel=1e-9)


def test_a_difference_of_means_is_made_of_two_functions_of_means_with_slopes():
    x = np.ones(5)
    with pytest.raises(TypeError, match="DifferenceOfMeans's b must be an OfMean, got function"):
        DifferenceOfMeans(_log_of_mean(x), lambda w: w @ x)
    with pytest.raises(ValueError, match="DifferenceOfMeans's a must be an OfMean with a slope"):
        DifferenceOfMeans(OfMean(lambda w: w @ x, np.log), _log_of_mean(x))


@pytest.mark.parametrize("trials", [10, 30, 60])
def test_a_difference_of_logarithms_of_means_is_studentized_on_scipys_own_resamples(trials):
    """Below 40 trials the interval of ``log(mean x) - log(mean y)`` on paired trials is the
    bootstrap-t computed here from scipy's paired resamples: each resample's t is its distance
    from the value in the delta method's standard error at its own means (the standard error of
    the mean of ``x / mean x - y / mean y``), its 2.5 % and 97.5 % quantiles turned around over
    the standard error of the trials; from 40 trials, BCa's interval, as any metric's."""
    rng = np.random.default_rng(trials)
    shared = rng.exponential(1.0, trials)
    x, y = shared * rng.exponential(1.0, trials), shared * rng.exponential(2.0, trials)
    metric = DifferenceOfMeans(_log_of_mean(x), _log_of_mean(y))
    got = uncertainty.estimate(metric, trials, seed=5)
    value = np.log(x.mean()) - np.log(y.mean())
    assert got["estimate"] == pytest.approx(value, rel=1e-12)

    def resampled(statistic):
        return stats.bootstrap(
            (x, y),
            statistic,
            paired=True,
            n_resamples=uncertainty.RESAMPLES,
            method="BCa" if trials >= uncertainty.BCA_MIN_TRIALS else "percentile",
            confidence_level=uncertainty.confidence_level(trials),
            random_state=np.random.default_rng(5),
        )

    def error(a, b, axis=-1):
        means_a, means_b = np.mean(a, axis, keepdims=True), np.mean(b, axis, keepdims=True)
        return np.std(a / means_a - b / means_b, axis=axis, ddof=1) / np.sqrt(trials)

    def difference(a, b, axis=-1):
        return np.log(np.mean(a, axis)) - np.log(np.mean(b, axis))

    if trials >= uncertainty.FEW_TRIALS:
        ci = resampled(difference).confidence_interval
        assert got["method"] == "BCa" and got["ci"] == pytest.approx([ci.low, ci.high], rel=1e-9)
        return
    t = (resampled(difference).bootstrap_distribution - value) / resampled(error).bootstrap_distribution
    t_high, t_low = np.percentile(t, [97.5, 2.5])
    low, high = value - t_high * error(x, y), value - t_low * error(x, y)
    assert got["method"].startswith("bootstrap-t")
    assert got["ci"] == pytest.approx([min(low, value), max(high, value)], rel=1e-9)


@pytest.mark.parametrize("trials", [10, 30])
def test_a_root_of_a_mean_over_many_steps_is_covered_at_its_nominal_rate_once_bias_corrected(trials):
    """300 simulated studies of a few trials of 400 steps of squared errors of mean 1 (as a 2-D
    position error's): the ARMSE of many trials is 1, while a study's, a root of a mean over its
    trials at each step, is biased low by about 1 / (8 n) and its spread averages down over the
    steps. The bias-corrected interval covers 1 at 95 %, within the binomial test's tolerance;
    the percentile interval of the same resamples covers significantly less."""
    rng = np.random.default_rng(trials)
    covered, plain, repetitions = 0, 0, 300
    for r in range(repetitions):
        squared = rng.exponential(1.0, (trials, 400))
        estimate = uncertainty.estimate(lambda w, x=squared: np.sqrt(w @ x).mean(axis=-1), trials, seed=r)
        assert estimate["method"].startswith("bias-corrected percentile")
        covered += estimate["ci"][0] <= 1.0 <= estimate["ci"][1]
        resampled = stats.bootstrap(
            (np.arange(trials),),
            lambda i, axis=-1, x=squared: np.sqrt(trial_weights(i, trials) @ x).mean(axis=-1),
            vectorized=True,
            n_resamples=uncertainty.RESAMPLES,
            method="percentile",
            confidence_level=uncertainty.confidence_level(trials),
            random_state=np.random.default_rng(r),
        ).confidence_interval
        plain += resampled.low <= 1.0 <= resampled.high
    assert stats.binomtest(covered, repetitions, 0.95).pvalue > 0.01, covered
    assert stats.binomtest(plain, repetitions, 0.95, alternative="less").pvalue < 0.01, plain


def test_the_jackknife_bias_is_that_of_leaving_out_each_trial_and_none_for_a_mean():
    """``jackknife_bias`` against the leave-one-out values computed one by one, for a root of a
    mean (biased) and a mean (zero but for rounding, under NO_BIAS of any spread)."""
    rng = np.random.default_rng(2)
    n, x = 12, rng.exponential(1.0, (12, 5))

    def both(w):
        return np.stack([np.sqrt(w @ x).mean(axis=-1), (w @ x).mean(axis=-1)], axis=-1)

    value = both(np.full(n, 1 / n))
    found = uncertainty.jackknife_bias(both, value, n)
    by_hand = (n - 1) * (
        np.mean([both(np.where(np.arange(n) == i, 0, 1 / (n - 1))) for i in range(n)], 0) - value
    )
    assert found == pytest.approx(by_hand, rel=1e-12, abs=1e-15)
    assert found[0] < -1e-4 and abs(found[1]) < 1e-14


@pytest.mark.filterwarnings("error")
def test_a_metric_with_no_value_once_a_trial_is_left_out_is_not_bias_corrected():
    """A ratio whose denominator is one trial's alone has no value without that trial (nor for
    most trials alone): its jackknife bias is undefined, so its interval is not moved (it would
    be infinite), it gets no bootstrap-t, and no warning is raised; nor for a mean with an
    infinite trial."""
    n = 8
    a, b = np.ones(n), np.where(np.arange(n) == n - 1, 1.0, 0.0)
    found = uncertainty.estimate(lambda w: (w @ a) / (w @ b), n, seed=0)
    assert found["estimate"] == 8.0 and found["method"] == "percentile"
    assert not np.isfinite(uncertainty.jackknife_bias(lambda w: (w @ a) / (w @ b), 8.0, n))
    infinite = uncertainty.estimate(lambda w: w @ np.where(np.arange(n) == 0, np.inf, 1.0), n)
    assert infinite["estimate"] == np.inf and not infinite["method"].startswith("bootstrap-t")


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


def test_the_coverage_of_intervals_on_fewer_trials_of_a_population():
    """trial_coverage draws studies of n of a population's trials: a sum over steps averaged over
    trials (final regret) is covered at 95 % on 50 trials, within the binomial test's tolerance;
    ARMSE of heavy-tailed errors is covered significantly less on 20, bias-corrected though its
    interval is: the correction is for a bias, not for tails a few trials did not draw
    (docs/benchmark.md). Each count's
    row is drawn from a stream of its own: the same whatever the other counts."""
    rng = np.random.default_rng(4)
    n, t = 400, 40
    expected = rng.exponential(1.0, (n, t))
    squared = rng.lognormal(0.0, 1.5, (n, t, 1))
    population = {"a": _policy(expected, squared, expected + rng.exponential(1.0, (n, t)))}
    said = []
    record = uncertainty.trial_coverage(population, counts=(20, 50), repeats=300, seed=1, say=said.append)
    assert record["population_trials"] == n and [row["trials"] for row in record["rows"]] == [20, 50]
    assert [line.split(":")[0] for line in said] == ["20 trials", "50 trials"]
    assert (
        uncertainty.trial_coverage(population, counts=(50,), repeats=300, seed=1)["rows"]
        == record["rows"][1:]
    )
    few, more = record["rows"]
    assert few["studies"]["a.armse"] == 300 and few["method"] == "BCa" + uncertainty.FEW_METHODS
    assert more["method"] == "BCa"
    armse = round(few["coverage"]["a.armse"] * 300)
    assert stats.binomtest(armse, 300, 0.95, alternative="less").pvalue < 0.01, armse
    regret = round(more["coverage"]["a.final_regret"] * 300)
    assert stats.binomtest(regret, 300, 0.95).pvalue > 0.01, regret


def test_the_coverage_of_paired_differences_on_fewer_trials():
    """trial_coverage also judges each pair's paired differences on the drawn trials: the counts
    are those of paired_differences run on the same draws, against the difference of the two
    policies' own values on the whole population; a difference of final regrets (a mean of
    paired trials) is covered at 95 % on 50 trials within the binomial test's tolerance; a
    difference constant over the trials (ASR, no optimal steps here) is left out."""
    rng = np.random.default_rng(7)
    n, t = 300, 30
    optimal = 1.0 + rng.exponential(1.0, (n, t))
    shared = rng.exponential(1.0, (n, 1))  # what the two policies' trials share
    population = {
        name: _policy(shared * rng.exponential(1.0, (n, t)), rng.lognormal(0.0, 0.5, (n, t, 1)), optimal)
        for name in ("a", "b")
    }
    row = uncertainty.trial_coverage(population, counts=(50,), repeats=200, seed=2)["rows"][0]
    found = row["differences"]
    assert sorted(found["coverage"]) == ["a - b.armse", "a - b.final_regret", "a - b.mean_sinr_db"]
    assert found["studies"] == dict.fromkeys(found["coverage"], 200)
    covered = round(found["coverage"]["a - b.final_regret"] * 200)
    assert stats.binomtest(covered, 200, 0.95).pvalue > 0.01, covered

    few = uncertainty.trial_coverage(population, counts=(8,), repeats=6, seed=2)["rows"][0]["differences"]
    values = {p: m.scalar_metrics() for p, m in population.items()}
    equal = population["a"].equal()
    draws = np.random.default_rng([2, 8])
    expected = dict.fromkeys(few["coverage"], 0)
    for r in range(6):
        drawn = draws.integers(0, n, 8)
        runs = {p: m.of_trials(drawn) for p, m in population.items()}
        for name, judged in uncertainty.paired_differences(runs, seed=r)["a - b"].items():
            if name == "asr":
                assert judged["method"] == uncertainty.METHODS["constant"]
                continue
            truth = values["a"][name](equal) - values["b"][name](equal)
            expected[f"a - b.{name}"] += judged["ci"][0] <= truth <= judged["ci"][1]
    assert few["coverage"] == {key: hits / 6 for key, hits in expected.items()}


def test_the_coverage_counts_the_studies_whose_interval_was_extended(monkeypatch):
    """Each row says how many studies' intervals were extended to their value (here every ARMSE
    interval is marked so by a stand-in of ``estimates``)."""
    rng = np.random.default_rng(0)
    expected = rng.exponential(1.0, (30, 5))
    population = {"a": _policy(expected, rng.exponential(1.0, (30, 5, 1)))}
    judge = uncertainty.estimates

    def marked(values, n, seed):
        found = judge(values, n, seed=seed)
        found["a", "armse"]["method"] = uncertainty.METHODS["extended"]
        return found

    monkeypatch.setattr(uncertainty, "estimates", marked)
    row = uncertainty.trial_coverage(population, counts=(6,), repeats=5)["rows"][0]
    assert row["extended"] == {"a.armse": 5, "a.mean_sinr_db": 0}  # regret and ASR: constant here
    assert row["confidence_level"] == uncertainty.confidence_level(6) > 0.95


def test_an_interval_that_misses_its_value_by_more_than_rounding_is_extended_and_says_so():
    """ARMSE of 8 trials of heavy-tailed errors: every resample lies below the value (a root of a
    mean over trials at each step is biased low on few trials). The bias-corrected interval, the
    percentile interval moved up by twice the jackknife's bias (computed here by leaving out each
    trial in turn), lies wholly above the value. It is extended to it and named so (a run raised
    IntervalError before)."""
    rng = np.random.default_rng(1)
    n, t = 8, 300
    expected = rng.exponential(1.0, (n, t))
    squared = rng.lognormal(0.0, 1.5, (n, t, 1))
    m = _policy(expected, squared, expected + rng.exponential(1.0, (n, t)))
    armse = uncertainty.policy_estimates(m)["armse"]
    assert armse["method"] == "bias-corrected percentile, extended to the value"
    assert armse["estimate"] == armse["ci"][0] < armse["ci"][1]
    level = uncertainty.confidence_level(n)
    resampled = stats.bootstrap(
        (np.arange(n),),
        lambda i, axis=-1: m.armse(trial_weights(i, n)),
        n_resamples=uncertainty.RESAMPLES,
        method="percentile",
        confidence_level=level,
        vectorized=True,
        random_state=np.random.default_rng(0),
    ).confidence_interval
    left_out = [m.armse(np.where(np.arange(n) == i, 0.0, 1 / (n - 1))) for i in range(n)]
    bias = (n - 1) * (np.mean(left_out) - armse["estimate"])
    assert resampled.high < armse["estimate"] < resampled.low - 2 * bias
    assert armse["ci"][1] == pytest.approx(resampled.high - 2 * bias, rel=1e-12)
    assert report.METHOD_MARKS[armse["method"]] == "§"


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
    argv = ["run", "--scenario", "paper-3-v1", "--policies", "ucb1,epsilon-greedy,best", "--trials", "12"]
    assert main([*argv, "--steps", "40", "--workers", "1", "--quiet", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert "BCa from 20 trials, percentile below" in summary["uncertainty"]
    assert summary["uncertainty"].endswith(
        "; below 20 trials the percentile interval's level is Hesterberg's "
        "expansion for a few trials (its z is Student's t with n - 1 degrees of freedom times "
        "sqrt(n / (n - 1))); below 40 trials a metric with a bias over trials (ARMSE, the bound and "
        "their ratio) has a bias-corrected percentile interval: the "
        "percentile interval moved by twice its jackknife bias; and a mean over trials (ASR, final "
        "regret, their paired differences) a bootstrap-t interval at 95 %, mean SINR in dB the "
        "bootstrap-t interval of the mean SINR, in dB, and a paired difference of mean SINRs in dB a "
        "bootstrap-t interval with the delta method's standard errors"
    )
    differences = summary["paired_differences"].values()
    assert {d["mean_sinr_db"]["method"] for d in differences} <= {"bootstrap-t", "constant over trials"}
    assert uncertainty.method_of(40) == uncertainty.METHOD
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
    # Best's regret is 0 up to the rounding of the env's sums, the same in every trial: a
    # constant, whose interval is the value itself
    assert abs(best["final_regret"]) < 1e-9
    assert best["method"]["final_regret"] == "constant over trials"
    assert best["ci"]["final_regret"] == [best["final_regret"], best["final_regret"]]
    table = (out / "table.md").read_text()
    assert "95 % interval" in table and "| ucb1 - best |" in table
    assert (out / "rmse.png").exists() and (out / "regret.png").exists()


def _every_estimate(summary):
    """Every (value, interval, method) of a summary: the table's cells and the paired differences."""
    for policy, row in summary["policies"].items():
        for key, ci in row["ci"].items():
            values, cis, methods = row[key], ci, row["method"][key]
            if not isinstance(values, list):
                values, cis, methods = [values], [cis], [methods]
            for value, interval, method in zip(values, cis, methods, strict=True):
                yield f"{policy} {key}", value, interval, method
    for pair, metrics in summary["paired_differences"].items():
        for key, judged in metrics.items():
            yield f"{pair} {key}", judged["estimate"], judged["ci"], judged["method"]


@pytest.mark.parametrize("trials", [6, 10, 24, 40])
def test_every_interval_of_a_run_contains_its_value(tmp_path, trials):
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-3-v1", "--policies", "mg-crb-cl,ucb1,best,fix1,random"]
    argv += ["--trials", str(trials), "--steps", "30", "--workers", "1", "--quiet", "--no-figures"]
    assert main([*argv, "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    seen = set()
    for name, value, (low, high), method in _every_estimate(summary):
        assert low <= value <= high, (name, value, low, high, method)
        seen.add(method)
    if trials < uncertainty.FEW_TRIALS:  # every metric is a mean over trials or biased
        assert {"bootstrap-t", "bias-corrected percentile", "constant over trials"} <= seen, seen
        assert "BCa" not in seen
    else:
        assert {"BCa", "constant over trials"} <= seen, seen
        assert not {"bootstrap-t", "bias-corrected percentile"} & seen, seen


@pytest.mark.parametrize("trials", [6, 7, 10, 19, 20, 50, 500])
def test_every_interval_contains_its_value_on_heavy_tailed_synthetic_policies(trials):
    """Pareto-tailed errors and rewards (the worst case for BCa's skew correction)."""
    rng = np.random.default_rng(trials)
    t = 40
    policies = {
        name: _policy(
            rng.pareto(1.5, size=(trials, t)) + 0.1,
            rng.pareto(1.2, size=(trials, t, 2)) * scale,
            optimal=np.full((trials, t), 50.0),
        )
        for name, scale in (("a", 1.0), ("b", 3.0), ("c", 0.3))
    }
    for m in policies.values():
        for name, judged in uncertainty.policy_estimates(m).items():
            for one in judged if isinstance(judged, list) else [judged]:
                low, high = one["ci"]
                assert low <= one["estimate"] <= high, (name, one)
    for pair, metrics in uncertainty.paired_differences(policies).items():
        for name, one in metrics.items():
            assert one["ci"][0] <= one["estimate"] <= one["ci"][1], (pair, name, one)


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("trials", [8, 25])
def test_a_metric_infinite_on_many_resamples_has_an_infinite_end_not_nan(trials):
    """A ratio whose denominator is one trial's alone is infinite on every resample that leaves
    that trial out (about a third of them): the upper end of its interval is infinite. On 25
    trials, where BCa is undefined and the percentile interval stands in, its upper tail lay
    between two infinite resamples and was NaN."""
    x = np.random.default_rng(0).exponential(1.0, trials)
    b = np.where(np.arange(trials) == 0, 1.0, 0.0)
    found = uncertainty.estimate(lambda w: (w @ x) / (w @ b), trials, seed=1)
    low, high = found["ci"]
    assert found["method"] == "percentile" and np.isfinite(low) and high == np.inf
    assert low <= found["estimate"] <= high


def test_a_mean_of_few_trials_whose_resamples_often_have_no_spread_gets_the_percentile_interval():
    """A share of successes over 6 trials, 5 of them successes: a third of the resamples are all
    successes, with no spread and an infinite t, so the bootstrap-t's upper quantile is infinite
    and the (expanded) percentile interval stands in; 3 successes of 6 give a bootstrap-t."""
    for successes, method in ((5, "percentile"), (3, "bootstrap-t")):
        x = (np.arange(6) < successes).astype(float)
        judged = uncertainty.estimate(lambda w, x=x: w @ x, 6, seed=1)
        assert judged["method"] == method and judged["ci"][0] <= judged["estimate"] <= judged["ci"][1]
        assert np.isfinite(judged["ci"]).all()


def test_the_estimate_is_the_metric_at_equal_weights_and_a_constant_has_a_point_interval():
    x = np.array([1.0, 2.0, 4.0, 8.0, 16.0, 32.0])
    judged = uncertainty.estimate(lambda w: w @ x, 6)
    assert judged["estimate"] == x.mean() and judged["method"] == "bootstrap-t"
    constant = uncertainty.estimate(lambda w: w @ np.full(30, 7.0), 30)
    assert constant["estimate"] == pytest.approx(7.0, rel=1e-15)
    assert constant["ci"] == [constant["estimate"]] * 2 and constant["method"] == "constant over trials"
    for few in (1, 2, 5):  # fewer than MIN_INTERVAL_TRIALS: the estimate alone
        alone = uncertainty.estimate(lambda w, few=few: w @ x[:few], few)
        assert alone == {"estimate": x[:few].mean(), "ci": None, "method": "none (fewer than 6 trials)"}
    wide = uncertainty.estimate(lambda w: w @ np.random.default_rng(0).normal(size=40), 40)
    assert wide["method"] == "BCa" and wide["ci"][0] < wide["estimate"] < wide["ci"][1]


# ---------------------------------------------------------------- across training seeds (rliable's way)
def test_the_interquartile_mean_is_the_mean_of_the_middle_half():
    from benchmarks.uncertainty import iqm

    values = np.array([9.0, 1.0, 5.0, 3.0, 7.0, 2.0, 8.0, 4.0])  # sorted: 1..5, 7..9
    assert iqm(values) == pytest.approx(np.mean(np.sort(values)[2:6]))
    assert iqm(np.arange(12.0)) == pytest.approx(np.mean(np.arange(3.0, 9.0)))


def test_the_stratified_interval_covers_a_known_iqm_at_about_its_nominal_rate():
    from benchmarks.uncertainty import across_seeds, iqm

    rng = np.random.default_rng(1)
    locations = (0.0, 1.0, 3.0)  # three tasks of different difficulty, ten runs each
    population = np.concatenate([rng.normal(loc, 1.0, 400_000) for loc in locations])
    truth = {"iqm": iqm(population), "mean": population.mean()}
    repeats = 300
    covered = {"iqm": 0, "mean": 0}
    for r in range(repeats):
        groups = [rng.normal(loc, 1.0, 10) for loc in locations]
        for statistic in covered:
            low, high = across_seeds(groups, statistic, seed=r)["ci"]
            covered[statistic] += low <= truth[statistic] <= high
    for statistic, count in covered.items():  # percentile bootstrap: near 95 %, a little under
        assert 0.89 <= count / repeats <= 0.985, (statistic, count / repeats)


def test_the_stratified_bootstrap_resamples_within_each_task():
    from benchmarks.uncertainty import across_seeds

    # one task's runs never stand in for another's: two constant tasks have no spread at all
    result = across_seeds([np.full(5, 1.0), np.full(5, 3.0)], "mean")
    assert result["value"] == 2.0 and result["ci"] == [2.0, 2.0]
    with pytest.raises(ValueError, match="statistic must be one of"):
        across_seeds([np.ones(3)], "median")
    with pytest.raises(ValueError, match="every group needs at least one score"):
        across_seeds([np.ones(3), np.array([])])


def test_metrics_on_the_same_resamples_share_their_rms_terms_and_give_the_same_numbers(monkeypatch):
    """Every estimate of a run draws the same resamples: ARMSE, the bound, their ratio and the
    paired differences reuse each policy's time-averaged RMS terms. The numbers are those of
    computing every metric afresh (sharing switched off), with far fewer products: the metrics
    of one bootstrap (:func:`uncertainty.estimates`) share one weight array anyway, so switching
    sharing off recomputes the terms once per bootstrap: a policy's, then its pairs'."""
    from benchmarks import metrics

    rng = np.random.default_rng(4)
    expected, squared = rng.exponential(1.0, (40, 30)), rng.exponential(1.0, (40, 30, 2))
    calls = []
    counted = metrics._root_mean_square
    monkeypatch.setattr(metrics, "_root_mean_square", lambda *a, **k: calls.append(1) or counted(*a, **k))

    def everything():
        policies = {
            name: uncertainty.TrialMetrics(
                {
                    "trial_expected": expected * scale,
                    "trial_optimal": expected + 1,
                    "trial_matches": expected > 1,
                    "trial_squared_error": squared * scale,
                    "trial_bound_squared": squared * scale / 2,
                },
                channels=6,
            )  # fmt: skip
            for name, scale in (("a", 1.0), ("b", 1.5), ("c", 0.7))
        }
        calls.clear()
        out = {name: uncertainty.policy_estimates(m) for name, m in policies.items()}
        return out | {"pairs": uncertainty.paired_differences(policies)}, len(calls)

    shared, shared_calls = everything()
    monkeypatch.setattr(uncertainty, "SHARED_INDEX_ELEMENTS", 0)
    afresh, afresh_calls = everything()
    assert json.dumps(shared, sort_keys=True) == json.dumps(afresh, sort_keys=True)
    assert shared_calls * 2 <= afresh_calls, (shared_calls, afresh_calls)


def test_the_committed_seed_coverage_is_what_the_measurement_gives():
    """docs/results/rl/seed-coverage.json (quoted beside the RL study's intervals) is what
    seed_coverage measures from its seed, here at the study's smallest count; and the coverage
    rises with the seeds, as a percentile bootstrap's should."""
    import json
    from pathlib import Path

    from benchmarks.uncertainty import seed_coverage

    committed = json.loads(
        (Path(__file__).resolve().parents[2] / "docs/results/rl/seed-coverage.json").read_text()
    )["one_group"]
    again = seed_coverage(counts=(3,), groups=1, repeats=committed["repeats"], seed=committed["seed"])
    # the population is drawn first, then the samples: the first count's rows agree exactly
    assert again["coverage"][0] == committed["coverage"][0]
    rows = committed["coverage"]
    assert [r["runs_per_group"] for r in rows] == [3, 5, 10]
    assert rows[0]["mean"] < rows[1]["mean"] < rows[2]["mean"] < 0.95


@pytest.mark.filterwarnings("ignore:The BCa confidence interval cannot be calculated")
@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")
@pytest.mark.parametrize("trials", [10, 30, 60])
def test_several_metrics_from_one_bootstrap_are_one_scipy_bootstrap_each(trials):
    """``estimates`` bootstraps every metric at once; each interval is, to the last bit, that of
    scipy.stats.bootstrap run on that metric alone with the same seed (percentile below 20
    trials at the expanded level, BCa above at 95 %; a constant metric gets its point interval, a
    skewed one BCa's fallback), or below 40 trials for a biased metric (a ratio of means) the
    percentile interval of its resamples moved by twice its jackknife bias, computed here by
    leaving out each trial in turn, and for a mean the bootstrap-t interval, computed here from
    scipy's resamples of the trials' values."""
    rng = np.random.default_rng(9)
    values = rng.exponential(1.0, (3, trials))
    values[2] = rng.lognormal(0.0, 3.0, trials)  # heavy tail: BCa may fall back to percentile
    metrics = {
        "mean": lambda w: w @ values[0],
        "ratio": lambda w: (w @ values[0]) / (w @ values[1]),
        "skewed": lambda w: w @ values[2],
        "constant": lambda w: w.sum(axis=-1) * 2.0,
        "log of a mean": OfMean(lambda w: w @ values[0], np.log),
    }
    together = uncertainty.estimates(metrics, trials, seed=3)
    assert uncertainty.estimates({}, trials) == {}
    method = "BCa" if trials >= uncertainty.BCA_MIN_TRIALS else "percentile"
    # Hesterberg's expanded percentile below BCA_MIN_TRIALS, written out: z = sqrt(n/(n-1)) t_{n-1}
    z = np.sqrt(trials / (trials - 1)) * stats.t.ppf(0.975, trials - 1)
    level = 0.95 if trials >= uncertainty.BCA_MIN_TRIALS else 1 - 2 * stats.norm.cdf(-z)
    for name, metric in metrics.items():

        def statistic(index, axis=-1, metric=metric):
            return metric(uncertainty.trial_weights(index, trials))

        alone = stats.bootstrap(
            (np.arange(trials),),
            statistic,
            vectorized=True,
            n_resamples=uncertainty.RESAMPLES,
            confidence_level=level,
            method=method,
            random_state=np.random.default_rng(3),
        )
        got = together[name]
        if name == "constant":
            assert got["ci"] == [2.0, 2.0] and got["method"] == "constant over trials"
        elif name == "ratio" and trials < uncertainty.FEW_TRIALS:
            left_out = [
                metric(np.where(np.arange(trials) == i, 0.0, 1 / (trials - 1))) for i in range(trials)
            ]
            bias = (trials - 1) * (np.mean(left_out) - got["estimate"])
            tails = np.percentile(alone.bootstrap_distribution, [50 * (1 - level), 50 * (1 + level)])
            assert got["method"].startswith("bias-corrected percentile")
            assert got["ci"] == pytest.approx(
                [min(tails[0] - 2 * bias, got["estimate"]), max(tails[1] - 2 * bias, got["estimate"])],
                rel=1e-12,
            )
        elif name in ("mean", "skewed", "log of a mean") and trials < uncertainty.FEW_TRIALS:
            # the bootstrap-t: each resample's t = (mean - value) / (its sd / sqrt(n)), on the same
            # resamples (scipy's, with the same seed), its 2.5 % and 97.5 % quantiles turned around;
            # the log of a mean gets the log of its mean's
            x = values[2 if name == "skewed" else 0]
            transform = np.log if name == "log of a mean" else (lambda v: v)

            def resampled(statistic, x=x):
                return stats.bootstrap(
                    (x,),
                    statistic,
                    n_resamples=uncertainty.RESAMPLES,
                    method="percentile",
                    random_state=np.random.default_rng(3),
                ).bootstrap_distribution

            means = resampled(np.mean)
            errors = resampled(lambda s, axis=-1: np.std(s, axis=axis, ddof=1)) / np.sqrt(trials)
            assert transform(means) == pytest.approx(alone.bootstrap_distribution, rel=1e-12)
            t_high, t_low = np.percentile((means - x.mean()) / errors, [97.5, 2.5])
            error = np.std(x, ddof=1) / np.sqrt(trials)
            low, high = x.mean() - t_high * error, x.mean() - t_low * error
            assert got["method"].startswith("bootstrap-t")
            assert got["estimate"] == pytest.approx(transform(x.mean()), rel=1e-12)
            expected = transform(np.array([min(low, x.mean()), max(high, x.mean())]))
            assert got["ci"] == pytest.approx(expected, rel=1e-9)
        elif got["method"] == method:
            ci = alone.confidence_interval
            assert got["ci"] == [min(ci.low, got["estimate"]), max(ci.high, got["estimate"])]
        else:  # BCa's fallback: the percentile interval of the same resamples
            low, high = np.percentile(alone.bootstrap_distribution, [2.5, 97.5])
            assert got["method"] == "percentile" and got["ci"] == [
                min(low, got["estimate"]),
                max(high, got["estimate"]),
            ]
        assert got == uncertainty.estimate(metric, trials, seed=3)


@pytest.mark.parametrize("threads", [2, 4])
def test_a_policys_intervals_are_the_same_bits_whatever_blas_threads_the_process_has(threads):
    """The bootstrap's matrix products (2,000 resamples of 400 trials by 300 steps) run on one
    BLAS thread whatever the process allows: on more, OpenBLAS splits them, and the last bits
    moved with the count of cores (a study's report on 2 cores against 16)."""
    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(7)
    n, t = 400, 300
    expected, squared = rng.exponential(1.0, size=(n, t)), rng.exponential(4.0, size=(n, t, 2))
    results = []
    for limit in (1, threads):
        with threadpool_limits(limits=limit, user_api="blas"):
            policy = _policy(expected, squared)  # a new one: no terms remembered from the other
            results.append(
                (
                    uncertainty.policy_estimates(policy, seed=3),
                    uncertainty.band(functools.partial(policy.rmse_curve, target=1), n, seed=3),
                )
            )
    (one, band_one), (many, band_many) = results
    assert json.dumps(one) == json.dumps(many)
    np.testing.assert_array_equal(band_one[0], band_many[0])
    np.testing.assert_array_equal(band_one[1], band_many[1])


def test_the_coverage_of_a_runs_intervals_is_measured_from_its_folder(tmp_path):
    """``python -m benchmarks.uncertainty --run DIR``: the studies are drawn from the run's own
    trials, whose values they are judged against; a folder that is no run is one line."""
    import subprocess
    import sys

    run = tmp_path / "run"
    argv = ["run", "--scenario", "paper-3-v1", "--policies", "ucb1,fix1", "--trials", "8", "--steps", "5"]
    assert main([*argv, "--workers", "1", "--quiet", "--no-figures", "--out", str(run)]) == 0
    out = tmp_path / "coverage.json"
    command = [sys.executable, "-m", "benchmarks.uncertainty", "--run", str(run), "--counts", "6,8"]
    done = subprocess.run([*command, "--repeats", "3", str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    record = json.loads(out.read_text())
    assert record["command"].endswith("--counts 6,8 --repeats 3") and record["population_trials"] == 8
    assert record["run"]["scenario"] == "paper-3-v1" and [r["trials"] for r in record["rows"]] == [6, 8]
    assert set(record["rows"][0]["coverage"]) <= {
        f"{p}.{k}" for p in ("ucb1", "fix1") for k in uncertainty.COVERAGE_METRICS
    }
    refused = subprocess.run([*command[:3], "--run", str(tmp_path)], capture_output=True, text=True)
    assert refused.returncode == 2 and refused.stderr.strip().splitlines()[-1].endswith("(no config.json)")
