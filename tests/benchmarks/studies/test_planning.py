"""The planning study on a few trials and steps: its runs, the best achievable bound beside
them, and its tables."""

import json

import pytest

from benchmarks.cli import main


def test_a_short_planning_study_reports_the_horizons_against_the_one_step_policies(tmp_path):
    out = tmp_path / "planning"
    argv = ["planning", "--scenarios", "1", "--fusions", "centralized", "--trials", "6", "--steps", "12"]
    assert main([*argv, "--workers", "1", "--quiet", "--out", str(out)]) == 0
    assert (out / "horizons.png").stat().st_size > 10_000  # ARMSE against H
    (run,) = json.loads((out / "planning.json").read_text())
    assert (run["scenario"], run["fusion"], run["trials"]) == (1, "centralized", 6)
    policies = run["policies"]
    assert {"best-tracking", "tracking-ucb", "plan-tracking:10", "plan-tracking-ucb:5"} <= set(policies)
    # H = 1 is best-tracking on the same trials: a difference of exactly zero
    same = run["minus"]["plan-tracking:1"]["best-tracking"]
    assert same["estimate"] == 0.0 and same["ci"] == [0.0, 0.0]
    # the best achievable bound is below every policy's own bound (a beam over the truth)
    best = run["best_bound"]["value"]
    assert all(best <= row["bound"]["value"] * (1 + 1e-9) for row in policies.values())
    for row in policies.values():  # ARMSE over the best bound, paired on trials, at equal weights
        ratio = row["armse_over_best_bound"]
        assert abs(ratio["estimate"] - row["armse"]["value"] / best) < 1e-9 * ratio["estimate"]
        assert ratio["ci"][0] <= ratio["estimate"] <= ratio["ci"][1]
    assert run["minus_best_tracking"]["plan-tracking:1"]["estimate"] == 0.0
    text = (out / "planning.md").read_text()
    assert text.startswith("# The planning study") and "Best achievable bound:" in text
    assert all(row["ms_per_trial_step"] > 0 for row in policies.values())
    _the_docs_say_what_the_planning_json_shows(tmp_path, out, run)


def _the_docs_say_what_the_planning_json_shows(tmp_path, out, run):
    """The values quoted in the docs count and judge from planning.json alone."""
    import shutil

    from benchmarks import verdicts
    from benchmarks.docs_tooling.generators import PLANNING_LEARNERS, planning_tables, planning_values

    docs = tmp_path / "docs"
    (docs / "results" / "planning").mkdir(parents=True)
    for name in ("planning.json", "timing.json"):
        shutil.copy(out / name, docs / "results" / "planning" / name)
    table = planning_values(docs)
    for learner in PLANNING_LEARNERS:
        better = verdicts.verdict(run["minus"][learner]["tracking-ucb"]["ci"], -1) == verdicts.HOLDS
        key = learner.replace(":", "-")
        assert (table[f"{key}.better"], table[f"{key}.studies"]) == (str(int(better)), "1")
    best = min(run["policies"], key=lambda p: run["policies"][p]["armse"]["value"])
    assert table["bound.1.best"] == f"`{best}`"  # the centralised run's best policy, against the best bound
    tables = planning_tables(docs)
    assert "## paper-1, centralized (6 trials)" in tables and "ARMSE / best bound" in tables


def test_the_planning_study_refuses_an_unknown_fusion_in_one_line(tmp_path, capsys):
    out = tmp_path / "planning"
    with pytest.raises(SystemExit) as exit_info:
        main(["planning", "--fusions", "median", "--out", str(out), "--quiet"])
    assert exit_info.value.code == 2
    assert "fusions must be among ['average', 'centralized']" in capsys.readouterr().err
    assert not out.exists()


def _run(folder, policies, trials, seed=0, **changes):
    from benchmarks import harness
    from benchmarks.study import Finished, Run
    from mimo_radar_env import VERSIONS

    options = VERSIONS["v1"].options(**changes)
    config = harness.make_config(
        "paper-1-v1", policies, trials, 10, seed, options=options, say=lambda _: None
    )
    harness.run(config, folder, progress=False)
    return Finished(Run(1, "paper-1-v1", tuple(policies), folder, options), config, {})


def test_planners_are_paired_with_another_runs_policies_on_the_trials_both_ran(tmp_path):
    """Against a group of another run's policies, the difference is the planner's ARMSE minus
    the group's mean ARMSE on the shared trials (computed here from a run of those trials
    alone); runs that do not share their trials are refused."""
    from benchmarks.errors import BenchError
    from benchmarks.studies.planning import cross_run_differences

    plan = _run(tmp_path / "plan", ["best-tracking", "plan-tracking:2"], trials=6)
    other = _run(tmp_path / "other", ["best-tracking", "random", "fix1"], trials=6)
    alone = _run(tmp_path / "alone", ["best-tracking", "plan-tracking:2", "random", "fix1"], trials=6)
    result = cross_run_differences(plan, other.folder, {"pair": ["random", "fix1"]}, seed=0)
    assert result["trials"] == 6
    d = result["minus"]["plan-tracking:2"]["pair"]

    from benchmarks import harness
    from benchmarks.report import trial_metrics

    metrics = trial_metrics(alone.config, harness.load_per_trial(alone.folder, alone.config))
    w = metrics["random"].equal()
    expected = (
        metrics["plan-tracking:2"].armse(w) - (metrics["random"].armse(w) + metrics["fix1"].armse(w)) / 2
    )
    assert abs(d["estimate"] - expected) < 1e-12
    assert d["ci"][0] <= d["estimate"] <= d["ci"][1]
    shifted = _run(tmp_path / "shifted", ["best-tracking", "random"], trials=6, seed=1)
    with pytest.raises(BenchError, match="another seed"):
        cross_run_differences(plan, shifted.folder, {"one": ["random"]}, seed=0)
    tracked_otherwise = _run(
        tmp_path / "otherwise", ["best-tracking", "random"], trials=6, filter_noise="estimated"
    )
    with pytest.raises(BenchError, match="do not share their trials"):
        cross_run_differences(plan, tracked_otherwise.folder, {"one": ["random"]}, seed=0)
