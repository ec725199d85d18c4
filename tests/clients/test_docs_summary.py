"""The results summary's computed statements (docs/results.md, and the README's copy): each
changes when an artefact it must cover changes."""

import json
import shutil
from pathlib import Path

import pytest

from benchmarks.docs_tooling import generators
from benchmarks.errors import BenchError

DOCS = Path(__file__).resolve().parents[2] / "docs"


@pytest.fixture
def docs(tmp_path):
    copy = tmp_path / "docs"
    shutil.copytree(DOCS, copy, ignore=shutil.ignore_patterns("*.png", "_build"))
    return copy


def edit(docs, relative, change):
    path = docs / "results" / relative
    record = json.loads(path.read_text())
    change(record)
    path.write_text(json.dumps(record))


def test_the_missed_targets_are_every_figure_below_its_target(docs):
    from benchmarks.speed.perf import TARGETS, target_met

    perf = json.loads((docs / "results/perf/perf.json").read_text())
    missed = [key for key in TARGETS if key in perf and not target_met(key, perf[key])]
    table = generators.summary_values(docs)
    assert [key for key in TARGETS if f"`{key}`" in table["missed"]] == missed
    edit(
        docs,
        "perf/perf.json",
        lambda r: r.update(bpso_speedup_vs_reference_xor=6.0, tracking_study_wall_s=1e4),
    )
    again = generators.summary_values(docs)["missed"]
    assert "bpso_speedup_vs_reference_xor" not in again and again.startswith("`tracking_study_wall_s`")


def test_the_sample_sizes_are_read_from_every_study(docs):
    table = generators.summary_values(docs)
    assert (table["claims.trials"], table["tracking.trials"], table["planning.trials"]) == (
        "500",
        "200",
        "50",
    )

    def fewer_seeds(record):
        for entry in record["scenarios"]:
            entry["learners"]["ppo-sinr"]["seeds"] = 2

    edit(docs, "rl/rl.json", fewer_seeds)
    assert generators.summary_values(docs)["rl.seeds"].endswith("2 for `ppo-sinr`")
    edit(docs, "planning/planning.json", lambda runs: runs[0].update(trials=49))
    with pytest.raises(BenchError, match="trials differ"):
        generators.summary_values(docs)


def test_the_readme_quotes_the_summary_of_the_results_page(docs):
    text = generators.results_summary(docs)
    page = (docs / "results.md").read_text()
    assert text.replace("](docs/", "](") in page
    (docs / "results.md").write_text(page.replace("**What to keep in mind:**", "**Caveats:**"))
    assert "**Caveats:**" in generators.results_summary(docs)
    (docs / "results.md").write_text("# Results\n")
    with pytest.raises(BenchError, match="no <!-- summary -->"):
        generators.results_summary(docs)


def test_the_tracking_targets_held_count_every_target(docs):
    targets = json.loads((docs / "results/tracking/targets.json").read_text())
    total = sum(len(r["best_tracking_lower"]) + len(r["tracking_ucb_lower"]) for r in targets)
    table = generators.summary_values(docs)
    assert table["targets"] == str(total) and table["targets.held"] == str(total)

    def one_fails(records):
        records[-1]["tracking_ucb_lower"][-1]["holds"] = False

    edit(docs, "tracking/targets.json", one_fails)
    assert generators.summary_values(docs)["targets.held"] == str(total - 1)


def test_the_armse_ratio_spans_every_policy_and_scenario(docs):
    from benchmarks.report import paper_armse

    ratios = []
    for n in (1, 2, 3):
        rows = json.loads((docs / f"results/v1/paper-{n}-v1-average.summary.json").read_text())["policies"]
        ratios += [row["armse"] / paper_armse(f"paper-{n}", p) for p, row in rows.items()]
    assert generators.summary_values(docs)["armse-ratio.average"] == f"{min(ratios):.1f} to {max(ratios):.1f}"


def test_the_planning_page_says_every_planner_gains_only_while_the_artefacts_show_it(docs):
    """ "Every planner looking ahead beats its one-step policy (the rollout most)" is checked on
    planning.json: a planner that stops beating it makes the values refuse to fill the page."""
    table = generators.planning_values(docs)
    assert float(table["gain.average"]) > float(table["gain.centralized"]) > 0

    def no_gain(runs):
        run = next(r for r in runs if r["fusion"] == "average")
        run["minus"]["plan-tracking-ucb:5"]["tracking-ucb"].update(estimate=0.01, ci=[-0.01, 0.03])

    edit(docs, "planning/planning.json", no_gain)
    with pytest.raises(BenchError, match="every planner looking ahead beats its one-step policy"):
        generators.planning_values(docs)
