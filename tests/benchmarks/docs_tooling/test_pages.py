"""The pages' generated blocks and value spans equal what the committed artefacts give; a changed artefact
number, an unknown generator and a number with no artefact are caught."""

import json
import re
import shutil
from pathlib import Path

import pytest

from benchmarks.cli import main
from benchmarks.docs_tooling.pages import regenerate

DOCS = Path(__file__).resolve().parents[3] / "docs"


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
    (tmp_path / "results").mkdir()
    (tmp_path / "page.md").write_text("<!-- generated: no-such-table -->\nx\n<!-- end generated -->\n")
    with pytest.raises(SystemExit) as exit_info:
        main(["docs", "--docs", str(tmp_path), "--check"])
    assert exit_info.value.code == 2 and "no generator called 'no-such-table'" in capsys.readouterr().err


@pytest.mark.parametrize("folder", ["", "plain"])
def test_a_folder_with_no_artefacts_is_refused_in_one_line(tmp_path, capsys, monkeypatch, folder):
    """``--docs ''`` is the current folder: a checkout's root, with the README's generated blocks
    and no artefacts beside them."""
    shutil.copy(DOCS.parent / "README.md", tmp_path / "README.md")
    (tmp_path / "plain").mkdir()
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        main(["docs", "--docs", folder, "--check"])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and err.count("\n") == 1
    assert f"--docs {folder!r} is not a docs folder: it has no results/ folder" in err


def test_a_missing_artefact_is_named_with_its_page_and_no_page_is_written(tmp_path, capsys):
    docs = tmp_path / "docs"
    shutil.copytree(DOCS, docs, ignore=shutil.ignore_patterns("_build", "*.png"))
    (docs / "results" / "perf" / "ray.json").unlink()
    first = docs / "agents.md"  # rendered before the page that reads the missing artefact
    first.write_text(first.read_text().replace("<!-- end generated -->", "stale\n<!-- end generated -->", 1))
    stale = first.read_text()
    with pytest.raises(SystemExit) as exit_info:
        main(["docs", "--docs", str(docs)])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert "benchmark.md:" in err and "ray.json" in err  # the first page that reads it
    assert first.read_text() == stale  # nothing written before the refusal


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


def test_a_value_span_anywhere_inside_a_code_span_is_found():
    """The page would show its comments as text: the span in the middle of a command line, as
    three of performance.md's did, is found; a value that carries its own backticks, a span between
    two code spans, and backticks left unpaired in their paragraph are not code around a span."""
    from benchmarks.docs_tooling.pages import coded_values

    span = "<!-- value: across x.first -->abc<!-- end value -->"
    inside = f"(`python -m tool {span} --key k`)"
    assert coded_values(inside) == [inside[1:-1]]
    assert coded_values(f"``a ` {span} ``") == [f"``a ` {span} ``"]  # a longer run closes it
    carried = "<!-- value: across x.command -->`python -m tool`<!-- end value -->"
    assert coded_values(f"running {carried}, then `b` and {span} and `c`") == []
    assert coded_values(f"one ` here\n\nand {span} and ` there") == []  # two paragraphs: no pair
    assert coded_values("`<!-- value: <source> <key> -->...<!-- end value -->`") == []  # the syntax, shown


LED_CASES = {
    "a paragraph opened by a value": "<!-- value: a b -->1<!-- end value --> trials, one thread.\n",
    "a paragraph's second line opened by a value": "On\n<!-- value: a b -->1<!-- end value --> trials.\n",
    "a list item's second line": "- the rollout in\n  <!-- value: a b -->1<!-- end value --> of them\n",
    "a word first": "Measured\non <!-- value: a b -->1<!-- end value --> trials.\n",
    "a marker line alone": "<!-- generated: x -->\n| a |\n|---|\n<!-- end generated -->\n",
    "inside a code fence": "```text\n<!-- value: a b -->1<!-- end value --> shown as code\n```\n",
}


@pytest.mark.parametrize("name", LED_CASES)
def test_lines_led_by_a_comment_are_those_commonmark_makes_raw_html(name):
    """markdown-it, the parser of the site's MyST, makes a line that opens with a comment followed by text
    an HTML block of its own (the paragraph breaks and its Markdown shows as typed); the check finds exactly
    those lines, and not a marker standing alone or a comment shown in code."""
    from benchmarks.docs_tooling.pages import comment_led_lines

    markdown_it = pytest.importorskip("markdown_it")
    text = LED_CASES[name]
    raw = [
        token.map[0] + 1
        for token in markdown_it.MarkdownIt("commonmark").parse(text)
        if token.type == "html_block" and re.search(r"-->\s*\S", token.content.strip())
    ]
    assert comment_led_lines(text) == raw
    assert bool(raw) == (name not in ("a word first", "a marker line alone", "inside a code fence"))


def test_no_page_breaks_a_paragraph_at_a_value_and_a_page_that_does_fails(tmp_path, capsys):
    """Every committed page, parsed by markdown-it, keeps its value spans inside paragraphs, list items and
    tables; a page with a value at a line's start fails the check, naming the line."""
    markdown_it = pytest.importorskip("markdown_it")
    parser = markdown_it.MarkdownIt("commonmark")
    for page in [*DOCS.glob("*.md"), DOCS.parent / "README.md"]:
        raw = [
            t.map[0] + 1
            for t in parser.parse(page.read_text())
            if t.type == "html_block" and "value:" in t.content
        ]
        assert raw == [], f"{page.name}: {raw}"
    docs = tmp_path / "docs"
    shutil.copytree(DOCS, docs, ignore=shutil.ignore_patterns("_build", "*.png"))
    page = docs / "agents.md"
    text = page.read_text()
    opened = "finds the exact optimum\nin <!-- value:"
    assert opened in text
    page.write_text(text.replace(opened, "finds the exact optimum in\n<!-- value:"))
    line = text[: text.index(opened)].count("\n") + 2
    with pytest.raises(SystemExit) as exit:
        main(["docs", "--docs", str(docs), "--check"])
    assert exit.value.code == 2
    assert f"agents.md: line {line} opens with an HTML comment followed by text" in capsys.readouterr().err
