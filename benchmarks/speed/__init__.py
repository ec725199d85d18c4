"""Developer tools: speed and memory measurements, each printed as a ratio to a reference
measured in the same run. Not installed with the package (they need a source checkout):
``python -m benchmarks.speed.tracker_speed``, ``mimo-radar-bench perf`` from a checkout."""

import json
from pathlib import Path
from typing import Any


def write_json(path: Path | None, result: Any) -> None:
    """A tool's result as indented JSON at ``path`` (its folder made; nothing for None)."""
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(result, indent=2) + "\n")
