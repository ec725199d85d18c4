"""What a worker process has before its task imports anything: tasks of the standard library
alone (unpickling a function of a test module would import the project itself)."""

from __future__ import annotations

import os
import sys


def imported(*modules: str) -> dict[str, object]:
    """Which of ``modules`` this process had imported, and its parent's pid."""
    return {"imported": [m in sys.modules for m in modules], "parent": os.getppid(), "pid": os.getpid()}


def overloads(module: str, kernel: str) -> int:
    """How many compiled overloads numba kernel ``kernel`` of the imported ``module`` holds."""
    return len(getattr(sys.modules[module], kernel).overloads)


def blas_threads() -> list[int]:
    """The thread count of each BLAS library this process has loaded (threadpoolctl's view)."""
    from threadpoolctl import threadpool_info

    return [info["num_threads"] for info in threadpool_info() if info["user_api"] == "blas"]
