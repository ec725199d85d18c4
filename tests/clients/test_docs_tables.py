"""The docs' generated blocks equal what the committed artefacts give, and a changed artefact
number is caught."""

import json
import shutil
from pathlib import Path

import pytest

from benchmarks.cli import main
from benchmarks.doctables import regenerate

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
    before = (docs / "results.md").read_text()
    assert main(["docs", "--docs", str(docs)]) == 0  # regenerating writes the new number
    after = (docs / "results.md").read_text()
    assert after != before and "| 116 (adopted) | 10 / 2 / 10 | 12 / 1 / 10 |" in after
    assert main(["docs", "--docs", str(docs), "--check"]) == 0


def test_an_unknown_generator_is_named(tmp_path, capsys):
    (tmp_path / "page.md").write_text("<!-- generated: no-such-table -->\nx\n<!-- end generated -->\n")
    with pytest.raises(SystemExit) as exit_info:
        main(["docs", "--docs", str(tmp_path), "--check"])
    assert exit_info.value.code == 2 and "no generator called 'no-such-table'" in capsys.readouterr().err
