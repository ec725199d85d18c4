"""The layout search's values quoted in docs/results.md: which searched layouts beat v1's, what
each wins and loses, that the shipped scenario set has the scored stations, and which verdicts
move with the seed, each against a computation of its own from the artefacts."""

import json
import shutil
from pathlib import Path

import pytest

from benchmarks.docs_tooling import generators
from benchmarks.errors import BenchError

DOCS = Path(__file__).resolve().parents[2] / "docs"
RESCORED = Path("results/layout-search/rescored.json")


@pytest.fixture
def docs(tmp_path):
    copy = tmp_path / "docs"
    shutil.copytree(DOCS / "results", copy / "results", ignore=shutil.ignore_patterns("*.png", "*.md"))
    return copy


def load(docs, path):
    return json.loads((docs / path).read_text())


def verdicts_of(card):
    return {c["id"]: c["verdict"] for c in card}


def test_layouts_that_beat_v1_are_listed_with_what_they_win_and_lose(docs):
    v1 = verdicts_of(load(docs, "results/claims/v1.json"))
    v1_holds = sum(v == "holds" for v in v1.values())
    rescored = load(docs, RESCORED)
    table = generators.layout_values(docs)
    for f in rescored["finalists"]:
        holds = f["counts"]["holds"]
        assert (f["name"] in table["better"].split(", ")) == (holds > v1_holds)
        assert table[f"{f['name']}.holds"] == str(holds)
        won = [c for c in v1 if v1[c] != "holds" and f["verdicts"][c] == "holds"]
        lost = [c for c in v1 if v1[c] == "holds" and f["verdicts"][c] != "holds"]
        assert table[f"{f['name']}.won"] == (", ".join(won) or "none")
        assert table[f"{f['name']}.lost"] == (", ".join(lost) or "none")
    # one layout fewer above v1's count: it drops out of the list and the count says so
    ten = next(f for f in rescored["finalists"] if f["name"] == "search-10")
    ten["counts"]["holds"] = v1_holds
    (docs / RESCORED).write_text(json.dumps(rescored))
    table = generators.layout_values(docs)
    assert (table["better"], table["better.count"], table["scored"]) == ("search-5", "1", "5")


def test_the_shipped_layout_must_still_lead(docs):
    """The page says the shipped layout has the most claims holding with the fewest contradicted:
    when the artefacts stop saying so, the values refuse to be read."""
    rescored = load(docs, RESCORED)
    ten = next(f for f in rescored["finalists"] if f["name"] == "search-10")
    ten["counts"]["holds"] += 1
    (docs / RESCORED).write_text(json.dumps(rescored))
    with pytest.raises(BenchError, match="search-5 no longer has the most claims holding"):
        generators.layout_values(docs)


def test_the_shipped_set_must_have_the_scored_stations(docs):
    rescored = load(docs, RESCORED)
    five = next(f for f in rescored["finalists"] if f["name"] == "search-5")
    five["vector"][0] += 1.0  # 1 km off: no longer the shipped scenarios' first transmitter
    (docs / RESCORED).write_text(json.dumps(rescored))
    with pytest.raises(BenchError, match="search-5 of the 500-trial scorecards is not layout 5"):
        generators.layout_values(docs)
    top = load(docs, "results/layout-search/top10.json")
    ranked = [f for f in top["finalists"] if f["name"] != "v1"]
    ranked[4]["vector"][0] += 1.0  # the search's own rank 5 moved too: now the stations disagree
    (docs / "results/layout-search/top10.json").write_text(json.dumps(top))
    with pytest.raises(BenchError, match="does not have the stations of search-5"):
        generators.layout_values(docs)


def test_seed_sensitivity_names_the_verdicts_that_move(docs):
    v1_cards = [verdicts_of(load(docs, f"results/{p}")) for p in generators.SEED_SCORECARDS.values()]
    cards = {"layout 116": v1_cards}
    five = next(f for f in load(docs, RESCORED)["finalists"] if f["name"] == "search-5")
    cards["search-5"] = [five["verdicts"]] + [
        verdicts_of(load(docs, f"results/{p}")) for p in generators.SET_SEED_SCORECARDS.values()
    ]
    table = generators.layout_values(docs)
    for layout, seeds in cards.items():
        key = f"seeds.{layout.replace(' ', '-')}"
        moving = [c for c in seeds[0] if len({s[c] for s in seeds}) > 1]
        assert table[key] == str(len(seeds)) == "3"
        assert table[f"{key}.moving"] == (", ".join(moving) or "none")
        assert table[f"{key}.holds"] == ", ".join(str(sum(v == "holds" for v in s.values())) for s in seeds)


def test_the_always_contradicted_claims_are_computed_over_every_scorecard(docs):
    """The summary's "contradicted in each of the scorecards" covers the readings, the other master
    seeds and every searched layout: a claim that holds in any one of them leaves the list, and
    one contradicted everywhere is listed (computed here from the artefacts)."""
    files = [*generators.READINGS.values(), *generators.SEED_SCORECARDS.values()]
    files += list(generators.SET_SEED_SCORECARDS.values())
    cards = [verdicts_of(load(docs, f"results/{f}")) for f in dict.fromkeys(files)]
    search = load(docs, "results/layout-search/search.json")["finalists"]
    cards += [f["verdicts"] for f in search if f["name"] != "v1"]
    cards += [f["verdicts"] for f in load(docs, RESCORED)["finalists"]]
    expected = [c for c in cards[0] if all(card[c] == "contradicted" for card in cards)]
    table = generators.claims_values(docs)
    assert table["scorecards"] == str(len(cards))
    assert table["always-contradicted"] == ", ".join(expected)
    assert "S2.5" not in expected  # it holds under the searched layouts
    # make S1.7 hold under one searched layout: the sentence drops it
    rescored = load(docs, RESCORED)
    rescored["finalists"][-1]["verdicts"]["S1.7"] = "holds"
    (docs / RESCORED).write_text(json.dumps(rescored))
    again = generators.claims_values(docs)["always-contradicted"]
    assert "S1.7" in expected and "S1.7" not in again.split(", ")
