"""The policy cost benchmark: each policy's time beside the harness's estimate, its memory beside its
declaration."""

from mimo_radar_env import random_scenario


def test_the_policy_cost_benchmark_measures_within_the_declaration():
    from benchmarks.speed.policy_cost import measure_policy

    row = measure_policy("tracking-ucb", random_scenario(4, 6, 2, 2, 3, horizon=6, seed=0), trials=2, steps=2)
    assert row["ms_per_trial_step"] > 0
    assert 0 < row["measured_mib_per_trial"] <= row["declared_mib_per_trial"]
