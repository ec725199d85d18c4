"""The perf command's quick mode: every figure is produced, as a positive number."""

import json

import numpy as np
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
    "bpso_speedup_vs_reference_xor",
    "bpso_speedup_vs_reference_set",
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
    for key in FIGURES:
        assert result[key] > 0, key
    assert 0 <= result["bpso_optimality_rate"] <= 1
    assert result["claims_v1_both_fusions_wall_s"] == pytest.approx(
        result["claims_v1_average_wall_s"] + result["claims_v1_centralized_wall_s"]
    )
    for rule in ("xor", "set"):  # the rework kept the numbers: the same selections, the same rate
        assert result[f"bpso_optimality_rate_{rule}"] == result[f"bpso_reference_optimality_rate_{rule}"]
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


def test_the_scaling_rows_measure_a_small_layout_and_the_growth_fit_is_a_slope():
    from benchmarks.speed import scaling

    row = scaling.measure(5, 6, 2, 2, 3, trials=4, steps=2)
    assert (row["M"], row["N"], row["K"], row["B"], row["solver"]) == (5, 6, 2, 4, "exact")
    assert row["ms_per_step"] > 0 and row["peak_mib"] > 0
    assert row["us_per_trial_step"] == pytest.approx(1e3 * row["ms_per_step"] / 4)
    assert scaling.growth([1, 2, 4, 8], [3, 6, 12, 24]) == pytest.approx(1.0)
    assert scaling.growth([1, 2, 4], [1, 4, 16]) == pytest.approx(2.0)


def test_the_step_stages_add_up_to_the_step_and_name_their_arithmetic():
    from benchmarks.speed import stages

    record = stages.measure(trials=4, steps=2)
    rows = record["rows"]
    env_stages = {"simulation", "tracker", "bound", "oracle search", "observation and info"}
    for fusion in ("average", "centralized"):
        assert {r["stage"] for r in rows if r["fusion"] == fusion} == env_stages
        timed = [r for r in rows if r["fusion"] == fusion and r["stage"] != "observation and info"]
        assert all(r["ms_per_step"] > 0 for r in timed)
    tracker = next(r for r in rows if r["stage"] == "tracker" and r["fusion"] == "average")
    assert tracker["achieved_operations_per_s"] == pytest.approx(
        tracker["declared_operations_per_trial"] * 4 / (tracker["ms_per_step"] / 1e3)
    )
    assert {r["stage"] for r in rows if r["fusion"] == "-"} == {
        "MG-CRB-CL act, BPSO (paper, rule set)",
        "MG-CRB-CL act, exact solver",
    }


@pytest.mark.slow
def test_a_first_run_from_an_empty_cache_writes_the_numba_cache(tmp_path):
    from benchmarks.speed import first_run

    args = ("paper", "--scenario", "1", "--trials", "2", "--steps", "2", "--quiet", "--no-figures")
    seconds = first_run.timed_run(tmp_path / "out", tmp_path / "cache", args)
    assert seconds > 0 and (tmp_path / "out" / "summary.json").is_file()
    # the kernels the run called are cached for the next run: BPSO's one-thread kernel among them
    assert any(
        p.name.startswith("_bpso_kernels.run_numba_serial") for p in (tmp_path / "cache").rglob("*.nbi")
    )


def test_first_run_refuses_no_repeats(capsys):
    from benchmarks.speed import first_run

    with pytest.raises(SystemExit):
        first_run.main(["--repeats", "0"])
    assert "--repeats must be at least 1" in capsys.readouterr().err


@pytest.mark.parametrize("argument", ["--trials", "--repeats"])
def test_the_bpso_breakdown_refuses_no_trials_or_repeats(argument, capsys):
    from benchmarks.speed import bpso_parts

    with pytest.raises(SystemExit):
        bpso_parts.main([argument, "0"])
    assert f"argument {argument}: must be an integer >= 1, got 0" in capsys.readouterr().err


