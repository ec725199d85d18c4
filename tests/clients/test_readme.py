"""README's Python blocks run as a newcomer pastes them, in a fresh interpreter."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers import readme_demo_table

README = Path(__file__).resolve().parents[2] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), re.DOTALL)


def _run(code: str, folder: Path) -> str:
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=folder, capture_output=True, text=True, timeout=900
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return result.stdout


def test_the_first_example_acts_validly(tmp_path):
    """The first block steps the env once; its action selects exactly Ms and Ns stations."""
    single = BLOCKS[0].split("\n\n#")[0]  # the single env's lines, before the vector env's
    assert "sample_action()" in single
    out = _run(single + "\nprint(info['action_valid'], reward > 0)\n", tmp_path)
    assert out.split()[-2:] == ["True", "True"]


@pytest.mark.slow
def test_every_block_runs_in_order(tmp_path):
    _run("\n".join(BLOCKS), tmp_path)


def test_the_demo_prints_what_the_readme_shows(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "benchmarks", "demo"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip() == readme_demo_table()
