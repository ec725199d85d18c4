"""The docs' generated blocks: every table and number that reports a measurement is written by
code from a committed artefact, never by hand.

A page marks a generated block with two HTML comments (invisible on the site)::

    <!-- generated: claims-verdicts -->
    ...written by the generator "claims-verdicts"...
    <!-- end generated -->

``mimo-radar-bench docs`` rewrites every block of every page of ``--docs`` from the artefacts
under ``DOCS/results``; ``--check`` changes nothing and fails, naming the blocks, where a page
differs from what the artefacts give (CI runs it). A generator is a function of the docs folder
registered with :func:`generator`; each names the artefacts it reads.
"""

from __future__ import annotations

import argparse
import difflib
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .errors import BenchError
from .studies.base import Command

BLOCK = re.compile(r"(<!-- generated: ([\w.-]+) -->\n)(.*?)(<!-- end generated -->)", re.DOTALL)
Generator = Callable[[Path], str]
GENERATORS: dict[str, Generator] = {}


def generator(name: str) -> Callable[[Generator], Generator]:
    """Register a block generator under ``name``."""

    def register(function: Generator) -> Generator:
        GENERATORS[name] = function
        return function

    return register


def read_json(docs: Path, relative: str) -> Any:
    path = docs / "results" / relative
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise BenchError(f"the docs read {path}, which is missing or not JSON ({exc})") from None


def render(text: str, docs: Path) -> str:
    """``text`` with every generated block rewritten; an unknown generator is an error."""

    def fill(match: re.Match[str]) -> str:
        name = match.group(2)
        if name not in GENERATORS:
            raise BenchError(f"no generator called {name!r}; known: {sorted(GENERATORS)}")
        body = GENERATORS[name](docs).rstrip("\n") + "\n"
        return match.group(1) + body + match.group(4)

    return BLOCK.sub(fill, text)


def pages(docs: Path) -> list[Path]:
    return sorted(p for p in docs.glob("*.md") if BLOCK.search(p.read_text()))


def regenerate(docs: Path, check: bool = False) -> list[str]:
    """Rewrite every page's blocks (or, with ``check``, only compare); the differences found,
    as unified diffs (empty when the pages match the artefacts)."""
    from . import docs_generators  # noqa: F401  (registers the generators)

    differences = []
    for page in pages(docs):
        old = page.read_text()
        new = render(old, docs)
        if new != old:
            diff = difflib.unified_diff(
                old.splitlines(),
                new.splitlines(),
                f"{page} (committed)",
                f"{page} (from the artefacts)",
                lineterm="",
            )
            differences.append("\n".join(diff))
            if not check:
                page.write_text(new)
    return differences


class DocsCommand(Command):
    name = "docs"
    order = 10
    help = "regenerate the docs' tables and numbers from the committed artefacts (--check: compare only)"
    description = (
        "Rewrite every '<!-- generated: NAME -->' block of DOCS/*.md from the artefacts under DOCS/results; "
        "with --check, change nothing and fail where a page differs from its artefacts."
    )

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("--docs", default="docs", help="the docs folder (default: docs)")
        parser.add_argument("--check", action="store_true", help="compare only; exit 1 on any difference")

    def main(self) -> int:
        docs = Path(self.args.docs)
        if not docs.is_dir():
            raise BenchError(f"--docs {docs} is not a folder")
        differences = regenerate(docs, check=self.args.check)
        if self.args.check and differences:
            print("\n\n".join(differences))
            print(f"mimo-radar-bench docs: {len(differences)} page(s) differ from their artefacts")
            return 1
        print(
            f"{len(pages(docs))} page(s) " + ("match their artefacts" if self.args.check else "regenerated")
        )
        return 0
