"""The tracking study's command: its runs, targets and trade-off figure, against its summaries."""

import json
import re

import pytest

from benchmarks.cli import main
from benchmarks.harness import PAPER_POLICIES
from benchmarks.studies import tracking


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("tracking")
    args = ["tracking", "--out", str(out), "--scenarios", "2", "--fusions", "centralized"]
    args += ["--trials", "6", "--steps", "15", "--shard-size", "3", "--workers", "1", "--quiet"]
    assert main(args) == 0
    return out


def test_it_runs_every_policy_and_writes_the_targets_and_figure(study, capsys):
    folder = study / "paper-2-v1-centralized"
    summary = json.loads((folder / "summary.json").read_text())
    assert list(summary["policies"]) == list(tracking.TRACKING_POLICIES)
    assert summary["env_options"]["fusion"] == "centralized" and summary["trials"] == 6
    config = json.loads((folder / "config.json").read_text())
    assert config["agent_params"] == {"mg-crb-cl": {"solver_params": {"rule": "set"}}}  # v1's reading
    assert (study / "tradeoff_paper-2.png").stat().st_size > 0
    text = (study / "targets.md").read_text()
    assert "best-tracking has a lower ARMSE" in text
    row = summary["policies"]["tracking-ucb"]
    line = next(x for x in text.splitlines() if x.startswith("| tracking-ucb | "))
    assert f"{row['armse']:.3f} [{row['ci']['armse'][0]:.3f}, {row['ci']['armse'][1]:.3f}]" in line
    assert f"{row['bound']:.3f} [{row['ci']['bound'][0]:.3f}, {row['ci']['bound'][1]:.3f}]" in line


def test_targets_follow_from_the_summary(study):
    (result,) = json.loads((study / tracking.TARGETS_FILE).read_text())
    summary = json.loads((study / "paper-2-v1-centralized" / "summary.json").read_text())
    rows = summary["policies"]
    assert (result["scenario"], result["fusion"]) == (2, "centralized")
    judged = result["best_tracking_lower"] + result["tracking_ucb_lower"]
    assert [(c["a"], c["b"]) for c in judged] == [("best-tracking", p) for p in PAPER_POLICIES] + [
        ("tracking-ucb", "best"),
        ("tracking-ucb", "mg-crb-cl"),
    ]
    for c in judged:
        # the paired estimate is the difference of the two ARMSEs: one metrics path, to round-off
        assert c["difference"] == pytest.approx(
            rows[c["a"]]["armse"] - rows[c["b"]]["armse"], rel=1e-12, abs=1e-14
        )
        assert c["verdict"] in ("holds", "consistent", "contradicted")
        assert c["ci"][0] <= c["ci"][1] and c["holds"] == (c["ci"][1] < 0)
    for policy, cost in result["cost"].items():
        assert cost["ratio"] == pytest.approx(rows[policy]["wall_s"] / rows["mg-crb-cl"]["wall_s"])
        assert cost["holds"] == (cost["ratio"] <= tracking.COST_LIMIT)
    assert result["regret"]["tracking-ucb"]["value"] == rows["tracking-ucb"]["final_regret"]


def test_paired_reads_either_order():
    summary = {"paired_differences": {"a - b": {"armse": {"estimate": 1.0, "ci": [0.5, 2.0]}}}}
    assert tracking.paired(summary, "a", "b", "armse") == (1.0, [0.5, 2.0])
    assert tracking.paired(summary, "b", "a", "armse") == (-1.0, [-2.0, -0.5])


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--fusion", "average"], "--fusion does not apply"),
        (["--fusions", "mean"], r"fusions must be among \['average', 'centralized'\]"),
        (["--scenarios", "4"], "--scenarios must list paper scenarios 1, 2, 3"),
        (["--ppo", "runs/{model}/model.zip"], r"a pattern may hold \{scenario\} and \{fusion\} only"),
    ],
)
def test_bad_arguments_are_named(tmp_path, capsys, extra, message):
    with pytest.raises(SystemExit) as exit_info:
        main(["tracking", "--out", str(tmp_path / "x"), "--trials", "6", "--quiet", *extra])
    assert exit_info.value.code == 2
    assert re.search(message, capsys.readouterr().err)
