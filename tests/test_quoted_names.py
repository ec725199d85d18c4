"""Every cross-reference of the packages' docstrings to a project name (``:func:`agents.make_env```,
``:class:`~mimo_radar_env.Scenario```...) names something that exists: the site renders a missing
one as plain text without a warning, so a module moved or renamed left its old name behind. So
does every dotted project name the docs' pages and the README quote as code."""

import importlib
import inspect
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("mimo_radar_env", "agents", "benchmarks")
ROLE = re.compile(r":(?:func|meth|class|data|attr|mod|exc):`~?((?:" + "|".join(PACKAGES) + r")\.[\w.]+)`")
#: Modules that import an optional dependency on import (tested where it is installed).
OPTIONAL = ("mimo_radar_env.torchrl_env",)
#: Dotted names the pages quote that are no Python names.
NOT_NAMES = {"mimo_radar_env.agents": "the entry-point group of agents of installed packages"}
CODE = re.compile(r"`((?:" + "|".join(PACKAGES) + r")\.[\w.]+)(?:\([^`]*\))?`")


def _found(pattern: re.Pattern[str], paths: list[Path]) -> dict[str, list[str]]:
    """Each project name ``pattern`` finds in ``paths``, with the files it stands in."""
    found: dict[str, list[str]] = {}
    for path in paths:
        for match in pattern.finditer(path.read_text()):
            found.setdefault(match.group(1).rstrip("."), []).append(str(path.relative_to(ROOT)))
    return found


#: The docstrings' link targets, and the names the pages quote as code.
TARGETS = _found(ROLE, [path for package in PACKAGES for path in sorted((ROOT / package).rglob("*.py"))])
QUOTED = _found(CODE, [*sorted((ROOT / "docs").glob("*.md")), ROOT / "README.md"])


def _resolves(target: str) -> bool:
    """Whether ``target`` is a module, or a name reached from one by attributes; an attribute a
    class sets on its instances (``self.NAME = ...`` in its source) counts as the class's."""
    parts = target.split(".")
    for split in range(len(parts), 0, -1):
        try:
            found = importlib.import_module(".".join(parts[:split]))
        except ImportError:
            continue
        for name in parts[split:]:
            if hasattr(found, name):
                found = getattr(found, name)
            elif inspect.isclass(found) and re.search(rf"\bself\.{name}\b\s*[:=]", inspect.getsource(found)):
                return True
            else:
                return False
        return True
    return False


def test_the_rule_finds_what_exists_and_what_does_not():
    assert _resolves("agents.costs.memory_per_trial") and _resolves("benchmarks.studies.claims")
    assert _resolves("agents.Agent.xp")  # set on each instance in Agent.__init__
    assert not _resolves("benchmarks.claims") and not _resolves("agents.Agent.memory_per_trial")


@pytest.mark.parametrize("target", sorted(t for t in TARGETS if not t.startswith(OPTIONAL)))
def test_every_docstring_link_to_the_project_names_what_exists(target):
    assert _resolves(target), f"{target} (in {sorted(set(TARGETS[target]))}) names nothing that exists"


@pytest.mark.parametrize(
    "name", sorted(n for n in QUOTED if not n.startswith(OPTIONAL) and n not in NOT_NAMES)
)
def test_every_project_name_the_docs_quote_exists(name):
    assert _resolves(name), f"{name} (in {sorted(set(QUOTED[name]))}) names nothing that exists"
