"""The scorecard judges claims right on synthetic studies whose answers are known."""

import json

import numpy as np
import pytest

from benchmarks import uncertainty, verdicts
from benchmarks.cli import main
from benchmarks.studies import claims
from mimo_radar_env import load_scenario

SHARED = np.random.default_rng(9).normal(0, 0.5, size=(60, 1))  # per-trial, common to all policies


def _metrics(rng, regret_per_step, n=60, t=1000):
    """A policy whose per-trial regret per step is ``regret_per_step`` plus trial noise shared
    across policies (the paired part) and a little of its own."""
    optimal = np.full((n, t), 5.0, np.float32)
    shared = SHARED
    expected = (optimal - regret_per_step - shared - rng.normal(0, 0.01, size=(n, t))).astype(np.float32)
    return uncertainty.TrialMetrics(
        {
            "trial_expected": expected,
            "trial_optimal": optimal,
            "trial_squared_error": np.full((n, t, 1), 4.0, np.float32),
            "trial_matches": np.zeros((n, t), np.uint8),
        },
        channels=6,
    )


@pytest.mark.parametrize(
    ("mg_regret", "verdict"),
    [(0.5, "holds"), (1.0, "consistent"), (1.5, "contradicted")],
)
def test_s2_3_is_judged_right(mg_regret, verdict):
    """S2.3: MG-CRB-CL's final regret below UCB1's and epsilon-greedy's (both at 1.0 per step)."""
    rng = np.random.default_rng(0)
    study = claims.Policies(
        {
            "mg-crb-cl": _metrics(rng, mg_regret),
            "ucb1": _metrics(rng, 1.0),
            "epsilon-greedy": _metrics(rng, 1.0),
        }
    )
    results = {r["id"]: r for r in claims.evaluate({"paper-2": study})}
    assert results["S2.3"]["verdict"] == verdict
    for comparison in results["S2.3"]["comparisons"]:
        assert comparison["estimate"] == pytest.approx(1000 * (mg_regret - 1.0), rel=0.02, abs=15)
    assert "S1.2" not in results  # a scenario that was not run
    first = results["S2.1"]["comparisons"][0]  # epsilon-greedy vs fix1: fix1 was not run
    assert first["verdict"] == "not evaluated" and results["S2.1"]["verdict"] != "holds"


def test_what_prepare_computes_early_is_what_the_judge_reads_with_the_same_numbers(monkeypatch):
    """Each policy prepared alone (as its tasks end): the judge then computes no ARMSE term of its
    own (every windowed and per-target term of the claims was prepared on the resamples it draws),
    and judges every claim of the scenario as it does afresh, to the bit."""
    from benchmarks import metrics as metrics_module
    from benchmarks.harness import PAPER_POLICIES

    def study():
        rng = np.random.default_rng(3)
        made = {p: _metrics(rng, 0.2 * i) for i, p in enumerate(PAPER_POLICIES)}
        for i, m in enumerate(made.values()):  # position errors that differ by policy and trial
            m.squared = (m.squared * (1 + i + rng.random((60, 1000, 1)))).astype(np.float32)
        return claims.Policies(made, load_scenario("paper-1-v1"))

    afresh = claims.evaluate({"paper-1": study()}, seed=4)
    prepared = study()
    for policy, metrics in prepared.items():
        claims.prepare("paper-1", policy, metrics, seed=4)
    calls = []
    terms = metrics_module._root_mean_square
    monkeypatch.setattr(
        metrics_module, "_root_mean_square", lambda *a, **k: calls.append(1) or terms(*a, **k)
    )
    judged = claims.evaluate({"paper-1": prepared}, seed=4)
    assert calls == []
    assert any(
        "armse" in c["comparison"] and " over " in c["comparison"] for r in judged for c in r["comparisons"]
    )
    assert json.dumps(judged, sort_keys=True) == json.dumps(afresh, sort_keys=True)
    prepared = study()
    for policy, metrics in prepared.items():  # another seed: other resamples, none of them reused
        claims.prepare("paper-1", policy, metrics, seed=5)
    assert json.dumps(claims.evaluate({"paper-1": prepared}, seed=4), sort_keys=True) == json.dumps(
        afresh, sort_keys=True
    )
    assert calls != []
    untracked = _metrics(np.random.default_rng(0), 0.0)
    untracked.tracked = False  # a run without the tracker: no ARMSE to prepare, the judge says so
    claims.prepare("paper-1", "ucb1", untracked, seed=4)


def test_claim_verdicts_combine_their_comparisons():
    assert verdicts.combine(["holds", "holds"]) == "holds"
    assert verdicts.combine(["holds", "consistent"]) == "consistent"
    assert verdicts.combine(["holds", "contradicted", "consistent"]) == "contradicted"
    assert verdicts.combine(["holds", "not evaluated"]) == "consistent"
    assert verdicts.combine(["not evaluated"]) == "not evaluated"


def test_every_claim_names_policies_the_paper_study_runs():
    from benchmarks.harness import PAPER_POLICIES

    for claim in claims.paper_claims():
        for comparison in claim.comparisons:
            assert set(comparison.policies) <= set(PAPER_POLICIES), (claim.id, comparison.text)


