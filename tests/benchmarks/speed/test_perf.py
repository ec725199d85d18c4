"""The perf command's quick mode: every figure is produced, and each means what it says (a ratio is
the quotient of the two figures measured beside it, a share within 0 and 1)."""

import json

import pytest

from benchmarks.cli import main

FIGURES = {
    "tracker_speedup_vs_filterpy",
    "exact_vs_bpso_speedup",
    "bpso_optimality_rate",
    "env_trial_steps_per_s_average",
    "env_trial_steps_per_s_centralized",
    "env_compiled_speedup_average",
    "env_compiled_speedup_centralized",
    "bpso_1thread_ms_xor",
    "bpso_1thread_ms_set",
    "claims_v1_average_wall_s",
    "claims_v1_centralized_wall_s",
    "tracking_study_wall_s",
    "flat_vector_trial_steps_per_s",
    "flat_sync_trial_steps_per_s",
    "flat_vector_vs_sync_speedup",
    "ppo_training_native_vs_sync_speedup",
}


def test_perf_quick_writes_every_figure(tmp_path, capsys):
    assert main(["perf", "--quick", "--workers", "1", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "perf.json").read_text())
    assert FIGURES <= set(result) and result["quick"] is True
    # each ratio is the quotient of the two figures measured beside it in the same run
    quotients = {
        "tracker_speedup_vs_filterpy": ("batched_channel_cycles_per_s", "filterpy_channel_cycles_per_s"),
        "exact_vs_bpso_speedup": ("bpso_ms", "exact_ms"),
        "env_compiled_speedup_average": (
            "env_trial_steps_per_s_average",
            "env_numpy_trial_steps_per_s_average",
        ),
        "env_compiled_speedup_centralized": (
            "env_trial_steps_per_s_centralized",
            "env_numpy_trial_steps_per_s_centralized",
        ),
        "flat_vector_vs_sync_speedup": ("flat_vector_trial_steps_per_s", "flat_sync_trial_steps_per_s"),
        "ppo_training_native_vs_sync_speedup": (
            "ppo_training_steps_per_s_native",
            "ppo_training_steps_per_s_sync",
        ),
    }
    for ratio, (numerator, denominator) in quotients.items():
        assert result[ratio] == pytest.approx(result[numerator] / result[denominator], rel=1e-9), ratio
    assert 0 <= result["bpso_optimality_rate"] <= 1
    assert result["claims_v1_both_fusions_wall_s"] == pytest.approx(
        result["claims_v1_average_wall_s"] + result["claims_v1_centralized_wall_s"]
    )
    for rule in ("xor", "set"):
        assert 0 <= result[f"bpso_optimality_rate_{rule}"] <= 1
    assert not any("reference" in key or "candidate" in key for key in result if key.startswith("bpso"))
    assert "tracker_speedup_vs_filterpy" in capsys.readouterr().out
    # every policy's cost beside its declaration, at 4 x 6 (K = 1 and 5) in quick mode
    cost = json.loads((tmp_path / "policy_cost.json").read_text())
    assert {(r["M"], r["N"], r["K"]) for r in cost["rows"]} == {(4, 6, 1), (4, 6, 5)}
    assert {r["policy"] for r in cost["rows"]} >= {"ucb1", "mg-crb-cl", "best-tracking", "tracking-ucb"}
    assert 0 < result["policy_memory_measured_over_declared_max"] <= 1
    assert (
        0
        < result["policy_time_measured_over_estimated_min"]
        <= result["policy_time_measured_over_estimated_max"]
    )
