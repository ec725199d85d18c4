"""The planning cost benchmark: each search timed beside best-tracking on the same steps."""

import pytest


def test_the_planning_cost_benchmark_measures_each_search_against_best_tracking():
    from benchmarks.speed.planning_cost import measure

    ratios = measure(trials=2, steps=1)
    assert ratios["best-tracking_ms_per_step"] > 0
    assert {k for k in ratios if k.endswith("_over_best_tracking")} == {
        f"plan-tracking:10-{s}_over_best_tracking" for s in ("beam", "rollout", "mcts")
    }
    assert all(v > 0 for v in ratios.values())
    for search in ("beam", "rollout", "mcts"):  # each ratio is the two times measured
        name = f"plan-tracking:10-{search}"
        ratio = ratios[f"{name}_ms_per_step"] / ratios["best-tracking_ms_per_step"]
        assert ratios[f"{name}_over_best_tracking"] == pytest.approx(ratio)
