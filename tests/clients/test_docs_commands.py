"""Every mimo-radar-bench command in the docs runs as written: bash would pass it unchanged (no
brace expansion, no placeholder words) and the command line's parser accepts it."""

import re
import shlex
from pathlib import Path

import pytest

from benchmarks.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
UNQUOTED_BRACES = re.compile(r"\{[^}'\"]*,[^}'\"]*\}")  # {1,2,3}: bash expands it


def _commands():
    for page in PAGES:
        for block in re.findall(r"```(?:bash|sh|console)\n(.*?)```", page.read_text(), re.DOTALL):
            loops = dict(re.findall(r"for (\w+) in (\S+)", block))  # for n in 1 2 3: take the first
            text = block.replace("\\\n", " ")
            for line in text.splitlines():
                for part in re.split(r"&&|;", line):
                    part = part.strip()
                    if part.startswith("mimo-radar-bench "):
                        for name, value in loops.items():
                            part = part.replace(f"${name}", value)
                        yield f"{page.name}: {part}", part


COMMANDS = dict(_commands())


def test_the_docs_have_commands():
    assert len(COMMANDS) >= 15


@pytest.mark.parametrize("where", sorted(COMMANDS))
def test_each_command_parses_as_written(where):
    line = COMMANDS[where]
    argv = shlex.split(line, comments=True)
    unquoted = " ".join(a for a in shlex.split(re.sub(r"'[^']*'|\"[^\"]*\"", "Q", line), comments=True))
    assert not UNQUOTED_BRACES.search(unquoted), f"bash would expand the braces of {line!r}"
    assert "..." not in argv and not any(a.isupper() and len(a) > 1 for a in argv), line
    build_parser().parse_args(argv[1:])  # SystemExit (exit 2) on anything the parser refuses
