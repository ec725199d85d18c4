"""The docs' filler: the pages hold the sentences; every table and value that reports a
measurement is filled from a committed artefact, never typed by hand.

A page marks a table with two HTML comments (invisible on the site)::

    <!-- generated: claims-verdicts -->
    ...written by the generator "claims-verdicts"...
    <!-- end generated -->

and a value in one of its sentences (a number, an interval, a verdict, a computed list) as a
*value span* on one line::

    optimal in <!-- value: model greedy-optimal-average -->99.0 % [96.4, 99.7]<!-- end value -->

``mimo-radar-bench docs`` rewrites every block and value of every page of ``--docs`` from the
artefacts under ``DOCS/results``; ``--check`` changes nothing and fails, naming the pages, where
one differs from what the artefacts give (CI runs it). Generators, value sources and value
tables (:func:`benchmarks.docs_tooling.generators.values`: every value of one finding by key)
are registered in :mod:`benchmarks.docs_tooling.generators`; each names the artefacts it reads.

Outside generated blocks and value spans, a number shaped like a measurement (a decimal
percentage, duration or interval, a ratio such as ``1.7x`` or ``1.19 times``) is an error:
:func:`unsourced_numbers` finds them, and ``--check`` fails on any. Constants of the model are
written as code (```[0.2, 1.2]```), which the check skips.
"""

from __future__ import annotations

import argparse
import difflib
import re
from collections.abc import Callable
from pathlib import Path

from ..cli import Command
from ..errors import BenchError
from .generators import GENERATORS, VALUE_SOURCES, forget_values

BLOCK = re.compile(r"(<!-- generated: ([\w.-]+) -->\n)(.*?)(<!-- end generated -->)", re.DOTALL)
VALUE = re.compile(r"(<!-- value: ([\w.-]+) ([\w.+-]+) -->)(.*?)(<!-- end value -->)")
#: A value span's opening comment, as it may stand inside a code span.
VALUE_OPENING = re.compile(r"<!-- value: [\w.-]+ [\w.+-]+ -->")
#: Numbers shaped like measurements; a match outside a generated block or value span is unsourced.
MEASUREMENT = re.compile(
    r"(?<![\w.])(?:"
    r"\d+\.\d+\s?%|(?!95\s?%)\d+\s?%"  # a percentage (95 % is the confidence level)
    r"|\d+\.\d+\s?(?:ms|s|min|h)\b"  # a decimal duration
    r"|\d+(?:\.\d+)?x\b|\d+\.\d+ times\b"  # a ratio
    r"|\[-?\d+\.\d+, -?\d+\.\d+\]"  # an interval
    r")"
)
#: What the prose check skips: generated blocks, value spans, code, maths, link targets, comments.
_NOT_PROSE = [
    re.compile(r"<!-- generated: .*?<!-- end generated -->", re.DOTALL),
    VALUE,
    re.compile(r"^(```|:::).*?^\1", re.DOTALL | re.MULTILINE),
    re.compile(r"`[^`\n]*`"),
    re.compile(r"\$[^$\n]+\$"),
    re.compile(r"\]\([^)\s]*\)"),
    re.compile(r"<!--.*?-->", re.DOTALL),
]


def unsourced_numbers(text: str) -> list[tuple[int, str]]:
    """The measurement-shaped numbers of ``text`` outside generated blocks and value spans,
    as ``(line, number)``; code, maths and link targets are not prose."""

    def blank(match: re.Match[str]) -> str:
        return re.sub(r"[^\n]", " ", match.group(0))  # keeps the line numbers

    for pattern in _NOT_PROSE:
        text = pattern.sub(blank, text)
    return [(text.count("\n", 0, match.start()) + 1, match.group(0)) for match in MEASUREMENT.finditer(text)]


def coded_values(text: str) -> list[str]:
    """The code spans of ``text`` that hold a value span, where the page would show its comments as
    text. A code span is CommonMark's: a run of backticks closed by the next run of the same
    length in its paragraph."""
    found = []
    for paragraph in re.split(r"\n[ \t]*\n", text):
        runs = list(re.finditer(r"`+", paragraph))
        opening = 0
        while opening < len(runs):
            length = len(runs[opening].group())
            closing = next((k for k in range(opening + 1, len(runs)) if len(runs[k].group()) == length), None)
            if closing is None:  # literal backticks
                opening += 1
                continue
            span = paragraph[runs[opening].start() : runs[closing].end()]
            if VALUE_OPENING.search(span):
                found.append(span)
            opening = closing + 1
    return found


