"""The perf command's quick mode and the speed suite's parts: every figure is produced, and each
means what it says (a ratio is the quotient of the two figures measured beside it, a rate the
work done over the time it took, a share within 0 and 1)."""

import json
import sys

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


def test_a_figure_is_compared_across_two_commits_of_a_repository(tmp_path):
    """Two commits of a small repository whose benchmark prints a known number: the comparison
    checks each out, runs it there and takes the number from its JSON line."""
    import subprocess

    from benchmarks.speed import across_commits

    repo = tmp_path / "repo"
    repo.mkdir()

    def git(*args):
        subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True)

    git("init", "-q")
    commits = []
    for value in (6.0, 2.0):
        (repo / "bench.py").write_text(
            f"import json\nprint('warming up')\nprint(json.dumps({{'ms': {value}}}))\n"
        )
        git("add", "bench.py")
        git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", f"ms {value}")
        commits.append(
            subprocess.run(
                ["git", "-C", str(repo), "rev-parse", "HEAD"], capture_output=True, text=True
            ).stdout.strip()
        )
    out = tmp_path / "compare.json"
    argv = [commits[0], commits[1], "--key", "ms", "--repeats", "2", "--repo", str(repo), "--json", str(out)]
    result = across_commits.main([*argv, "--", sys.executable, "bench.py"])
    assert result["values"] == {commits[0]: [6.0, 6.0], commits[1]: [2.0, 2.0]}
    assert result["ratio"] == pytest.approx(3.0)
    assert json.loads(out.read_text())["ratio"] == pytest.approx(3.0)
    assert (
        subprocess.run(
            ["git", "-C", str(repo), "worktree", "list"], capture_output=True, text=True
        ).stdout.count("\n")
        == 1
    )
    with pytest.raises(RuntimeError, match="did not end with a JSON object holding 'nope'"):
        across_commits.compare(repo, (commits[0], commits[1]), [sys.executable, "bench.py"], "nope", 1)
