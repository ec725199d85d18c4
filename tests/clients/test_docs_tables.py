"""The docs' generated blocks equal what the committed artefacts give, and a changed artefact
number is caught."""

import json
import shutil
from pathlib import Path

import pytest

from benchmarks.cli import main
from benchmarks.docs_tooling.pages import regenerate

DOCS = Path(__file__).resolve().parents[2] / "docs"


def test_the_committed_docs_match_their_artefacts(capsys):
    assert regenerate(DOCS, check=True) == []
    assert main(["docs", "--docs", str(DOCS), "--check"]) == 0
    assert "match their artefacts" in capsys.readouterr().out


def test_a_changed_artefact_number_fails_the_check(tmp_path, capsys):
    docs = tmp_path / "docs"
    shutil.copytree(DOCS, docs, ignore=shutil.ignore_patterns("_build", "*.png"))
    path = docs / "results" / "calibration" / "calibration.json"
    report = json.loads(path.read_text())
    judged = next(c for c in report["candidates"] if c["index"] == report["best"])
    judged["scorecards"]["500"]["holds"] += 1  # one number of one artefact
    path.write_text(json.dumps(report))
    assert main(["docs", "--docs", str(docs), "--check"]) == 1
    out = capsys.readouterr().out
    assert "-| 116 (adopted) | 10 / 2 / 10 | 11 / 1 / 10 |" in out
    assert "+| 116 (adopted) | 10 / 2 / 10 | 12 / 1 / 10 |" in out
    before = (docs / "results-layouts.md").read_text()
    assert main(["docs", "--docs", str(docs)]) == 0  # regenerating writes the new number
    after = (docs / "results-layouts.md").read_text()
    assert after != before and "| 116 (adopted) | 10 / 2 / 10 | 12 / 1 / 10 |" in after
    assert main(["docs", "--docs", str(docs), "--check"]) == 0


def test_an_unknown_generator_is_named(tmp_path, capsys):
    (tmp_path / "page.md").write_text("<!-- generated: no-such-table -->\nx\n<!-- end generated -->\n")
    with pytest.raises(SystemExit) as exit_info:
        main(["docs", "--docs", str(tmp_path), "--check"])
    assert exit_info.value.code == 2 and "no generator called 'no-such-table'" in capsys.readouterr().err


def test_prose_numbers_need_an_artefact(tmp_path, capsys):
    from benchmarks.docs_tooling.pages import unsourced_numbers

    text = (
        "It took 12.5 s and was 1.7x faster, 3 times more, optimal in 96.0 % [92.3, 98.0] of cases\n"
        "with 95 % intervals; `clipped to [0.2, 1.2]` in code, 1000 steps, 120 super arms;\n"
        "<!-- value: model nees-ncv -->4.01 [3.96, 4.06]<!-- end value --> and 17 % of a step.\n"
    )
    assert unsourced_numbers(text) == [
        (1, "12.5 s"),
        (1, "1.7x"),
        (1, "96.0 %"),
        (1, "[92.3, 98.0]"),
        (3, "17 %"),
    ]
    docs = tmp_path / "docs"
    shutil.copytree(DOCS, docs, ignore=shutil.ignore_patterns("_build", "*.png"))
    page = docs / "model.md"
    page.write_text(page.read_text() + "\nA step takes 12.5 s here.\n")
    assert main(["docs", "--docs", str(docs), "--check"]) == 1
    out = capsys.readouterr().out
    assert "model.md:" in out and "'12.5 s' is quoted without an artefact" in out
    assert "1 number(s) in prose rest on no artefact" in out


