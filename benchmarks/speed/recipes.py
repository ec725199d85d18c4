"""What each Python recipe of the docs costs: every block run alone, in a fresh interpreter.

Run: ``python -m benchmarks.speed.recipes [--json docs/results/perf/recipes.json]``.

Each ```python block of :data:`PAGES` runs in its own ``python -c`` process, in an empty
temporary folder, with nothing imported beforehand (what a reader who pastes it gets); its
wall time, the interpreter's start included, is recorded. A block that imports a library of
:data:`OWN_ENVIRONMENT` is not run here (torchrl shadows this project's ``benchmarks``; it runs
in ``.ci/wheel-check``). ``tests/clients/test_docs_recipes.py`` runs the same blocks the same
way (:func:`run_recipe`).
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..outputs import output_file, write_json

#: The pages whose Python blocks are recipes.
PAGES = ("clients.md", "ppo.md")
#: Libraries whose recipes run in their own environment, not in the project's.
OWN_ENVIRONMENT = {"torchrl": ".ci/wheel-check, in a fresh virtual environment"}
DOCS = Path(__file__).parents[2] / "docs"


@dataclass(frozen=True)
class Recipe:
    """A Python block of a docs page: its page, its place among the page's blocks, the
    section it is in, and its code."""

    page: str
    index: int
    section: str
    code: str

    @property
    def key(self) -> str:
        return f"{self.page}[{self.index}]"

    @property
    def digest(self) -> str:
        """The SHA-256 of the code: a timing is of this code only."""
        import hashlib

        return hashlib.sha256(self.code.encode()).hexdigest()

    def imports(self, module: str) -> bool:
        return re.search(rf"^\s*(from|import) {re.escape(module)}\b", self.code, flags=re.M) is not None


def recipes(docs: Path = DOCS) -> list[Recipe]:
    """Every Python block of :data:`PAGES`, in page order."""
    found = []
    for page in PAGES:
        section = ""
        text = (docs / page).read_text()
        index = 0
        for match in re.finditer(r"^(#{1,3} [^\n]*)$|^```python\n(.*?)^```", text, flags=re.M | re.S):
            if match.group(1):
                section = match.group(1).lstrip("#").strip()
            else:
                found.append(Recipe(page, index, section, match.group(2)))
                index += 1
    return found


def run_recipe(recipe: Recipe, timeout: float = 900) -> tuple[subprocess.CompletedProcess, float]:
    """Runs ``recipe`` alone in a fresh interpreter in an empty folder: the process and its
    wall time in seconds."""
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        result = subprocess.run(
            [sys.executable, "-c", recipe.code], cwd=folder, capture_output=True, text=True, timeout=timeout
        )
        return result, time.perf_counter() - start


def measure(progress: Any = print, known: list[dict[str, Any]] | None = None) -> list[dict[str, Any]]:
    """A row per recipe: its wall time run alone. A recipe with a row in ``known`` for the same
    page, place and code keeps that row (not run again)."""
    kept = {(r["page"], r["index"], r["sha256"]): r for r in known or []}
    rows = []
    for recipe in recipes():
        if (recipe.page, recipe.index, recipe.digest) in kept:
            rows.append(kept[(recipe.page, recipe.index, recipe.digest)])
            progress(f"{recipe.key:<14} {recipe.section:<40} kept")
            continue
        row: dict[str, Any] = {
            "page": recipe.page,
            "index": recipe.index,
            "section": recipe.section,
            "sha256": recipe.digest,
        }
        own = [module for module in OWN_ENVIRONMENT if recipe.imports(module)]
        if own:
            row["not_run"] = OWN_ENVIRONMENT[own[0]]
        else:
            result, seconds = run_recipe(recipe)
            if result.returncode != 0:
                raise RuntimeError(f"{recipe.key} failed:\n{result.stderr[-2000:]}")
            row["seconds"] = round(seconds, 1)
        rows.append(row)
        progress(f"{recipe.key:<14} {recipe.section:<40} {row.get('seconds', row.get('not_run'))}")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description="what each Python recipe of the docs costs, run alone")
    parser.add_argument("--json", type=output_file, default=None, help="write the rows to this file")
    parser.add_argument(
        "--changed",
        action="store_true",
        help="time only the recipes that --json's file has no row for (new or edited ones)",
    )
    args = parser.parse_args()
    from ..study import machine

    known = json.loads(Path(args.json).read_text())["rows"] if args.changed and args.json else None
    rows = measure(known=known)
    if args.json:
        record = {"command": "python -m benchmarks.speed.recipes", "machine": machine(), "rows": rows}
        write_json(args.json, record, indent=1)


if __name__ == "__main__":
    main()
