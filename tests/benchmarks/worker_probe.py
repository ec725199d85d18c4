"""What a worker process has before its task imports anything: a task of the standard library
alone (unpickling a function of a test module would import the project itself)."""

from __future__ import annotations

import os
import sys


def imported(*modules: str) -> dict[str, object]:
    """Which of ``modules`` this process had imported, and its parent's pid."""
    return {"imported": [m in sys.modules for m in modules], "parent": os.getppid(), "pid": os.getpid()}
