"""Sphinx configuration: the Markdown pages of docs/ (MyST) and an API reference from the
docstrings. Build: ``sphinx-build -W -b html docs docs/_build/html`` (the ``docs`` extra)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

project = "mimo-radar-env"
author = "the mimo-radar-env developers"
copyright = "2026, the mimo-radar-env developers"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build"]
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence"]
html_theme = "furo"
html_title = "mimo-radar-env"
html_static_path = ["_static"]
html_css_files = ["tables.css"]

autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "description"
autodoc_inherit_docstrings = False  # Gymnasium's own docstrings are not ours to render
autodoc_member_order = "bysource"
# the agents package re-exports Agent: an annotation names the class where it is defined
autodoc_type_aliases = {"Agent": "agents.base.Agent"}
napoleon_google_docstring = False
napoleon_numpy_docstring = True
nitpicky = False


ENV_PAGE = Path(__file__).parent / "_generated" / "environment.md"


def _write_env_page() -> None:
    """The env's docstring is its documentation (Markdown sections, as in Gymnasium's envs):
    render it as a page of its own, through MyST."""
    import inspect

    from mimo_radar_env import MimoRadarSelectEnv

    text = inspect.cleandoc(MimoRadarSelectEnv.__doc__ or "")
    # the docstring's reST roles (:class:`~x.Y`) as MyST roles ({py:class}`~x.Y`): links
    text = re.sub(r":(class|func|meth|mod|data|attr):`([^`]+)`", r"{py:\1}`\2`", text)
    ENV_PAGE.parent.mkdir(exist_ok=True)
    page = "# The environment: `MimoRadarSelect`\n\n"
    page += "(The docstring of `mimo_radar_env.MimoRadarSelectEnv`.)\n\n"
    page += text + "\n"
    if not ENV_PAGE.exists() or ENV_PAGE.read_text() != page:
        ENV_PAGE.write_text(page)


def _env_docstring(app, what, name, obj, options, lines) -> None:
    if what == "class" and name.endswith("MimoRadarSelectEnv"):
        lines[:] = ["Its docstring is its documentation, rendered on :doc:`_generated/environment`."]


_write_env_page()


def _data_pages_are_orphans(app, docname, source) -> None:
    """The studies' own report pages under results/ are reached from their study's page, not
    listed in the sidebar: mark them orphans (in no toctree, by design)."""
    if docname.startswith("results/") and not source[0].startswith("---"):
        source[0] = "---\norphan: true\n---\n" + source[0]


def setup(app):
    app.connect("autodoc-process-docstring", _env_docstring)
    app.connect("source-read", _data_pages_are_orphans)