def test_claims_subcommand_runs_and_writes_the_scorecard(tmp_path, capsys):
    argv = ["claims", "--scenarios", "1", "--trials", "6", "--steps", "60", "--workers", "1"]
    assert main([*argv, "--quiet", "--no-figures", "--out", str(tmp_path)]) == 0
    card = (tmp_path / "claims.md").read_text()
    assert "| S1.1 | paper-1 | **holds** |" in card  # the noise-free Best selections
    assert "not evaluated" in card  # windows past 60 s
    assert (tmp_path / "claims.json").exists() and (tmp_path / "paper-1-v1" / "summary.json").exists()
    with pytest.raises(SystemExit):
        main(["claims", "--scenarios", "4", "--out", str(tmp_path / "x"), "--quiet"])


def test_the_claims_command_judges_the_metrics_its_report_read(tmp_path, monkeypatch):
    """No shard is read back: the report joins the shards the run wrote, held in memory, and the
    judge takes the report's metrics; its scorecard is the one judged from the folder afresh."""
    from benchmarks import harness

    reads = []
    read = harness.read_shard

    def counted(path, *args):
        reads.append(path)
        return read(path, *args)

    monkeypatch.setattr(harness, "read_shard", counted)
    argv = ["claims", "--scenarios", "1", "--trials", "6", "--steps", "30", "--workers", "1"]
    assert main([*argv, "--quiet", "--no-figures", "--out", str(tmp_path)]) == 0
    assert reads == []
    judged = json.loads((tmp_path / "claims.json").read_text())
    assert judged == json.loads(json.dumps(claims.judge_studies([tmp_path / "paper-1-v1"])))
    shards = sorted((tmp_path / "paper-1-v1" / "shards").rglob("*.npz"))
    assert len(shards) == 6 and sorted(reads) == shards  # judged afresh: each shard read from the folder


def test_each_policys_intervals_are_computed_while_the_other_tasks_run(tmp_path, monkeypatch):
    """A policy's metrics and intervals, and the claims' parts of it (:func:`claims.prepare`), are
    computed as soon as its last shard is saved, between the tasks, not all after the last one;
    the summary is the one computed afresh from the folder."""
    from benchmarks import harness, report, uncertainty

    events = []
    task, estimates = harness.run_task, uncertainty.policy_estimates
    monkeypatch.setattr(harness, "run_task", lambda *args: events.append("task") or task(*args))
    monkeypatch.setattr(
        uncertainty, "policy_estimates", lambda *args: events.append("estimates") or estimates(*args)
    )
    prepare = claims.prepare
    monkeypatch.setattr(claims, "prepare", lambda *args: events.append("prepare") or prepare(*args))
    argv = [
        "claims",
        "--scenarios",
        "1",
        "--trials",
        "6",
        "--steps",
        "30",
        "--workers",
        "1",
        "--shard-size",
        "6",
    ]
    assert main([*argv, "--quiet", "--no-figures", "--out", str(tmp_path)]) == 0
    # one task a policy, each followed by its intervals and what the claims read of it alone
    assert events == ["task", "estimates", "prepare"] * 6
    monkeypatch.undo()
    folder = tmp_path / "paper-1-v1"
    config = harness.RunConfig(**json.loads((folder / "config.json").read_text()))
    afresh = report.summarize(config, harness.load_per_trial(folder, config))
    assert json.loads((folder / "summary.json").read_text()) == json.loads(json.dumps(afresh))


def test_compare_claims_puts_scorecards_side_by_side(tmp_path, capsys):
    import json

    first = [{"id": "S1.2", "scenario": "paper-1", "claim": "c", "verdict": "holds"}]
    second = [{"id": "S1.2", "scenario": "paper-1", "claim": "c", "verdict": "contradicted"}]
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "claims.json").write_text(json.dumps(first))
    (tmp_path / "b.json").write_text(json.dumps(second))
    assert main(["compare-claims", f"v0={tmp_path / 'a'}", f"v1={tmp_path / 'b.json'}"]) == 0
    table = capsys.readouterr().out
    assert "| S1.2 | paper-1 | c | holds | contradicted |" in table
    assert "| **holds** | | | 1 | 0 |" in table and "| **contradicted** | | | 0 | 1 |" in table
    with pytest.raises(SystemExit):
        main(["compare-claims", f"x={tmp_path / 'missing'}"])


def test_each_scenario_runs_in_a_folder_of_its_name_inside_out(tmp_path):
    """The paper study writes a scenario's run into OUT/<name>; scenario names are checked (test_validation)
    so that this folder is always a child of OUT."""
    scenarios = [load_scenario("paper-2-v1", name=name) for name in ("caf\xe9", "v1+jitter.2")]
    runs = claims.paper_runs([*scenarios, "paper-1-v1"], tmp_path)
    assert [(run.folder.parent, run.folder.name) for run in runs] == [
        (tmp_path, "caf\xe9"),
        (tmp_path, "v1+jitter.2"),
        (tmp_path, "paper-1-v1"),
    ]