def comment_led_lines(text: str) -> list[int]:
    """The lines of ``text`` (1-based, outside code fences) that open with an HTML comment followed
    by text, such as a value span at a line's start. CommonMark reads such a line as a raw HTML
    block: it ends the paragraph there and shows the line's Markdown as typed."""
    found, fence = [], None
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.lstrip()
        marker = stripped[:3]
        if marker in ("```", ":::"):
            fence = None if fence == marker else (fence or marker)
        elif fence is None and re.match(r"<!--.*?-->\s*\S", stripped):
            found.append(number)
    return found


def render(text: str, docs: Path) -> str:
    """``text`` with every generated block and value span filled from the artefacts; an unknown
    generator, value source or key is an error."""
    forget_values()

    def fill(match: re.Match[str]) -> str:
        name = match.group(2)
        if name not in GENERATORS:
            raise BenchError(f"no generator called {name!r}; known: {sorted(GENERATORS)}")
        body = _read(lambda: GENERATORS[name](docs), f"the generated block {name!r}").rstrip("\n") + "\n"
        return match.group(1) + body + match.group(4)

    coded = coded_values(text)
    if coded:
        raise BenchError(
            f"a value span inside a code span shows its comments on the page: {coded[0]!r} "
            "(let the value carry its backticks)"
        )

    def quote(match: re.Match[str]) -> str:
        source, key = match.group(2), match.group(3)
        if source not in VALUE_SOURCES:
            raise BenchError(f"no value source called {source!r}; known: {sorted(VALUE_SOURCES)}")
        value = _read(lambda: VALUE_SOURCES[source](docs, key), f"the value {source} {key}")
        return match.group(1) + value + match.group(5)

    rendered = VALUE.sub(quote, BLOCK.sub(fill, text))
    led = comment_led_lines(rendered)
    if led:
        raise BenchError(
            f"line {led[0]} opens with an HTML comment followed by text, which CommonMark reads as raw HTML: "
            "the paragraph breaks there and the line's Markdown shows as typed (start the line with a word)"
        )
    return rendered


def _read(make: Callable[[], str], what: str) -> str:
    """``make()``, an artefact it reads and cannot find named in one line."""
    try:
        return make()
    except FileNotFoundError as exc:
        raise BenchError(f"{what} reads {exc.filename}, which is not there") from None


def pages(docs: Path) -> list[Path]:
    """The docs' pages, and the README beside the docs folder (its quickstart's times are generated too)."""
    readme = docs.parent / "README.md"
    return [*sorted(docs.glob("*.md")), *([readme] if readme.is_file() else [])]


def regenerate(docs: Path, check: bool = False) -> list[str]:
    """Rewrite every page's blocks (or, with ``check``, only compare); the differences found,
    as unified diffs (empty when the pages match the artefacts)."""
    rendered = []
    for page in pages(docs):  # every page rendered before any is written
        old = page.read_text()
        try:
            rendered.append((page, old, render(old, docs)))
        except BenchError as exc:
            raise BenchError(f"{page}: {exc}") from None
    differences = []
    for page, old, new in rendered:
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


def unsourced(docs: Path) -> list[str]:
    """Every measurement-shaped number of the pages (and of the README beside the docs folder)
    outside generated blocks and value spans."""
    return [
        f"{page}:{line}: {number!r} is quoted without an artefact (put it in a value span or a "
        "generated block; write a model constant as code)"
        for page in pages(docs)
        for line, number in unsourced_numbers(page.read_text())
    ]


class DocsCommand(Command):
    name = "docs"
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
        if not (docs / "results").is_dir():
            raise BenchError(
                f"--docs {self.args.docs!r} is not a docs folder: it has no results/ folder of the artefacts "
                "its pages are generated from (the project's is docs/, in a source checkout)"
            )
        differences = regenerate(docs, check=self.args.check)
        if self.args.check and differences:
            print("\n\n".join(differences))
            print(f"mimo-radar-bench docs: {len(differences)} page(s) differ from their artefacts")
            return 1
        problems = unsourced(docs)
        if problems:
            print("\n".join(problems))
            print(f"mimo-radar-bench docs: {len(problems)} number(s) in prose rest on no artefact")
            return 1
        print(
            f"{len(pages(docs))} page(s) " + ("match their artefacts" if self.args.check else "regenerated")
        )
        return 0
