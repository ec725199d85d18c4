"""Reports: the table's cells and marks, and the summary against the curves."""

import csv
import json

import numpy as np
import pytest

from benchmarks import report
from benchmarks.cli import main


def test_cells_carry_the_interval_and_its_method_mark():
    assert report.format_estimate(1.23456, [1.2, 1.3], "{:.3f}") == "1.235 [1.200, 1.300]"
    assert report.format_estimate(0.5, [0.4, 0.6], "{:.2f}", 100, "percentile") == "50.00 [40.00, 60.00]†"
    assert (
        report.format_estimate(2.0, [2.0, 2.0], "{:.1f}", method="constant over trials") == "2.0 [2.0, 2.0]‡"
    )
    assert report.format_estimate(-0.0001, None, "{:.1f}") == "0.0"  # never -0.0
    assert report.format_estimate(None, None, "{:.1f}") == "—"


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    argv = [
        "run",
        "--scenario",
        "paper-3-v1",
        "--policies",
        "mg-crb-cl,fix2",
        "--trials",
        "6",
        "--steps",
        "12",
    ]
    assert main([*argv, "--workers", "1", "--quiet", "--out", str(out)]) == 0
    return out


def test_the_summary_follows_from_the_curves(small_run):
    summary = json.loads((small_run / "summary.json").read_text())
    with open(small_run / "curves.csv") as handle:
        rows = list(csv.DictReader(handle))
    for policy, row in summary["policies"].items():
        mine = [r for r in rows if r["policy"] == policy]
        rmse = np.array([[float(r[f"rmse_target{k}"]) for k in (1, 2)] for r in mine])
        assert row["armse_per_target"] == pytest.approx(list(rmse.mean(axis=0)), rel=1e-9)
        assert row["final_regret"] == pytest.approx(float(mine[-1]["cumulative_regret"]), rel=1e-9)
        assert row["asr"] == pytest.approx(np.mean([float(r["asr"]) for r in mine]), abs=1e-12)
        linear = np.mean([10 ** (float(r["mean_sinr_db"]) / 10) for r in mine])
        assert row["mean_sinr_db"] == pytest.approx(10 * np.log10(linear), rel=1e-9)
        assert row["method"]["armse"] == "bias-corrected percentile"  # 6 trials: a root of a mean
        # a mean: bootstrap-t, or percentile where resamples of one value (12 steps' share of
        # optimal selections is one of 13 values) leave its t infinite
        assert row["method"]["asr"] in ("bootstrap-t", "percentile", "constant over trials")


def test_the_table_shows_the_summary_with_marks(small_run):
    summary = json.loads((small_run / "summary.json").read_text())
    table = (small_run / "table.md").read_text()
    row = summary["policies"]["fix2"]
    assert f"{row['bound']:.3f} [{row['ci']['bound'][0]:.3f}, {row['ci']['bound'][1]:.3f}]‡" in table
    assert report.method_legend(summary["trials"]) in table


def test_a_table_of_fewer_trials_than_40_marks_its_bias_corrected_and_bootstrap_t_intervals(small_run):
    """On fewer than 40 trials ARMSE's interval is bias-corrected and final regret's a bootstrap-t
    (docs/benchmark.md): their cells carry their marks and the table says what they mean; a
    table of 40 trials does not."""
    summary = json.loads((small_run / "summary.json").read_text())
    table = (small_run / "table.md").read_text()  # 6 trials
    legend = report.method_legend(6)
    assert legend in table and "§" in legend and "¶" in legend
    row = summary["policies"]["mg-crb-cl"]
    assert row["method"]["armse"] == "bias-corrected percentile"
    assert f"{row['armse']:.3f} [{row['ci']['armse'][0]:.3f}, {row['ci']['armse'][1]:.3f}]§" in table
    assert row["method"]["final_regret"] == "bootstrap-t"
    regret, (low, high) = row["final_regret"], row["ci"]["final_regret"]
    assert f"{regret:.1f} [{low:.1f}, {high:.1f}]¶" in table
    assert legend in report.table_markdown(summary, 2, intervals="short")
    legend_40 = report.table_markdown(summary | {"trials": 40}, 2).split("|")[0]
    assert "§" not in legend_40 and "¶" not in legend_40


