"""The layout search: constraints, reproducibility, the objective and the predictor check."""

import numpy as np
import pytest

from benchmarks.studies import calibration, layout_search
from benchmarks.studies.layout_search import INFEASIBLE, layout_from_vector, v1_layout, vector_from_layout
from mimo_radar_env import RadarModel, load_scenario


def moved(station: int, km: tuple[float, float]) -> layout_search.Layout:
    x = vector_from_layout(v1_layout()).reshape(-1, 2)
    x[station] = km
    return layout_from_vector(x.ravel())


def test_v1_layout_meets_every_constraint():
    assert layout_search.violation(v1_layout()) == 0
    assert calibration.constraint_failure(v1_layout()) is None


@pytest.mark.parametrize(
    "case",
    ["outside the region", "on a track", "S1.1 broken"],
)
def test_a_layout_breaking_each_hard_constraint_is_rejected(case):
    if case == "outside the region":
        layout = moved(5, (101.0, 50.0))
        reason = "outside"
    elif case == "on a track":
        model = RadarModel.from_scenario(load_scenario("paper-2-v1"))
        point = model.nominal[0][300, [0, 2]] / 1e3  # a point of Scenario 2's nominal track (km)
        layout = moved(7, (float(point[0]), float(point[1]) + 1.0))  # 1 km from it at most
        reason = "km from a nominal track"
    else:  # TX1 and TX3 swap places: Best's Scenario 1 selections leave their windows
        x = vector_from_layout(v1_layout()).reshape(-1, 2)
        x[[0, 2]] = x[[2, 0]]
        layout = layout_from_vector(x.ravel())
        reason = "Best selects the paper's super arm"
    assert layout_search.violation(layout) > 0
    assert layout_search.objective(vector_from_layout(layout)) > INFEASIBLE
    assert reason in calibration.constraint_failure(layout)


def test_objective_of_a_feasible_layout_counts_its_predictors():
    p = layout_search.predictors(v1_layout())
    assert len(p["checks"]) == 12 and set(layout_search.PREDICTED) <= set(p["checks"])
    leads = list(p["median_lead"].values())
    assert all(lead > 0 for lead in leads)
    expected = -sum(p["checks"].values()) - min(leads[1:])
    assert layout_search.objective(vector_from_layout(v1_layout())) == pytest.approx(expected)


def test_search_is_reproducible_with_a_fixed_seed():
    a = layout_search.search(seed=4, generations=1, population=1)
    b = layout_search.search(seed=4, generations=1, population=1)
    assert a["ranked"] == b["ranked"] and a["evaluations"] == b["evaluations"] == 40
    assert a["v1_objective"] == b["v1_objective"] < 0
    # the first population holds v1's layout, so the best is at least as good as v1's
    assert a["ranked"][0]["objective"] <= a["v1_objective"]
    assert [e["objective"] for e in a["ranked"]] == sorted(e["objective"] for e in a["ranked"])


def test_distinct_feasible_skips_infeasible_and_repeated_layouts():
    ranked = [
        {"vector": [1.0, 2.0], "objective": -3.0},
        {"vector": [1.0, 2.0], "objective": -3.0},
        {"vector": [5.0, 2.0], "objective": INFEASIBLE + 1},
        {"vector": [7.0, 2.0], "objective": -1.0},
    ]
    assert [e["vector"] for e in layout_search.distinct_feasible(ranked, 3)] == [[1.0, 2.0], [7.0, 2.0]]


def test_agreement_compares_each_predictor_with_its_comparison():
    checks = {name: True for name in layout_search.PREDICTED}
    results = [
        {
            "id": claim,
            "comparisons": [{"comparison": text, "verdict": "holds" if i % 2 == 0 else "contradicted"}],
        }
        for i, (claim, text) in enumerate(layout_search.PREDICTED.values())
    ]
    a = layout_search.agreement(checks, results)
    assert a["compared"] == 4 and a["agree"] == 2
    assert np.array_equal([v["scorecard"] for v in a["pairs"].values()], [True, False, True, False])


