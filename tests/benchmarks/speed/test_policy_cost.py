"""The policy cost benchmark: each policy's time beside the harness's estimate, its memory beside its
declaration, and the ratios it reports."""

import pytest

import agents
from benchmarks.resources import STEP_OVERHEAD_SECONDS
from benchmarks.speed import policy_cost
from mimo_radar_env import random_scenario
from mimo_radar_env.envs.cost import seconds_per_trial_step


@pytest.mark.parametrize("trials", [2, 5])
def test_a_row_is_the_estimate_of_a_shard_of_its_trials_beside_the_measurement(trials):
    scenario = random_scenario(4, 6, 2, 2, 3, horizon=6, seed=0)
    row = policy_cost.measure_policy("plan-tracking", scenario, trials=trials, steps=2)
    agent = agents.make_agent("plan-tracking", scenario)
    # one step of one shard: the per-step overhead and the planner's own, then each trial's share
    by_hand = (
        STEP_OVERHEAD_SECONDS
        + agents.costs.seconds_per_step(agent)
        + trials * (seconds_per_trial_step(scenario) + agents.costs.seconds_per_trial_step(agent))
    )
    assert row["declared_ms_per_trial_step"] == pytest.approx(1e3 * by_hand / trials, rel=1e-12)
    assert row["ms_per_trial_step"] > 0
    assert 0 < row["measured_mib_per_trial"] <= row["declared_mib_per_trial"]


def test_the_ratios_are_over_every_row_and_the_record_names_its_trial_counts():
    rows = [
        {"ms_per_trial_step": 2.0, "declared_ms_per_trial_step": 1.0, "measured_mib_per_trial": 1.0,
         "declared_mib_per_trial": 4.0},
        {"ms_per_trial_step": 1.0, "declared_ms_per_trial_step": 4.0, "measured_mib_per_trial": 3.0,
         "declared_mib_per_trial": 4.0},
    ]  # fmt: skip
    assert policy_cost.ratios(rows) == {
        "policy_memory_measured_over_declared_max": 0.75,
        "policy_time_measured_over_estimated_min": 0.25,
        "policy_time_measured_over_estimated_max": 2.0,
    }
    record = policy_cost.record(rows, (4, 50), 5, 12.3)
    assert record["command"] == "python -m benchmarks.speed.policy_cost --trials 4,50 --steps 5"
    assert record["trials"] == [4, 50]


@pytest.mark.parametrize("text", ["0", "4,x", "", "-3,4"])
def test_trial_counts_must_be_positive_integers(text):
    import argparse

    with pytest.raises(argparse.ArgumentTypeError, match="trial counts must be integers >= 1"):
        policy_cost._counts(text)
    assert policy_cost._counts("4,50") == (4, 50)