def test_the_run_output_explains_once_and_says_where_its_files_are(tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1,random,fix1,best", "--trials", "6"]
    argv += ["--steps", "4", "--workers", "1", "--quiet", "--no-figures", "--out", str(out)]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    lines = printed.strip().splitlines()
    assert report.LEGEND in lines  # ASR, bound, regret and their units, in one line
    assert "bootstrap over trials" not in printed  # how intervals are computed: in table.md
    assert lines[-1] == f"outputs in {out}: table.md, summary.json, curves.csv"
    assert [line.split(" |")[0] for line in lines if line.startswith("| ucb1 - ")] == [
        "| ucb1 - random", "| ucb1 - fix1", "| ucb1 - best"
    ]  # fmt: skip
    assert "paper ARMSE" not in printed  # 4 steps are not the paper's 1000
    table = (out / "table.md").read_text()
    assert table.count("bootstrap over trials") == 1
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["paired_differences"]) == 6  # every pair is kept
    assert main([*argv[:-1], str(tmp_path / "all"), "--pairs", "all"]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ") and " - " in line]
    assert len(rows) == 1 + 6  # the header and every pair
    assert main(argv) == 0  # again into the same folder: nothing left to run
    assert "resumed: 4 of 4 tasks already done in" in capsys.readouterr().err


def test_the_papers_numbers_stand_beside_a_run_only_at_its_horizon():
    row = {key: None for key in report.VALUE_KEYS} | {"wall_s": 1.0}
    summary = {"scenario": "paper-1-v1", "trials": 1, "seed": 0, "policies": {"mg-crb-cl": row}}
    summary["env_options"] = {"fusion": "average"}
    assert "paper ARMSE (m)" in report.table_markdown({**summary, "steps": 1000}, 1)
    assert "paper ARMSE (m)" not in report.table_markdown({**summary, "steps": 999}, 1)
    assert "paper ARMSE (m)" not in report.table_markdown({**summary, "scenario": "x", "steps": 1000}, 1)


def test_a_policy_with_parameters_of_the_runs_own_is_labelled_with_them(tmp_path, capsys):
    assert (
        report.policy_label("mg-crb-cl", {"solver_params": {"rule": "set"}})
        == "mg-crb-cl (solver_params.rule=set)"
    )
    assert report.policy_label("ppo:runs/ppo-paper1/model.zip") == "ppo (ppo-paper1)"
    assert report.policy_label("tracking-ucb:0.5") == "tracking-ucb:0.5"
    argv = ["--trials", "2", "--steps", "2", "--workers", "1", "--quiet", "--no-figures"]
    assert main(["paper", "--scenario", "1", *argv, "--out", str(tmp_path / "paper")]) == 0
    assert "| mg-crb-cl (solver_params.rule=set) |" in capsys.readouterr().out  # v1's paper study
    run = [
        "run",
        "--scenario",
        "paper-1-v1",
        "--policies",
        "mg-crb-cl,ucb1",
        *argv,
        "--out",
        str(tmp_path / "run"),
    ]
    assert main(run) == 0
    assert "| mg-crb-cl |" in capsys.readouterr().out  # the agent's defaults


def test_the_papers_numbers_stand_beside_its_policy_only_as_the_version_reads_it():
    """Under v1 the paper's MG-CRB-CL is BPSO's standard rule: a row of the agent's default rule
    (the same name, another policy) gets no paper numbers; under v0 the default is the paper's."""
    row = {key: None for key in report.VALUE_KEYS} | {"wall_s": 1.0}
    base = {"trials": 1, "seed": 0, "steps": 1000, "env_options": {"fusion": "average"}}
    base["policies"] = {"mg-crb-cl": row}

    def paper_cells(scenario, params):
        table = report.table_markdown({**base, "scenario": scenario, "agent_params": params}, 1)
        line = next(line for line in table.splitlines() if line.startswith("| mg-crb-cl"))
        return line.split(" | ")[-2:]

    assert paper_cells("paper-1-v1", {}) == ["—", "— |"]
    assert paper_cells("paper-1-v1", {"mg-crb-cl": {"solver_params": {"rule": "set"}}}) == [
        "1.1030",
        "45.84 |",
    ]
    assert paper_cells("paper-1", {}) == ["1.1030", "45.84 |"]


def test_fewer_trials_than_an_interval_needs_give_estimates_and_say_why(tmp_path, capsys):
    """On 2 to 5 trials a bootstrap interval cannot hold 95 %: it lies within the trials' range.
    The table gives the estimates alone and says so, and the summary has neither intervals nor
    paired differences."""
    from benchmarks import uncertainty

    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1,best", "--trials", "5", "--steps", "4"]
    assert main([*argv, "--workers", "1", "--quiet", "--no-figures", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert "uncertainty" not in summary and "paired_differences" not in summary
    assert all("ci" not in row for row in summary["policies"].values())
    table = (out / "table.md").read_text()
    assert uncertainty.NO_INTERVALS in table and "[" not in table.split("| policy |")[1]
    assert uncertainty.NO_INTERVALS in capsys.readouterr().out