def test_command_scores_the_best_layout_and_records_the_agreement(tmp_path):
    import json

    from benchmarks.cli import main as cli_main

    args = ["search-layouts", "--generations", "1", "--population", "1", "--final", "1", "--no-v1-scorecard"]
    assert cli_main([*args, "--trials", "6", "--steps", "20", "--quiet", "--out", str(tmp_path)]) == 0
    found = json.loads((tmp_path / "search.json").read_text())
    assert (found["trials"], found["steps"], found["evaluations"]) == (6, 20, 40)
    (finalist,) = found["finalists"]
    assert finalist["name"] == "search-1"
    judged = [v for v in finalist["verdicts"].values() if v in finalist["counts"]]
    assert all(finalist["counts"][k] == judged.count(k) for k in finalist["counts"])
    assert finalist["agreement"]["compared"] == len(layout_search.PREDICTED)
    assert (tmp_path / "search-1" / "claims.json").exists()


def test_command_scores_only_the_ranks_asked_for(tmp_path, capsys):
    import json

    from benchmarks.cli import main as cli_main

    args = ["search-layouts", "--generations", "1", "--population", "1", "--no-v1-scorecard", "--quiet"]
    with pytest.raises(SystemExit) as exit_info:
        cli_main([*args, "--final", "2", "--score", "3", "--trials", "6", "--out", str(tmp_path)])
    assert exit_info.value.code == 2
    assert "--score 3: ranks run from 1 to --final (2)" in capsys.readouterr().err
    assert not (tmp_path / "search.json").exists()  # refused before the search
    out = tmp_path / "scored"
    assert (
        cli_main([*args, "--final", "2", "--score", "2", "--trials", "6", "--steps", "5", "--out", str(out)])
        == 0
    )
    found = json.loads((out / "search.json").read_text())
    (finalist,) = found["finalists"]
    second = layout_search.distinct_feasible(found["ranked"], 2)[1]
    assert (finalist["name"], finalist["rank"], finalist["vector"]) == ("search-2", 2, second["vector"])
    assert not (out / "search-1").exists()


def test_the_search_and_its_scorecards_are_estimated_before_anything_runs(tmp_path, capsys, monkeypatch):
    """--max-hours is checked against the search (its layouts at the time one takes here) and
    its scorecards (each v1's paper study) before the search: a refusal is one line, exit 2,
    nothing written; the estimate counts the scorecards asked for."""
    from benchmarks.cli import main as cli_main
    from benchmarks.studies.layout_search import LayoutSearch

    estimates = []
    real = LayoutSearch.estimate_seconds
    monkeypatch.setattr(
        LayoutSearch, "estimate_seconds", lambda self, cards: estimates.append(cards) or real(self, cards)
    )
    out = tmp_path / "search"
    args = ["search-layouts", "--generations", "1", "--population", "1", "--quiet", "--out", str(out)]
    for extra, said in (
        (["--final", "0", "--no-v1-scorecard"], "the search and its 0 scorecard(s) would take about"),
        (["--final", "2", "--trials", "6", "--steps", "5"], "would take about"),  # a scorecard's run, or all
    ):
        with pytest.raises(SystemExit) as exit_info:
            cli_main([*args, *extra, "--max-hours", "1e-9"])
        assert exit_info.value.code == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and said in err[0] and "--max-hours 1e-09" in err[0]
        assert not out.exists()
    assert estimates == [0, 3]  # no scorecard; then two ranks and v1's own layout


def test_a_search_with_no_scorecard_finishes(tmp_path):
    """--final 0 with --no-v1-scorecard searches and scores nothing (it used to fail after the
    search on the empty list of ranks)."""
    import json

    from benchmarks.cli import main as cli_main

    args = ["search-layouts", "--generations", "1", "--population", "1", "--final", "0", "--no-v1-scorecard"]
    assert cli_main([*args, "--quiet", "--out", str(tmp_path)]) == 0
    found = json.loads((tmp_path / "search.json").read_text())
    assert found["finalists"] == [] and found["evaluations"] == 40
