"""Every mimo-radar-bench command in the docs runs as written: bash would pass it unchanged (no
brace expansion, no placeholder words), the command line's parser accepts it, and a scenario it
names is one of its env version's."""

import re
import shlex
from pathlib import Path

import pytest

from benchmarks.cli import build_parser
from benchmarks.settings import scenario_for_version

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


def _epilog_commands():
    """The examples of ``mimo-radar-bench --help``."""
    from benchmarks.cli import EPILOG

    for line in EPILOG.replace("\\\n", " ").splitlines():
        line = line.strip()
        if line.startswith("mimo-radar-bench "):
            yield f"--help: {line}", line


COMMANDS = dict(_commands()) | dict(_epilog_commands())


def test_the_docs_have_commands():
    assert len(COMMANDS) >= 15


@pytest.mark.parametrize("where", sorted(COMMANDS))
def test_each_command_parses_as_written(where):
    line = COMMANDS[where]
    argv = shlex.split(line, comments=True)
    unquoted = " ".join(a for a in shlex.split(re.sub(r"'[^']*'|\"[^\"]*\"", "Q", line), comments=True))
    assert not UNQUOTED_BRACES.search(unquoted), f"bash would expand the braces of {line!r}"
    assert "..." not in argv and not any(a.isupper() and len(a) > 1 for a in argv), line
    args = build_parser().parse_args(argv[1:])  # SystemExit (exit 2) on anything the parser refuses
    if isinstance(getattr(args, "scenario", None), str) and hasattr(args, "env_version"):
        scenario_for_version(args.scenario, args.env_version)  # a v0 name under v1 is refused


def _runnable_examples():
    """The examples that name a scenario and run from this checkout as written (no model or
    layout file of the reader's own): run and paper, made small."""
    for where, line in sorted(COMMANDS.items()):
        argv = shlex.split(line, comments=True)[1:]
        if argv[0] not in ("run", "paper") or "ppo:" in line or ".yaml" in line:
            continue
        yield where, argv


@pytest.mark.parametrize(
    ("where", "argv"), list(_runnable_examples()), ids=lambda v: v if isinstance(v, str) else ""
)
def test_each_example_that_names_a_scenario_runs(where, argv, tmp_path):
    from benchmarks.cli import main

    small = [
        "--trials",
        "2",
        "--steps",
        "2",
        "--workers",
        "1",
        "--quiet",
        "--no-figures",
        "--out",
        str(tmp_path / "o"),
    ]
    assert main([*argv, *small]) == 0, where  # the last --trials, --steps and --out win
