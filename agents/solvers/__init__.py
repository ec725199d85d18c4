"""Super-arm solvers, pluggable into every index policy (``solver="bpso" | "exact" | "alternating"``)."""

from __future__ import annotations

import inspect
from typing import Any

from .alternating import AlternatingSolver
from .base import SuperArmSolver
from .bpso import BPSOSolver
from .exact import ExactSolver

SOLVERS: dict[str, type[SuperArmSolver]] = {
    cls.name: cls for cls in (ExactSolver, BPSOSolver, AlternatingSolver)
}


def make_solver(name: str | SuperArmSolver, tx_count: int, rx_count: int, **params: Any) -> SuperArmSolver:
    """A solver by name, or pass an instance through."""
    if isinstance(name, SuperArmSolver):
        return name
    if name not in SOLVERS:
        raise ValueError(f"unknown solver {name!r}; available solvers are {sorted(SOLVERS)}")
    allowed = list(inspect.signature(SOLVERS[name]).parameters)[2:]  # after tx_count, rx_count
    unknown = sorted(set(params) - set(allowed))
    if unknown:
        raise ValueError(
            f"bad parameters for solver {name!r}: unknown {unknown}; it takes {allowed or 'none'}"
        )
    return SOLVERS[name](tx_count, rx_count, **params)


def compiled_kernels(name: str, threads: int | None = None) -> list[Any]:
    """The numba kernels solver ``name`` runs with ``threads`` numba threads (default: the
    current count); none without numba, or for a solver that has none."""
    from . import _bpso_kernels

    if name != BPSOSolver.name or not _bpso_kernels.HAVE_NUMBA:
        return []
    return [_bpso_kernels.initial_positions, _bpso_kernels.numba_kernel(threads)]


__all__ = [
    "SOLVERS",
    "compiled_kernels",
    "AlternatingSolver",
    "BPSOSolver",
    "ExactSolver",
    "SuperArmSolver",
    "make_solver",
]
