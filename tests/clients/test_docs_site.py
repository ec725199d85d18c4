"""The documentation site builds with warnings as errors (the docs extra)."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_sphinx_builds_the_site_without_warnings(tmp_path):
    pytest.importorskip("myst_parser", reason="the site needs the docs extra: pip install -e '.[docs]'")
    pytest.importorskip("furo", reason="the site needs the docs extra: pip install -e '.[docs]'")
    done = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", str(ROOT / "docs"), str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    env_api, agents_api = ((tmp_path / f"api-{p}.html").read_text() for p in ("env", "agents"))
    assert "EnvOptions" in env_api and "make_agent" in agents_api  # generated from the docstrings
    env_page = (tmp_path / "_generated" / "environment.html").read_text()
    assert "Action Space" in env_page and "Observation Space" in env_page