def test_the_bpso_breakdown_knocks_out_each_part_and_refuses_a_stale_one(monkeypatch):
    from agents.solvers import _bpso_kernels
    from benchmarks.speed import bpso_parts

    result = bpso_parts.measure(trials=4, repeats=1, rule="xor")
    assert result["rule"] == "xor" and result["q_max"] == 100
    assert 0 <= result["mean_iterations"] <= 100 and 0 <= result["share_all_iterations"] <= 1
    assert [row["part"] for row in result["parts"]] == list(bpso_parts.PARTS)
    assert result["kernel_ms"] > 0 and result["reference_ms"] > 0 and result["whole_swarm_ms"] > 0
    for row in result["parts"]:
        assert row["without_ms"] > 0
        assert row["cost_ms"] == pytest.approx(result["whole_swarm_ms"] - row["without_ms"])
    # the whole swarm (the kernel without its stop at the optimum) selects what the kernel does
    args = bpso_parts.kernel_arguments(60, "set")
    np.testing.assert_array_equal(bpso_parts.variant()(*args), _bpso_kernels.run_numba_serial(*args))
    stale = {"a part the kernel no longer has": [("e = exp(-v)", "e = 1.0")]}
    monkeypatch.setattr(bpso_parts, "PARTS", stale)
    with pytest.raises(RuntimeError, match="no longer holds 'a part the kernel no longer has'"):
        bpso_parts.variant("a part the kernel no longer has")


def test_the_iteration_count_is_where_the_kernel_stops(monkeypatch):
    """The counting variant selects what the kernel does, and its count is the iteration at which
    the global best first holds the eq19 optimum (the exact solver's value), q_max where it never
    does: checked against the numpy kernel run for 1, 2, ... iterations, which runs every one."""
    from agents.solvers import ExactSolver, _bpso_kernels
    from benchmarks.speed import bpso_parts

    counting = bpso_parts.counting_variant()
    for rule in ("set", "xor"):
        index, tx, rx, positions, keys, _, c1, c2, _, _, clamp, set_rule = bpso_parts.kernel_arguments(
            30, rule
        )
        # a constant inertia, so that a run of q iterations is the first q of a longer run
        swarm = (c1, c2, 0.65, 0.65, clamp, set_rule)
        iterations = 12
        args = (index, tx, rx, positions, keys, iterations, *swarm)
        counted = counting(*args)
        np.testing.assert_array_equal(counted[:, :-1], _bpso_kernels.run_numba_serial(*args))
        optimum = np.einsum("bm,bn,bmn->b", *ExactSolver(tx, rx).solve(index, None), index)
        first = np.full(len(index), iterations)
        for q in range(iterations, -1, -1):
            if q == 0:  # the starting swarm alone: the best of its valid particles
                fit, valid = _bpso_kernels._fitness_np(index, positions, 4, tx, rx)
                best = positions[np.arange(len(index)), np.argmax(np.where(valid, fit, -np.inf), axis=1)]
                value = np.einsum("bm,bn,bmn->b", best[:, :4], best[:, 4:], index)
            else:
                best = _bpso_kernels.run_numpy(index, tx, rx, positions, keys, q, *swarm)
                value = np.einsum("bm,bn,bmn->b", best[:, :4], best[:, 4:], index)
            first = np.where(value >= optimum, q, first)
        np.testing.assert_array_equal(counted[:, -1], first)
        assert 0 < np.mean(first < iterations) and (rule == "xor" or np.mean(first < iterations) > 0.5)
    monkeypatch.setattr(bpso_parts, "COUNTING", [("e = exp(-v)", "e = 1.0")])
    with pytest.raises(RuntimeError, match="iteration count"):
        bpso_parts.counting_variant()


def test_the_float32_transcription_selects_valid_super_arms_and_refuses_a_stale_replacement(monkeypatch):
    from agents.solvers import _bpso_kernels
    from benchmarks.speed import bpso_parts

    float32 = bpso_parts.float32_variant()
    for rule in ("set", "xor"):
        args = bpso_parts.kernel_arguments(200, rule)
        selected, kernel = float32(*args), _bpso_kernels.run_numba_serial(*args)
        assert (selected[:, :4].sum(axis=1) == 2).all() and (selected[:, 4:].sum(axis=1) == 3).all()
        # the same uniforms decide nearly every flip the same way in float32 and float64
        assert (selected == kernel).all(axis=1).mean() > 0.9
    result = bpso_parts.float32_comparison(trials=40, repeats=1)
    assert set(result["rules"]) == {"set", "xor"}
    for row in result["rules"].values():
        assert all(row[f"{k}_ms"] > 0 for k in ("kernel", "float32", "reference"))
        assert all(0 <= row[f"{k}_optimality_rate"] <= 1 for k in ("kernel", "float32", "reference"))
    monkeypatch.setattr(bpso_parts, "FLOAT32", [("e = exp(-v)", "e = 1.0")])
    with pytest.raises(RuntimeError, match="float32 transcription"):
        bpso_parts.float32_variant()
