"""The recipes of docs/clients.md run as written."""

import re
from pathlib import Path

import pytest

DOC = Path(__file__).parents[2] / "docs" / "clients.md"
BLOCKS = re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.S)
NEEDS = {
    "stable_baselines3": "rl extra",
    "sb3_contrib": "test extra",
    "torchrl": "its own environment, .ci/wheel-check",
    "SMPyBandits": "test extra",
}


def test_the_page_has_recipes():
    assert len(BLOCKS) >= 4


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_recipe_runs(index):
    code = BLOCKS[index]
    for module, extra in NEEDS.items():
        if f"from {module}" in code or f"import {module}" in code:
            pytest.importorskip(module, reason=f"the recipe needs {module} ({extra})")
    exec(compile(code, f"{DOC.name}[{index}]", "exec"), {"__name__": "__recipe__"})
