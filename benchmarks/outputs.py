"""Where a command writes: its output folder and the JSON files of its figures, checked as its
arguments are parsed (refused before the work, not after it). Light on imports: a tool that times
a command in its own process (``benchmarks.speed.timeline``) imports it before the command."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any


def folder(text: str) -> str:
    """An argparse type: a folder to write into, named (an empty ``--out ''`` would write into the
    current folder), that is not a file and not under one."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"must name a folder, got {text!r}")
    above = _nearest_existing(Path(text))
    if not above.is_dir():
        where = "is a file" if above == Path(text) else f"is under the file {above}"
        raise argparse.ArgumentTypeError(f"must be a folder, and {text!r} {where}")
    return text


def output_file(text: str) -> Path:
    """An argparse type: a file a tool writes when it is done (:func:`write_json`), named, that is
    not a folder and not under a file: refused before the work, not after it."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"must name a file, got {text!r}")
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"must be a file, and {text!r} is a folder")
    above = _nearest_existing(path.parent)
    if not above.is_dir():
        raise argparse.ArgumentTypeError(f"must be a file, and {text!r} is under the file {above}")
    return path


def _nearest_existing(path: Path) -> Path:
    """``path`` or its nearest ancestor that exists."""
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def write_json(path: Path | None, result: Any, indent: int = 2, end: str = "\n") -> None:
    """``result`` as indented JSON at ``path``, its missing folders made (nothing for None)."""
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(result, indent=indent) + end)