def test_value_spans_are_filled_from_the_figures(tmp_path, capsys):
    docs = tmp_path / "docs"
    shutil.copytree(DOCS, docs, ignore=shutil.ignore_patterns("_build", "*.png"))
    path = docs / "results" / "model" / "figures.json"
    record = json.loads(path.read_text())
    record["figures"]["nees-imm"].update(value=3.5, ci=[3.4, 3.6])
    path.write_text(json.dumps(record))
    assert main(["docs", "--docs", str(docs), "--check"]) == 1
    assert "+  <!-- value: model nees-imm -->3.50 [3.40, 3.60]<!-- end value -->" in capsys.readouterr().out
    page = docs / "model.md"
    page.write_text(page.read_text() + "\n<!-- value: model no-such-figure -->1<!-- end value -->\n")
    with pytest.raises(SystemExit) as exit_info:
        main(["docs", "--docs", str(docs)])
    assert exit_info.value.code == 2 and "no figure 'no-such-figure'" in capsys.readouterr().err


def test_a_value_table_is_read_once_per_rendering_and_names_its_keys(tmp_path):
    """A page's sentence quotes a value table's keys; a key the table lacks is named with the
    keys it has, and a value span inside a code span (whose comments Markdown would show) is
    refused."""
    from benchmarks.docs_tooling import generators
    from benchmarks.docs_tooling.pages import render
    from benchmarks.errors import BenchError

    calls = []

    @generators.values("test-table")
    def table(docs):
        calls.append(docs)
        return {"a": "1", "b": "two"}

    try:
        span = "<!-- value: test-table {} -->?<!-- end value -->"
        page = f"A {span.format('a')} and {span.format('b')}."
        assert render(page, tmp_path) == page.replace("?", "1", 1).replace("?", "two", 1)
        assert calls == [tmp_path]
        render(page, tmp_path)
        assert len(calls) == 2  # a new rendering reads the artefacts again
        with pytest.raises(BenchError, match="the values 'test-table' have no 'c'; they have: a, b"):
            render("<!-- value: test-table c -->?<!-- end value -->", tmp_path)
        with pytest.raises(BenchError, match="inside a code span"):
            render("`<!-- value: test-table a -->1<!-- end value -->`", tmp_path)
    finally:
        del generators.VALUE_SOURCES["test-table"]


def test_the_reading_moves_are_each_column_against_the_one_it_modifies(tmp_path):
    """Hand-made scorecards: each change lists exactly the claims whose verdict differs from the
    column it modifies (not from the column beside it), and the claims contradicted everywhere."""
    from benchmarks.docs_tooling import generators

    docs = tmp_path / "docs"
    (docs / "results" / "claims").mkdir(parents=True)
    base = {"S1": "holds", "S2": "contradicted", "A1": "consistent"}
    columns = {
        "v0": base,
        "v0 + dB": base | {"A1": "holds"},
        "v0 + shared truth": base,
        "v0 + set rule": base | {"S1": "consistent", "A1": "contradicted"},
        "v1, section 1 layout": base | {"A1": "holds"},
        "v1": base | {"A1": "holds", "S1": "contradicted"},
        "v1, centralised": base | {"A1": "holds", "S1": "contradicted"},
    }
    for label, path in generators.READINGS.items():
        card = [{"id": claim, "verdict": verdict} for claim, verdict in columns[label].items()]
        (docs / "results" / path).write_text(json.dumps(card))
    table = generators.reading_values(docs)
    assert (table["db.moves"], table["db.holds"], table["db.base-holds"]) == (
        "A1 (consistent to holds)",
        "2",
        "1",
    )
    assert table["shared-truth.moves"] == "no claim"
    assert table["set-rule.moves"] == "S1 (holds to consistent), A1 (consistent to contradicted)"
    assert table["set-rule.holds"] == "0"
    # the section 1 layout is against v0, the calibrated layout against the section 1 layout
    assert table["all-three.moves"] == "A1 (consistent to holds)"
    assert (table["layout.moves"], table["layout.holds"]) == ("S1 (holds to contradicted)", "1")
    assert table["centralized.moves"] == "no claim"
    assert (table["always"], table["always.count"]) == ("S2", "1")
